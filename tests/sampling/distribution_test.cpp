#include "../support/chi2.h"
#include "candela/sampling/distribution.h"
#include "candela/sampling/mis.h"
#include "candela/sampling/rng.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

using namespace candela;

TEST_CASE("Distribution1D pmf, pdf and inversion", "[sampling][quick]") {
    std::vector<float> f = {1.f, 0.f, 3.f, 0.f, 4.f};
    Distribution1D d(f);
    CHECK_FALSE(d.is_uniform_fallback());
    CHECK(d.integral() == Approx(8.f / 5.f));
    CHECK(d.pmf(0) == Approx(1.f / 8.f));
    CHECK(d.pmf(1) == 0.f);
    CHECK(d.pmf(2) == Approx(3.f / 8.f));
    CHECK(d.pmf(4) == Approx(0.5f));
    CHECK(d.pmf(5) == 0.f);
    Pcg32 rng(3, 4);
    for (int i = 0; i < 20000; ++i) {
        float u = rng.next_float(), pdf = 0.f, pmf = 0.f, ur = -1.f;
        std::size_t off = 99;
        float x = d.sample_continuous(u, &pdf, &off);
        REQUIRE(x >= 0.f);
        REQUIRE(x < 1.f);
        REQUIRE(f[off] > 0.f);
        REQUIRE(pdf == Approx(d.pdf(x)));
        std::size_t k = d.sample_discrete(u, &pmf, &ur);
        REQUIRE(k == off);
        REQUIRE(pmf == d.pmf(k));
        REQUIRE(ur >= 0.f);
        REQUIRE(ur < 1.f);
    }
    // u at the top of the range and exactly 0.
    CHECK(d.sample_continuous(0.99999994f) < 1.f);
    CHECK(d.sample_discrete(0.f) == 0);
}

TEST_CASE("Distribution1D falls back to uniform and rejects bad input", "[sampling][quick]") {
    Distribution1D z(std::vector<float>{0.f, 0.f, 0.f, 0.f});
    CHECK(z.is_uniform_fallback());
    CHECK(z.pmf(2) == Approx(0.25f));
    float pdf = 0.f;
    float x = z.sample_continuous(0.6f, &pdf);
    CHECK(x == Approx(0.6f));
    CHECK(pdf == 1.f);
    CHECK_THROWS_AS(Distribution1D(std::vector<float>{}), Error);
    CHECK_THROWS_AS(Distribution1D(std::vector<float>{1.f, -1.f}), Error);
    CHECK_THROWS_AS(Distribution1D(std::vector<float>{1.f, std::nanf("")}), Error);
    CHECK_THROWS_AS(Distribution2D(std::vector<float>{1.f, 2.f, 3.f}, 2, 2), Error);
}

TEST_CASE("Distribution1D discrete frequencies match the pmf", "[sampling][stat]") {
    std::vector<float> f = {0.5f, 2.f, 0.f, 1.f, 7.f, 0.25f, 3.f};
    Distribution1D d(f);
    constexpr int kN = 200000;
    std::vector<double> count(f.size(), 0.0);
    Pcg32 rng(5, 6);
    for (int i = 0; i < kN; ++i)
        count[d.sample_discrete(rng.next_float())] += 1.0;
    double stat = 0.0;
    int bins = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
        double e = kN * double(d.pmf(i));
        if (e == 0.0) {
            CHECK(count[i] == 0.0);
            continue;
        }
        stat += (count[i] - e) * (count[i] - e) / e;
        ++bins;
    }
    double p = candela::test::chi2_survival(stat, bins - 1);
    INFO("chi2 = " << stat << ", p = " << p);
    // Single test at the 1% level.
    constexpr double kSignificance = 0.01;
    CHECK(p > kSignificance);
}

TEST_CASE("chi2: Distribution2D", "[sampling][stat]") {
    // A 32 x 16 table with a bright spot, a zero row and smooth variation, sampled on [0,1)^2 and
    // mapped to the sphere by the equal-area map z = 1 - 2y, phi = 2 pi x (Jacobian 4 pi).
    constexpr std::size_t kNu = 32, kNv = 16;
    std::vector<float> f(kNu * kNv);
    for (std::size_t v = 0; v < kNv; ++v)
        for (std::size_t u = 0; u < kNu; ++u) {
            float val = 1.f + std::sin(float(u) * 0.4f) * 0.5f + float(v) * 0.1f;
            if (u == 20 && v == 5) val = 40.f;
            if (v == 9) val = 0.f;
            f[v * kNu + u] = val;
        }
    Distribution2D d(f, kNu, kNv);
    auto to_sphere = [](Vec2 p) {
        float z = 1.f - 2.f * p.y, r = std::sqrt(std::max(0.f, 1.f - z * z));
        float phi = 2.f * kPi * p.x;
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    auto sample = [&](Vec2 u, float) -> std::optional<Vec3> {
        float pdf = 0.f;
        Vec2 p = d.sample_continuous(u, &pdf);
        // The returned pdf must agree with pdf() at the sample.
        if (std::abs(pdf - d.pdf(p)) > 1e-4f * pdf) return Vec3(0.f); // flagged as non-unit
        return to_sphere(p);
    };
    auto pdf = [&](const Vec3& w) {
        float y = (1.f - std::clamp(w.z, -1.f, 1.f)) * 0.5f;
        float phi = std::atan2(w.y, w.x);
        if (phi < 0.f) phi += 2.f * kPi;
        float x = std::min(phi * kInv2Pi, 0.99999994f);
        return d.pdf(Vec2(x, std::min(y, 0.99999994f))) * kInv4Pi;
    };
    // Bins aligned with the table cells (4x oversampled) so the piecewise-constant pdf is smooth
    // inside every cell.
    auto r = candela::test::chi2_test(sample, pdf, 1000000, 4 * int(kNv), 4 * int(kNu), 17, 0.01);
    INFO(r.message);
    CHECK(r.passed);
    // Quadrature of a piecewise-constant pdf on aligned cells is exact up to float rounding.
    constexpr double kIntegralTolerance = 1e-4;
    CHECK(r.pdf_integral == Approx(1.0).margin(kIntegralTolerance));
}

TEST_CASE("Distribution2D with an all-zero table samples uniformly", "[sampling][quick]") {
    Distribution2D d(std::vector<float>(12, 0.f), 4, 3);
    CHECK(d.is_uniform_fallback());
    float pdf = 0.f;
    Vec2 p = d.sample_continuous(Vec2(0.3f, 0.7f), &pdf);
    CHECK(p.x == Approx(0.3f));
    CHECK(p.y == Approx(0.7f));
    CHECK(pdf == 1.f);
}

TEST_CASE("power heuristic limits and complementarity", "[sampling][quick]") {
    const float inf = std::numeric_limits<float>::infinity();
    CHECK(power_heuristic(1, inf, 1, 3.f) == 1.f);
    CHECK(power_heuristic(1, 3.f, 1, inf) == 0.f);
    CHECK(power_heuristic(1, 0.f, 1, 0.f) == 0.f);
    CHECK(power_heuristic(1, 2.f, 1, 0.f) == 1.f);
    CHECK(power_heuristic(1, 0.f, 1, 2.f) == 0.f);
    CHECK(power_heuristic(1, 1.f, 1, 1.f) == Approx(0.5f));
    CHECK(power_heuristic(1, 1.f, 1, 2.f) == Approx(0.2f));
    CHECK(power_heuristic(2, 1.f, 1, 2.f) == Approx(0.5f));
    // Huge densities must not overflow their squares.
    CHECK(power_heuristic(1, 1e30f, 1, 1e30f) == Approx(0.5f));
    CHECK(std::isfinite(power_heuristic(1, 1e-30f, 1, 1e30f)));
    Pcg32 rng(1, 1);
    for (int i = 0; i < 1000; ++i) {
        float a = std::exp(20.f * (rng.next_float() - 0.5f));
        float b = std::exp(20.f * (rng.next_float() - 0.5f));
        REQUIRE(power_heuristic(1, a, 1, b) + power_heuristic(1, b, 1, a) == Approx(1.f));
        REQUIRE(balance_heuristic(1, a, 1, b) + balance_heuristic(1, b, 1, a) == Approx(1.f));
    }
}
