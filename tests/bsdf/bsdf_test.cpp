#include "../support/chi2.h"
#include "candela/bsdf/bsdf.h"
#include "candela/sampling/rng.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;
using candela::test::chi2_test;
using candela::test::sidak_significance;

namespace {

// Chi-square tests in this file: Lambertian (4 angles x 2 sides) + microfacet (5 alphas x 4
// angles + 2 back-side cases). Family-wise error rate 1% (Sidak).
constexpr int kNumChi2Tests = 8 + 22;
const double kSignificance = sidak_significance(0.01, kNumChi2Tests);
constexpr int kChi2Samples = 1000000;
// Relative agreement between independently computed float values of the same quantity
// (a few ulps after a handful of transcendental operations).
constexpr float kRelTol = 1e-4f;
// Integrated-pdf tolerance: the harness quadrature resolves smooth lobes to ~1e-6 and lobe cut
// offs (horizon) inside cells to ~1e-4.
constexpr double kIntegralTolerance = 2e-3;

Vec3 dir_theta(float theta_deg, float phi_deg = 30.f) {
    float t = deg_to_rad(theta_deg), p = deg_to_rad(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

Material diffuse(Rgb albedo) {
    Material m;
    m.kind = BsdfKind::Diffuse;
    m.albedo = albedo;
    return m;
}

Material microfacet(float alpha, Rgb eta = Rgb(0.2f, 0.9f, 1.3f), Rgb k = Rgb(3.9f, 2.4f, 2.2f)) {
    Material m;
    m.kind = BsdfKind::Microfacet;
    m.alpha = alpha;
    m.eta = eta;
    m.k = k;
    return m;
}

Material dielectric(BsdfKind kind, float ior) {
    Material m;
    m.kind = kind;
    m.ior = ior;
    m.reflectance = Rgb(0.9f, 0.8f, 0.7f);
    m.transmittance = Rgb(0.6f, 0.7f, 0.95f);
    return m;
}

bool close_rgb(const Rgb& a, const Rgb& b, float rel) {
    for (int i = 0; i < 3; ++i)
        if (std::abs(a[i] - b[i]) > rel * std::max(std::abs(a[i]), std::abs(b[i])) + 1e-30f)
            return false;
    return true;
}

candela::test::Chi2Result run_bsdf_chi2(const Material& m, const Vec3& wo, double zoom,
                                        std::uint64_t seed, int theta_bins, int phi_bins) {
    auto sample = [m, wo](Vec2 u, float uc) -> std::optional<Vec3> {
        auto s = bsdf_sample(m, wo, u, uc);
        if (!s) return std::nullopt;
        return s->wi;
    };
    auto pdf = [m, wo](const Vec3& wi) { return bsdf_pdf(m, wo, wi); };
    if (zoom <= 1.0)
        return chi2_test(sample, pdf, kChi2Samples, theta_bins, phi_bins, seed, kSignificance);
    Vec3 axis(-wo.x, -wo.y, wo.z); // specular reflection direction
    auto [zs, zp] = candela::test::zoom_view(sample, pdf, axis, zoom);
    return chi2_test(zs, zp, kChi2Samples, theta_bins, phi_bins, seed, kSignificance);
}

} // namespace

TEST_CASE("chi2: Lambertian", "[bsdf][stat]") {
    Material m = diffuse(Rgb(0.5f));
    for (float theta : {0.f, 30.f, 60.f, 80.f})
        for (float side : {1.f, -1.f}) {
            Vec3 wo = dir_theta(theta);
            wo.z *= side;
            INFO("theta_o = " << theta << ", side " << side);
            auto r = run_bsdf_chi2(m, wo, 1.0,
                                   100 + std::uint64_t(theta) + (side < 0.f ? 1000u : 0u), 20, 40);
            INFO(r.message);
            CHECK(r.passed);
            CHECK(r.pdf_integral == Approx(1.0).margin(kIntegralTolerance));
        }
}

TEST_CASE("chi2: Beckmann microfacet conductor", "[bsdf][stat]") {
    std::uint64_t seed = 200;
    for (float alpha : {0.025f, 0.05f, 0.25f, 0.5f, 0.8f})
        for (float theta : {0.f, 30.f, 60.f, 80.f}) {
            Material m = microfacet(alpha);
            Vec3 wo = dir_theta(theta);
            // Magnify the lobe (angular width ~2 alpha) to span ~1 radian so that it covers many
            // cells; wide lobes are tested unzoomed.
            double zoom = std::max(1.0, 0.5 / double(alpha));
            INFO("alpha = " << alpha << ", theta_o = " << theta << ", zoom = " << zoom);
            auto r = run_bsdf_chi2(m, wo, zoom, seed++, 40, 80);
            INFO(r.message);
            CHECK(r.passed);
            // Failed samples (reflections below the horizon) account for the missing mass.
            CHECK(r.pdf_integral <= 1.0 + kIntegralTolerance);
        }
    // Two-sided: a viewer below the surface sees the mirrored lobe.
    for (float alpha : {0.05f, 0.5f}) {
        Material m = microfacet(alpha);
        Vec3 wo = dir_theta(45.f);
        wo.z = -wo.z;
        INFO("back side, alpha = " << alpha);
        auto r = run_bsdf_chi2(m, wo, std::max(1.0, 0.5 / double(alpha)), seed++, 40, 80);
        INFO(r.message);
        CHECK(r.passed);
    }
}

TEST_CASE("chi2 has power for narrow microfacet lobes", "[bsdf][stat]") {
    // Samples of alpha = 0.025 tested against the pdf of alpha = 0.0265 (6% wider) must be
    // rejected: the zoomed view resolves the lobe shape.
    Material sampled = microfacet(0.025f), claimed = microfacet(0.0265f);
    Vec3 wo = dir_theta(30.f);
    auto sample = [&](Vec2 u, float uc) -> std::optional<Vec3> {
        auto s = bsdf_sample(sampled, wo, u, uc);
        if (!s) return std::nullopt;
        return s->wi;
    };
    auto pdf = [&](const Vec3& wi) { return bsdf_pdf(claimed, wo, wi); };
    auto [zs, zp] = candela::test::zoom_view(sample, pdf, Vec3(-wo.x, -wo.y, wo.z), 20.0);
    auto r = chi2_test(zs, zp, kChi2Samples, 40, 80, 300, kSignificance);
    INFO(r.message);
    CHECK_FALSE(r.passed);
}

TEST_CASE("sampled f and pdf agree with bsdf_f and bsdf_pdf", "[bsdf][quick]") {
    Pcg32 rng(9, 9);
    std::vector<Material> mats = {diffuse(Rgb(0.3f, 0.6f, 0.9f)), microfacet(0.025f),
                                  microfacet(0.3f), microfacet(1.2f)};
    for (const Material& m : mats)
        for (int i = 0; i < 20000; ++i) {
            Vec3 wo = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
            auto s = bsdf_sample(m, wo, Vec2(rng.next_float(), rng.next_float()), rng.next_float());
            if (!s) continue;
            REQUIRE(s->wi.z * wo.z > 0.f);
            REQUIRE(std::abs(length(s->wi) - 1.f) < 1e-5f);
            REQUIRE(s->pdf == Approx(bsdf_pdf(m, wo, s->wi)).epsilon(kRelTol));
            REQUIRE(close_rgb(s->f, bsdf_f(m, wo, s->wi), kRelTol));
            REQUIRE((s->flags & kSpecular) == 0);
            REQUIRE(s->eta == 1.f);
        }
}

TEST_CASE("reciprocity of diffuse and microfacet BSDFs", "[bsdf][quick]") {
    Pcg32 rng(10, 1);
    std::vector<Material> mats = {diffuse(Rgb(0.7f)), microfacet(0.05f), microfacet(0.4f)};
    for (const Material& m : mats)
        for (int i = 0; i < 20000; ++i) {
            Vec3 a = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
            Vec3 b = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
            REQUIRE(close_rgb(bsdf_f(m, a, b), bsdf_f(m, b, a), kRelTol));
        }
}

TEST_CASE("no NaN or Inf from any material in degenerate configurations", "[bsdf][quick]") {
    std::vector<Material> mats = {diffuse(Rgb(0.5f)),
                                  microfacet(0.f),
                                  microfacet(1e-6f),
                                  microfacet(0.5f),
                                  microfacet(0.3f, Rgb(1.f), Rgb(0.f)),
                                  dielectric(BsdfKind::Glass, 1.5f),
                                  dielectric(BsdfKind::Refraction, 1.5f),
                                  dielectric(BsdfKind::Glass, 1.f)};
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    Material emit;
    emit.kind = BsdfKind::Emission;
    emit.radiance = Rgb(5.f);
    mats.push_back(mirror);
    mats.push_back(emit);
    std::vector<Vec3> dirs = {Vec3(0, 0, 1),
                              Vec3(0, 0, -1),
                              Vec3(1, 0, 0),
                              Vec3(0, 1, 0),
                              Vec3(1, 0, 1e-8f),
                              Vec3(1, 0, -1e-8f),
                              normalize(Vec3(1, 1, 1e-4f)),
                              normalize(Vec3(1, 0, 1)),
                              normalize(Vec3(-1, 0, 1))};
    const Vec2 us[] = {Vec2(0, 0), Vec2(0.99999994f, 0.99999994f), Vec2(0.5f, 0.5f),
                       Vec2(0.99999994f, 0.f)};
    for (const Material& m : mats)
        for (const Vec3& wo : dirs) {
            for (const Vec3& wi : dirs) {
                REQUIRE(is_finite(bsdf_f(m, wo, wi)));
                REQUIRE(std::isfinite(bsdf_pdf(m, wo, wi)));
                REQUIRE(bsdf_pdf(m, wo, wi) >= 0.f);
            }
            for (Vec2 u : us)
                for (float uc : {0.f, 0.5f, 0.99999994f}) {
                    auto s = bsdf_sample(m, wo, u, uc);
                    if (!s) continue;
                    REQUIRE(is_finite(s->f));
                    REQUIRE(is_finite(s->wi));
                    REQUIRE(std::isfinite(s->pdf));
                    REQUIRE(s->pdf > 0.f);
                    REQUIRE(is_finite(s->weight));
                }
        }
    REQUIRE(is_finite(bsdf_albedo_hint(emit)));
}

TEST_CASE("a precomputed cosine direction gives the same sample as computing it", "[bsdf][quick]") {
    const Material m = diffuse(Rgb(0.2f, 0.5f, 0.8f));
    Pcg32 rng(5, 6);
    for (int i = 0; i < 20000; ++i) {
        const Vec3 wo = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
        const Vec2 u(rng.next_float(), rng.next_float());
        const Vec3 cosine = square_to_cosine_hemisphere(u);
        const auto a = bsdf_sample(m, wo, u, 0.f);
        const auto b = bsdf_sample(m, wo, u, 0.f, &cosine);
        REQUIRE(a.has_value() == b.has_value());
        if (!a) continue;
        REQUIRE(a->wi == b->wi);
        REQUIRE(a->f == b->f);
        REQUIRE(a->pdf == b->pdf);
        REQUIRE(a->weight == b->weight);
    }
}

TEST_CASE("a sample's path weight is f |cos| / pdf for every material", "[bsdf][quick]") {
    // The simplified weights (Lambertian albedo, the smooth lobes' reflectance and
    // transmittance / eta^2) must equal the quotient they replace, to its rounding.
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    mirror.reflectance = Rgb(0.9f, 0.7f, 0.5f);
    Material glass = dielectric(BsdfKind::Glass, 1.5f);
    glass.transmittance = Rgb(0.8f, 0.9f, 1.f);
    Material rough = dielectric(BsdfKind::Glass, 1.33f);
    rough.roughness = 0.3f;
    const std::vector<Material> mats = {diffuse(Rgb(0.3f, 0.6f, 0.9f)),
                                        microfacet(0.3f),
                                        mirror,
                                        glass,
                                        dielectric(BsdfKind::Refraction, 1.5f),
                                        rough};
    Pcg32 rng(17, 3);
    for (const Material& m : mats) {
        int checked = 0;
        for (int i = 0; i < 5000; ++i) {
            const Vec3 wo = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
            auto s = bsdf_sample(m, wo, Vec2(rng.next_float(), rng.next_float()), rng.next_float());
            if (!s) continue;
            ++checked;
            const Rgb quotient = s->f * (std::abs(s->wi.z) / s->pdf);
            REQUIRE(close_rgb(s->weight, quotient, kRelTol));
        }
        // Every material samples most directions (only grazing or below-horizon ones fail).
        REQUIRE(checked > 2500);
    }
}

TEST_CASE("Lambertian with albedo 1 conserves energy", "[bsdf][stat]") {
    // Estimate the directional albedo with uniform hemisphere sampling (not the BSDF's own
    // sampling, which would make every weight exactly 1). The estimator of integral f cos has
    // variance 2pi * 1/pi... computed empirically; accept 5 standard errors.
    constexpr double kSigmas = 5.0;
    constexpr int kN = 200000;
    Material m = diffuse(Rgb(1.f));
    Pcg32 rng(12, 3);
    for (float theta : {0.f, 45.f, 85.f}) {
        Vec3 wo = dir_theta(theta);
        double sum = 0, sum2 = 0;
        for (int i = 0; i < kN; ++i) {
            Vec3 wi = square_to_uniform_hemisphere(Vec2(rng.next_float(), rng.next_float()));
            double v = bsdf_f(m, wo, wi).y * wi.z / square_to_uniform_hemisphere_pdf(wi);
            sum += v;
            sum2 += v * v;
        }
        double mean = sum / kN, se = std::sqrt((sum2 / kN - mean * mean) / kN);
        INFO("theta_o = " << theta << ": albedo " << mean << " +- " << se);
        CHECK(std::abs(mean - 1.0) < kSigmas * se);
    }
}

TEST_CASE("microfacet energy: zero for an index-matched conductor, at most 1 otherwise",
          "[bsdf][stat]") {
    // eta = 1, k = 0: the conductor is index-matched to vacuum and F = 0 (up to float rounding
    // in the exact Fresnel formula, relative to a perfect conductor's response).
    constexpr float kMatchedResidual = 1e-5f;
    Material matched = microfacet(0.3f, Rgb(1.f), Rgb(0.f));
    Material mirror_like = microfacet(0.3f, Rgb(1.f), Rgb(1000.f));
    Pcg32 rng(13, 5);
    for (int i = 0; i < 1000; ++i) {
        Vec3 wo = square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
        Vec3 wi = square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(max_component(bsdf_f(matched, wo, wi)) <=
                kMatchedResidual * max_component(bsdf_f(mirror_like, wo, wi)));
    }
    // A near-perfect conductor (F ~ 1): the directional albedo (integral of f cos) must not
    // exceed 1, estimated by importance sampling and cross-checked against uniform sampling.
    constexpr double kSigmas = 5.0;
    constexpr int kN = 200000;
    Material perfect = microfacet(0.5f, Rgb(1.f), Rgb(1000.f));
    for (float alpha : {0.05f, 0.25f, 0.5f, 1.0f}) {
        perfect.alpha = alpha;
        for (float theta : {0.f, 45.f, 80.f}) {
            Vec3 wo = dir_theta(theta);
            double s_is = 0, s2_is = 0, s_u = 0, s2_u = 0;
            for (int i = 0; i < kN; ++i) {
                Vec2 u(rng.next_float(), rng.next_float());
                auto s = bsdf_sample(perfect, wo, u, 0.5f);
                double v = s ? s->f.y * s->wi.z / s->pdf : 0.0;
                s_is += v;
                s2_is += v * v;
                Vec3 wi = square_to_cosine_hemisphere(u);
                double w = bsdf_f(perfect, wo, wi).y * kPi; // f cos / (cos/pi)
                s_u += w;
                s2_u += w * w;
            }
            double m_is = s_is / kN,
                   se_is = std::sqrt(std::max(0.0, s2_is / kN - m_is * m_is) / kN);
            double m_u = s_u / kN, se_u = std::sqrt(std::max(0.0, s2_u / kN - m_u * m_u) / kN);
            INFO("alpha " << alpha << ", theta_o " << theta << ": albedo (importance) " << m_is
                          << " +- " << se_is << ", (cosine) " << m_u << " +- " << se_u);
            CHECK(m_is <= 1.0 + kSigmas * se_is);
            CHECK(std::abs(m_is - m_u) < kSigmas * std::sqrt(se_is * se_is + se_u * se_u));
            // At normal incidence only normals with tan(theta_h) < 1 reflect above the horizon
            // and F, G <= 1, so the albedo is at most P(tan^2 < 1) = 1 - exp(-1/alpha^2).
            if (theta == 0.f) {
                double bound = 1.0 - std::exp(-1.0 / (double(alpha) * alpha));
                CHECK(m_is <= bound + kSigmas * se_is);
            }
        }
    }
}

TEST_CASE("Fresnel equations", "[bsdf][quick]") {
    // Normal incidence: ((eta - 1) / (eta + 1))^2.
    CHECK(fresnel_dielectric(1.f, 1.5f) == Approx(0.04f).epsilon(kRelTol));
    CHECK(fresnel_dielectric(-1.f, 1.5f) == Approx(0.04f).epsilon(kRelTol));
    CHECK(fresnel_dielectric(0.7f, 1.f) == Approx(0.f).margin(1e-7f));
    // Grazing incidence reflects everything.
    CHECK(fresnel_dielectric(0.f, 1.5f) == Approx(1.f));
    // Total internal reflection beyond the critical angle (inside, sin > 1/1.5).
    float cos_crit = std::sqrt(1.f - 1.f / (1.5f * 1.5f));
    CHECK(fresnel_dielectric(-(cos_crit - 1e-3f), 1.5f) == 1.f);
    CHECK(fresnel_dielectric(-(cos_crit + 1e-3f), 1.5f) < 1.f);
    Pcg32 rng(14, 2);
    // Below this cosine the float round trip cos_i -> cos_t -> cos_i loses digits (1 - cos^2).
    constexpr float kMinWellConditionedCos = 0.05f;
    // F changes fast near grazing; a float round trip of the angle moves it by up to ~1e-5.
    constexpr float kRoundTripTol = 1e-4f;
    for (int i = 0; i < 10000; ++i) {
        float c = kMinWellConditionedCos + (1.f - kMinWellConditionedCos) * rng.next_float();
        float eta = 1.f + 2.f * rng.next_float();
        // Reciprocity: the same interface seen from the other side at the refracted angle.
        float sin2_t = (1.f - c * c) / (eta * eta);
        float cos_t = std::sqrt(1.f - sin2_t);
        REQUIRE(fresnel_dielectric(c, eta) ==
                Approx(fresnel_dielectric(-cos_t, eta)).margin(kRoundTripTol));
        // The exact conductor formula with k = 0 reduces to the dielectric one.
        REQUIRE(fresnel_conductor(c, eta, 0.f) == Approx(fresnel_dielectric(c, eta)).margin(1e-5f));
        float k = 10.f * rng.next_float();
        float fc = fresnel_conductor(c, 3.f * rng.next_float(), k);
        REQUIRE(fc >= 0.f);
        REQUIRE(fc <= 1.f);
        REQUIRE(fresnel_conductor(c, 1.f, 0.f) == Approx(0.f).margin(1e-6f));
    }
    // A strongly absorbing conductor is an almost perfect mirror.
    CHECK(fresnel_conductor(0.8f, 1.f, 1000.f) > 0.999f);
    // Silver at normal incidence from its (eta, k) (green channel): known ~0.97.
    CHECK(fresnel_conductor(1.f, 0.059881f, 3.5892f) == Approx(0.9827f).epsilon(1e-3f));
}

TEST_CASE("specular directions: mirror law, Snell's law, reversibility", "[bsdf][quick]") {
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    mirror.reflectance = Rgb(0.9f, 0.5f, 0.2f);
    Material glass = dielectric(BsdfKind::Glass, 1.5f);
    Material refr = dielectric(BsdfKind::Refraction, 1.5f);
    Pcg32 rng(15, 7);
    for (int i = 0; i < 5000; ++i) {
        Vec3 wo = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
        if (std::abs(wo.z) < 1e-3f) continue;
        auto s = bsdf_sample(mirror, wo, Vec2(0.5f, 0.5f), 0.5f);
        REQUIRE(s);
        REQUIRE(s->wi.x == -wo.x);
        REQUIRE(s->wi.y == -wo.y);
        REQUIRE(s->wi.z == wo.z);
        REQUIRE((s->flags & kSpecular));
        REQUIRE(close_rgb(s->f * std::abs(s->wi.z) / s->pdf, mirror.reflectance, kRelTol));
        REQUIRE(is_black(bsdf_f(mirror, wo, s->wi)));
        REQUIRE(bsdf_pdf(mirror, wo, s->wi) == 0.f);

        // Glass: force transmission with uc close to 1 (unless TIR).
        auto t = bsdf_sample(glass, wo, Vec2(0.f, 0.f), 0.99999994f);
        REQUIRE(t);
        float eta_rel = wo.z > 0.f ? 1.5f : 1.f / 1.5f;
        if (t->flags & kTransmission) {
            REQUIRE(t->wi.z * wo.z < 0.f);
            REQUIRE(t->eta == Approx(eta_rel));
            float sin_o = std::sqrt(std::max(0.f, 1.f - wo.z * wo.z));
            float sin_i = std::sqrt(std::max(0.f, 1.f - t->wi.z * t->wi.z));
            REQUIRE(sin_o == Approx(eta_rel * sin_i).margin(1e-5f)); // Snell: n_o sin = n_i sin
            // Plane of incidence: the tangential parts are anti-parallel.
            REQUIRE(cross(Vec3(wo.x, wo.y, 0), Vec3(t->wi.x, t->wi.y, 0)).z ==
                    Approx(0.f).margin(1e-5f));
            REQUIRE(wo.x * t->wi.x + wo.y * t->wi.y <= 0.f);
            // Reversibility: refracting wi back yields wo.
            auto back = bsdf_sample(refr, t->wi, Vec2(0.f, 0.f), 0.99999994f);
            REQUIRE(back);
            REQUIRE(back->wi.x == Approx(wo.x).margin(1e-4f));
            REQUIRE(back->wi.y == Approx(wo.y).margin(1e-4f));
            REQUIRE(back->wi.z == Approx(wo.z).margin(1e-4f));
            REQUIRE(back->eta == Approx(1.f / eta_rel));
            // Path weight of Glass transmission: transmittance / eta^2 (the pdf is 1 - F).
            Rgb w = t->f * std::abs(t->wi.z) / t->pdf;
            REQUIRE(close_rgb(w, glass.transmittance / (eta_rel * eta_rel), kRelTol));
            float F = fresnel_dielectric(wo.z, 1.5f);
            REQUIRE(t->pdf == Approx(1.f - F).epsilon(kRelTol));
        } else {
            // Only total internal reflection may refuse transmission.
            REQUIRE(wo.z < 0.f);
            REQUIRE(fresnel_dielectric(wo.z, 1.5f) == 1.f);
            REQUIRE(!bsdf_sample(refr, wo, Vec2(0.f, 0.f), 0.5f));
        }
        REQUIRE(is_black(bsdf_f(glass, wo, -wo)));
        REQUIRE(bsdf_pdf(glass, wo, Vec3(-wo.x, -wo.y, wo.z)) == 0.f);
    }
}

TEST_CASE("glass splits energy by Fresnel", "[bsdf][stat]") {
    // The reflected fraction of N samples is binomial(N, F): accept 5 standard deviations.
    constexpr double kSigmas = 5.0;
    constexpr int kN = 100000;
    Material glass = dielectric(BsdfKind::Glass, 1.5f);
    Pcg32 rng(16, 4);
    for (float theta : {0.f, 40.f, 70.f, 85.f}) {
        for (float side : {1.f, -1.f}) {
            Vec3 wo = dir_theta(theta);
            wo.z *= side;
            float F = fresnel_dielectric(wo.z, glass.ior);
            int reflected = 0;
            for (int i = 0; i < kN; ++i) {
                auto s = bsdf_sample(glass, wo, Vec2(rng.next_float(), rng.next_float()),
                                     rng.next_float());
                REQUIRE(s);
                bool refl = (s->flags & kReflection) != 0;
                reflected += refl;
                // Lobe probability, reported as pdf, is F or 1 - F; they sum to one.
                REQUIRE(s->pdf == Approx(refl ? F : 1.f - F).epsilon(kRelTol));
                Rgb w = s->f * std::abs(s->wi.z) / s->pdf;
                Rgb expect = refl ? glass.reflectance : glass.transmittance / (s->eta * s->eta);
                REQUIRE(close_rgb(w, expect, kRelTol));
            }
            double frac = double(reflected) / kN;
            double sd = std::sqrt(std::max(double(F) * (1.0 - F), 1e-12) / kN);
            INFO("theta " << theta << " side " << side << ": F = " << F << ", fraction " << frac);
            CHECK(std::abs(frac - F) <= kSigmas * sd + 1e-12);
        }
    }
    // Energy of an untinted interface: R + T = 1 with radiance scaling undone (T * eta^2).
    Material white = dielectric(BsdfKind::Glass, 1.33f);
    white.reflectance = Rgb(1.f);
    white.transmittance = Rgb(1.f);
    for (float theta : {10.f, 50.f, 80.f}) {
        Vec3 wo = dir_theta(theta);
        auto r = bsdf_sample(white, wo, Vec2(0, 0), 0.f);
        auto t = bsdf_sample(white, wo, Vec2(0, 0), 0.99999994f);
        REQUIRE(r);
        REQUIRE(t);
        float R = r->f.x * std::abs(r->wi.z);
        float T = t->f.x * std::abs(t->wi.z) * t->eta * t->eta;
        CHECK(R + T == Approx(1.f).epsilon(kRelTol));
    }
}

TEST_CASE("emission and albedo hints", "[bsdf][quick]") {
    Material e;
    e.kind = BsdfKind::Emission;
    e.radiance = Rgb(2.f, 4.f, 1.f);
    CHECK(!bsdf_sample(e, Vec3(0, 0, 1), Vec2(0.3f, 0.3f), 0.3f));
    CHECK(is_black(bsdf_f(e, Vec3(0, 0, 1), Vec3(0, 0, 1))));
    CHECK(bsdf_albedo_hint(e).y == 1.f);
    CHECK(bsdf_albedo_hint(diffuse(Rgb(0.25f))).x == 0.25f);
    Rgb hint = bsdf_albedo_hint(microfacet(0.3f));
    CHECK(hint.x > 0.f);
    CHECK(hint.x <= 1.f);
}
