#include "../support/chi2.h"
#include "candela/bsdf/microfacet.h"
#include "candela/sampling/warp.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace candela;
using candela::test::chi2_test;
using candela::test::sidak_significance;

namespace {

// Family-wise error rate of all chi-square tests in this file.
constexpr double kAlpha = 0.01;
// Number of chi-square tests in this file expected to pass (Sidak correction).
constexpr int kNumChi2Tests = 12;
const double kSignificance = sidak_significance(kAlpha, kNumChi2Tests);
// Samples per chi-square test: enough that 10^3 cells each expect >> 5 counts.
constexpr int kSamples = 1000000;
// |integral of pdf - 1| allowed: smooth pdfs integrate to ~1e-6, but a jump that crosses cells
// (a cone edge) is resolved only to ~1e-3 of the crossed cells' mass by the harness (depth cap).
constexpr double kIntegralTolerance = 1e-3;

void check(const candela::test::Chi2Result& r) {
    INFO(r.message);
    CHECK(r.passed);
    CHECK(r.pdf_integral == Approx(1.0).margin(kIntegralTolerance));
}

} // namespace

TEST_CASE("concentric disk maps into the unit disk", "[sampling][quick]") {
    Pcg32 rng(7, 1);
    // Float rounding of r cos, r sin for r = 1.
    constexpr float kRadiusSlack = 1e-6f;
    for (int i = 0; i < 10000; ++i) {
        Vec2 d = square_to_uniform_disk_concentric(Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(d.x * d.x + d.y * d.y <= 1.f + kRadiusSlack);
    }
    Vec2 c = square_to_uniform_disk_concentric(Vec2(0.5f, 0.5f));
    CHECK(c.x == 0.f);
    CHECK(c.y == 0.f);
}

TEST_CASE("chi2: cosine hemisphere", "[sampling][stat]") {
    auto r =
        chi2_test([](Vec2 u, float) { return std::optional<Vec3>(square_to_cosine_hemisphere(u)); },
                  [](const Vec3& w) { return square_to_cosine_hemisphere_pdf(w); }, kSamples, 20,
                  40, 1, kSignificance);
    check(r);
}

TEST_CASE("chi2: uniform hemisphere and sphere", "[sampling][stat]") {
    auto r1 = chi2_test(
        [](Vec2 u, float) { return std::optional<Vec3>(square_to_uniform_hemisphere(u)); },
        [](const Vec3& w) { return square_to_uniform_hemisphere_pdf(w); }, kSamples, 20, 40, 2,
        kSignificance);
    check(r1);
    auto r2 =
        chi2_test([](Vec2 u, float) { return std::optional<Vec3>(square_to_uniform_sphere(u)); },
                  [](const Vec3& w) { return square_to_uniform_sphere_pdf(w); }, kSamples, 20, 40,
                  3, kSignificance);
    check(r2);
}

TEST_CASE("chi2: uniform cone", "[sampling][stat]") {
    for (float cos_max : {0.3f, 0.9f, -0.5f}) {
        INFO("cos_max = " << cos_max);
        auto r = chi2_test(
            [cos_max](Vec2 u, float) {
                return std::optional<Vec3>(square_to_uniform_cone(u, cos_max));
            },
            [cos_max](const Vec3& w) { return square_to_uniform_cone_pdf(w, cos_max); }, kSamples,
            30, 30, 4, kSignificance);
        check(r);
    }
    // A narrow cone (half-angle ~2.6 deg) seen through a zoomed view so that it spans many cells.
    const float cos_narrow = 0.999f;
    auto [zs, zp] = candela::test::zoom_view(
        [cos_narrow](Vec2 u, float) {
            return std::optional<Vec3>(square_to_uniform_cone(u, cos_narrow));
        },
        [cos_narrow](const Vec3& w) { return square_to_uniform_cone_pdf(w, cos_narrow); },
        Vec3(0, 0, 1), 30.0);
    check(chi2_test(zs, zp, kSamples, 30, 30, 5, kSignificance));
}

TEST_CASE("chi2: Beckmann normals", "[sampling][stat]") {
    for (float alpha : {0.1f, 0.5f, 1.0f}) {
        INFO("alpha = " << alpha);
        double zoom = 0.5 / alpha > 1.0 ? 0.5 / alpha : 1.0;
        auto [zs, zp] = candela::test::zoom_view(
            [alpha](Vec2 u, float) { return std::optional<Vec3>(square_to_beckmann(u, alpha)); },
            [alpha](const Vec3& w) { return square_to_beckmann_pdf(w, alpha); }, Vec3(0, 0, 1),
            zoom);
        check(chi2_test(zs, zp, kSamples, 30, 40, 6, kSignificance));
    }
}

TEST_CASE("chi2 harness rejects a wrong pdf", "[sampling][stat]") {
    // Cosine-distributed samples tested against the uniform-hemisphere pdf must be rejected,
    // and so must uniform samples tested against a slightly wrong normalisation.
    auto bad =
        chi2_test([](Vec2 u, float) { return std::optional<Vec3>(square_to_cosine_hemisphere(u)); },
                  [](const Vec3& w) { return square_to_uniform_hemisphere_pdf(w); }, 100000, 10, 20,
                  8, kSignificance);
    CHECK_FALSE(bad.passed);
    auto scaled =
        chi2_test([](Vec2 u, float) { return std::optional<Vec3>(square_to_uniform_sphere(u)); },
                  [](const Vec3&) { return 1.02f * kInv4Pi; }, kSamples, 10, 20, 9, kSignificance);
    CHECK_FALSE(scaled.passed);
    // Samples where the pdf is zero (beyond float-rounding strays) are a hard failure.
    auto outside =
        chi2_test([](Vec2 u, float) { return std::optional<Vec3>(square_to_uniform_sphere(u)); },
                  [](const Vec3& w) { return 2.f * square_to_uniform_hemisphere_pdf(w) * 0.5f; },
                  100000, 10, 20, 11, kSignificance);
    CHECK_FALSE(outside.passed);
    // A sampler that fails half the time with a pdf integrating to 1/2 is consistent.
    auto half = chi2_test(
        [](Vec2 u, float uc) -> std::optional<Vec3> {
            if (uc < 0.5f) return std::nullopt;
            return square_to_uniform_sphere(u);
        },
        [](const Vec3&) { return 0.5f * kInv4Pi; }, kSamples, 10, 20, 10, kSignificance);
    INFO(half.message);
    CHECK(half.passed);
    CHECK(half.pdf_integral == Approx(0.5).margin(kIntegralTolerance));
}

TEST_CASE("uniform triangle barycentrics", "[sampling][stat]") {
    // Mean of uniform barycentrics is (1/3, 1/3, 1/3); each has variance 1/18.
    constexpr int kN = 200000;
    // 5 standard errors of the mean: false-alarm probability ~6e-7 per component.
    constexpr double kSigmas = 5.0;
    Pcg32 rng(11, 3);
    double sum[3] = {0, 0, 0};
    for (int i = 0; i < kN; ++i) {
        Vec3 b = square_to_uniform_triangle(Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(b.x >= 0.f);
        REQUIRE(b.y >= 0.f);
        REQUIRE(b.z >= 0.f);
        REQUIRE(b.x + b.y + b.z == Approx(1.f).margin(1e-6));
        for (int k = 0; k < 3; ++k)
            sum[k] += b[k];
    }
    double se = std::sqrt(1.0 / 18.0 / kN);
    for (int k = 0; k < 3; ++k)
        CHECK(std::abs(sum[k] / kN - 1.0 / 3.0) < kSigmas * se);
}

TEST_CASE("visible slopes: the inversion hits its CDF, monotone, inside the support",
          "[sampling][quick]") {
    // The closed-form CDF at the returned slope reproduces u: the float result carries ~1e-7
    // relative error in x, which moves F by at most p(x) * that.
    constexpr double kCdfTol = 1e-6;
    for (float t : {0.f, 0.01f, 0.3f, 1.f, 5.f, 100.f, 1e5f}) {
        const double hi = t > 0.f ? std::min(kMaxVisibleSlope, 1.0 / t) : kMaxVisibleSlope;
        const double z = warp_detail::visible_slope_cdf(hi, t);
        float prev = -1e30f;
        for (int i = 1; i < 2000; ++i) {
            const float u = float(i) / 2000.f;
            const float x = sample_visible_slope(u, t);
            INFO("t = " << t << ", u = " << u << ", x = " << x);
            REQUIRE(std::isfinite(x));
            REQUIRE(x >= prev);
            REQUIRE(double(x) <= hi * (1.0 + 1e-6) + 1e-12);
            REQUIRE(warp_detail::visible_slope_cdf(x, t) / z == Approx(u).margin(kCdfTol));
            REQUIRE(sample_visible_slope_pdf(x, t) >= 0.f);
            prev = x;
        }
        // Extreme u stay finite.
        REQUIRE(std::isfinite(sample_visible_slope(0.f, t)));
        REQUIRE(std::isfinite(sample_visible_slope(0.99999994f, t)));
    }
}

TEST_CASE("visible slopes: normalisation is sqrt(pi) (1 + Lambda)", "[sampling][quick]") {
    // Z(t) = F(1/t) must equal sqrt(pi) (1 + Lambda(theta)) for alpha = 1, with Lambda from its
    // own formula in microfacet.h, and the pdf must integrate to 1 (midpoint rule, 2e5 cells).
    constexpr double kSqrtPi = 1.7724538509055160273;
    for (float theta_deg : {0.f, 20.f, 50.f, 80.f, 89.f}) {
        const float theta = deg_to_rad(theta_deg);
        const float t = std::tan(theta);
        const double hi = t > 0.f ? std::min(kMaxVisibleSlope, 1.0 / t) : kMaxVisibleSlope;
        const Vec3 w(std::sin(theta), 0.f, std::cos(theta));
        const double lambda = beckmann_lambda(w, 1.f);
        CHECK(warp_detail::visible_slope_cdf(hi, t) / kSqrtPi ==
              Approx(1.0 + lambda).epsilon(1e-5));
        constexpr int kCells = 200000;
        const double lo = -10.0, dx = (hi - lo) / kCells;
        double integral = 0.0;
        for (int i = 0; i < kCells; ++i)
            integral += sample_visible_slope_pdf(float(lo + (i + 0.5) * dx), t) * dx;
        CHECK(integral == Approx(1.0).margin(1e-4));
    }
}
