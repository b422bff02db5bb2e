// BSDF furnace: for every BSDF kind, the directional albedo estimated by importance sampling
// (the mean of f |cos| / pdf over bsdf_sample, with its standard error) equals the albedo from
// deterministic quadrature of f |cos| over the sphere (delta lobes: their analytic lobe
// weights), at several angles, from both sides for dielectrics.
//
// The albedo counts transmitted radiance with the factor eta^2 that undoes the 1/eta^2 radiance
// scaling of bsdf.h: a lossless dielectric conserves power (R + T = 1), while its radiance
// albedo is R + T / eta^2. With that convention the lossless cases give exactly 1 (white
// Lambertian, white mirror, white smooth glass); the rough materials (conductor with F ~ 1,
// white rough glass) give less than 1, the single-scattering energy that the Smith
// shadowing-masking term removes, and the test checks that loss against the quadrature.
#include "../support/chi2.h"
#include "candela/bsdf/bsdf.h"
#include "candela/sampling/rng.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <sstream>

using namespace candela;

namespace {

/// z bound of the importance-sampled albedo against the quadrature (one-sided false failure
/// rate ~6e-7 per comparison; ~60 comparisons in this file).
constexpr double kZ = 5.0;
/// Samples per importance-sampled albedo: standard errors of ~1e-3 for the rough lobes.
constexpr int kSamples = 100000;
/// Quadrature accuracy: smooth integrands are resolved to ~1e-6 of their value; the horizon
/// cut of wide lobes and the Fresnel kink at the critical angle cross cells and are resolved
/// to ~1e-4 at worst (chi2.h). Added to the statistical bound.
constexpr double kQuadratureTol = 2e-4;
/// Quadrature cells and absolute tolerance in total. Measured: these agree with 40 x 80 cells
/// and a tolerance of 1e-7 to within 2e-6 on every rough-glass case below, at a fifth of the
/// cost (the adaptive rule spends its time on the discontinuities, not the cells).
constexpr int kThetaBins = 20, kPhiBins = 40;
constexpr double kQuadratureAbsTol = 1e-4;
/// Float rounding of a weight that is 1 in exact arithmetic (a few ulps), for the bound
/// albedo <= 1 when every sample weighs the same (zero variance).
constexpr double kFloatFloor = 1e-6;
/// Largest standard error accepted: guards against an estimate whose error bar is so wide that
/// the z-test has no power.
constexpr double kMaxStdErr = 5e-3;

Vec3 dir_theta(float theta_deg, float phi_deg = 30.f) {
    float t = deg_to_rad(theta_deg), p = deg_to_rad(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

/// n of the side of direction w for a dielectric (+z outside, vacuum).
float side_index(const Material& m, const Vec3& w) {
    return w.z > 0.f ? 1.f : m.ior;
}

/// Power weight of a direction: eta^2 = (n(wi side) / n(wo side))^2 for transmission, else 1.
float power_weight(const Material& m, const Vec3& wo, const Vec3& wi) {
    if (!m.has_transmission() || wo.z * wi.z > 0.f) return 1.f;
    const float eta = side_index(m, wi) / side_index(m, wo);
    return eta * eta;
}

struct Estimate {
    double mean = 0.0, se = 0.0;
};

/// Mean and standard error of the green channel of f |cos| / pdf (times the power weight) over
/// kSamples BSDF samples; failed samples count as 0.
Estimate albedo_sampled(const Material& m, const Vec3& wo, std::uint64_t seed) {
    Pcg32 rng(seed, 77);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < kSamples; ++i) {
        const Vec2 u(rng.next_float(), rng.next_float());
        auto s = bsdf_sample(m, wo, u, rng.next_float());
        double v = 0.0;
        if (s && s->pdf > 0.f)
            v = double(s->f.y) * std::abs(s->wi.z) / s->pdf * power_weight(m, wo, s->wi);
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / kSamples;
    return {mean, std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples)};
}

/// Quadrature of f |cos| (times the power weight) over the half space on the side `side` of the
/// surface (side = +1: wo's side, -1: the other), magnified about `axis` by `zoom`.
double half_space_quadrature(const Material& m, const Vec3& wo, float side, const Vec3& axis,
                             double zoom) {
    auto g = [m, wo, side](const Vec3& wi) -> float {
        if (!(wi.z * wo.z * side > 0.f)) return 0.f;
        return bsdf_f(m, wo, wi).y * std::abs(wi.z) * power_weight(m, wo, wi);
    };
    return test::integrate_sphere(test::zoomed_density(g, axis, zoom), kThetaBins, kPhiBins,
                                  kQuadratureAbsTol);
}

/// Deterministic directional albedo of a non-delta material: the reflected half space zoomed
/// about the mirror direction, the transmitted one about the smooth refraction direction (or
/// the inward normal under total internal reflection). Lobes of width ~alpha are magnified to
/// ~1 radian.
double albedo_quadrature(const Material& m, const Vec3& wo, float alpha) {
    const double zoom = std::max(1.0, 0.5 / double(alpha));
    const float up = wo.z > 0.f ? 1.f : -1.f;
    // Wide lobes are integrated unrotated, so that the horizon lies on cell edges.
    const bool wide = zoom == 1.0;
    double sum = half_space_quadrature(m, wo, 1.f,
                                       wide ? Vec3(0.f, 0.f, up) : Vec3(-wo.x, -wo.y, wo.z), zoom);
    if (m.has_transmission()) {
        Vec3 axis(0.f, 0.f, -up);
        Vec3 wt;
        if (!wide && refract(wo, Vec3(0.f, 0.f, up), wo.z > 0.f ? m.ior : 1.f / m.ior, &wt))
            axis = wt;
        sum += half_space_quadrature(m, wo, -1.f, axis, zoom);
    }
    return sum;
}

void check_agreement(const Estimate& e, double expected, const std::string& what) {
    INFO(what << ": importance sampling " << e.mean << " +- " << e.se << ", quadrature "
              << expected);
    CHECK(std::abs(e.mean - expected) <= kZ * e.se + kQuadratureTol * std::max(1.0, expected));
    CHECK(e.se <= kMaxStdErr);
}

Material white_glass(BsdfKind kind, float roughness, float ior) {
    Material m;
    m.kind = kind;
    m.roughness = roughness;
    m.ior = ior;
    m.reflectance = m.transmittance = Rgb(1.f);
    return m;
}

} // namespace

TEST_CASE("furnace: white Lambertian and white mirror reflect everything", "[bsdf][stat]") {
    Material lambert;
    lambert.albedo = Rgb(1.f);
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    mirror.reflectance = Rgb(1.f);
    for (float theta : {0.f, 45.f, 85.f})
        for (float side : {1.f, -1.f}) {
            Vec3 wo = dir_theta(theta);
            wo.z *= side;
            std::ostringstream what;
            what << "theta " << theta << " side " << side;
            // Lambertian: quadrature of (1/pi) |cos| over the hemisphere is 1.
            const double q = albedo_quadrature(lambert, wo, 1.f);
            CHECK(q == Approx(1.0).margin(kQuadratureTol));
            check_agreement(albedo_sampled(lambert, wo, 1), q, "lambert " + what.str());
            // Mirror: the delta lobe's weight, reflectance = 1, for every sample.
            check_agreement(albedo_sampled(mirror, wo, 2), 1.0, "mirror " + what.str());
        }
}

TEST_CASE("furnace: smooth glass and refraction conserve power", "[bsdf][stat]") {
    for (float ior : {1.5f, 2.4f})
        for (float theta : {0.f, 30.f, 60.f, 85.f})
            for (float side : {1.f, -1.f}) {
                Vec3 wo = dir_theta(theta);
                wo.z *= side;
                std::ostringstream what;
                what << "ior " << ior << " theta " << theta << " side " << side;
                // Glass: F reflected + (1 - F) transmitted (eta^2 undoes the 1/eta^2) = 1.
                const Material glass = white_glass(BsdfKind::Glass, 0.f, ior);
                REQUIRE(glass.is_delta());
                const Estimate g = albedo_sampled(glass, wo, 3);
                check_agreement(g, 1.0, "glass " + what.str());
                // Refraction: 1, or 0 under total internal reflection (absorbed).
                const Material refr = white_glass(BsdfKind::Refraction, 0.f, ior);
                const bool tir = fresnel_dielectric(wo.z, ior) >= 1.f;
                check_agreement(albedo_sampled(refr, wo, 4), tir ? 0.0 : 1.0,
                                "refraction " + what.str());
                // The radiance albedo itself is R + T / eta^2, below 1 entering a denser medium.
                const float F = fresnel_dielectric(wo.z, ior);
                const float eta = wo.z > 0.f ? ior : 1.f / ior;
                Pcg32 rng(5, 5);
                double radiance = 0.0;
                constexpr int kN = 1000;
                for (int i = 0; i < kN; ++i) {
                    auto s = bsdf_sample(glass, wo, Vec2(0.5f, 0.5f), rng.next_float());
                    REQUIRE(s);
                    radiance += s->f.y * std::abs(s->wi.z) / s->pdf;
                }
                // Each sample's weight is exactly 1 or 1/eta^2; the mean is within binomial
                // noise of F + (1 - F) / eta^2.
                const double expect = F + (1.0 - F) / (eta * eta);
                const double sd =
                    std::abs(1.0 - 1.0 / (eta * eta)) * std::sqrt(double(F) * (1.0 - F) / kN);
                CHECK(std::abs(radiance / kN - expect) <= kZ * sd + 1e-6);
            }
}

TEST_CASE("furnace: rough conductor albedo against quadrature", "[bsdf][stat]") {
    // F ~ 1 (k = 1000): the albedo is the Smith single-scattering energy, at most 1.
    Material m;
    m.kind = BsdfKind::Microfacet;
    m.eta = Rgb(1.f);
    m.k = Rgb(1000.f);
    std::uint64_t seed = 10;
    for (float alpha : {0.05f, 0.3f, 0.8f})
        for (float theta : {0.f, 45.f, 75.f}) {
            m.alpha = alpha;
            const Vec3 wo = dir_theta(theta);
            const double q = albedo_quadrature(m, wo, alpha);
            const Estimate e = albedo_sampled(m, wo, seed++);
            std::ostringstream what;
            what << "alpha " << alpha << " theta " << theta << " (energy loss " << 1.0 - q << ")";
            check_agreement(e, q, what.str());
            CHECK(q <= 1.0 + kQuadratureTol);
            CHECK(q > 0.5); // Smith's loss is a few percent, up to ~30% at alpha 0.8, grazing
        }
}

TEST_CASE("furnace: rough glass and rough refraction against quadrature", "[bsdf][stat]") {
    std::uint64_t seed = 40;
    for (float alpha : {0.05f, 0.3f, 0.8f})
        for (float theta : {0.f, 45.f, 75.f})
            for (float side : {1.f, -1.f}) {
                const Material m = white_glass(BsdfKind::Glass, alpha, 1.5f);
                REQUIRE_FALSE(m.is_delta());
                Vec3 wo = dir_theta(theta);
                wo.z *= side;
                const double q = albedo_quadrature(m, wo, alpha);
                const Estimate e = albedo_sampled(m, wo, seed++);
                std::ostringstream what;
                what << "glass alpha " << alpha << " theta " << theta << " side " << side
                     << " (energy loss " << 1.0 - q << ")";
                check_agreement(e, q, what.str());
                // Lossless facets: only shadowing-masking removes energy.
                CHECK(q <= 1.0 + kQuadratureTol);
                CHECK(e.mean <= 1.0 + kZ * e.se + kFloatFloor);
                CHECK(q > 0.5);
            }
    for (float theta : {0.f, 45.f, 75.f})
        for (float side : {1.f, -1.f}) {
            const Material m = white_glass(BsdfKind::Refraction, 0.3f, 1.5f);
            Vec3 wo = dir_theta(theta);
            wo.z *= side;
            const double q = albedo_quadrature(m, wo, 0.3f);
            std::ostringstream what;
            what << "refraction alpha 0.3 theta " << theta << " side " << side;
            check_agreement(albedo_sampled(m, wo, seed++), q, what.str());
            CHECK(q <= 1.0 + kQuadratureTol);
        }
}
