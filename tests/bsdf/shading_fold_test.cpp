// The folded lobe of a shading normal that leans from the geometric one (bsdf_f_folded,
// bsdf_pdf_folded, bsdf_sample_folded): for a Lambertian, a rough conductor and a rough glass
// with the geometric normal 20 degrees off the shading normal, f|cos| integrates to what the
// unfolded lobe integrates to over the whole sphere (the energy a drop would lose is kept, none
// is created), the pdf still integrates to the unfolded one's mass, the sampler draws the
// folded pdf (chi-square), every sample leaves on the geometric side its lobe says with f and
// pdf equal to the evaluation's, and no sampled path weight exceeds 1.
#include "../support/chi2.h"
#include "candela/bsdf/bsdf.h"
#include "candela/sampling/rng.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace candela;
using candela::test::chi2_test;
using candela::test::integrate_sphere;
using candela::test::sidak_significance;

namespace {

// The 80-triangle icosphere's vertex normals lean up to 21 degrees from its faces.
constexpr float kTiltDeg = 20.f;
// Chi-square tests in this file: 3 materials x 2 views.
constexpr int kNumChi2Tests = 6;
// Family-wise false-failure rate 1% over the file (Sidak).
const double kSignificance = sidak_significance(0.01, kNumChi2Tests);
// 40 x 80 cells then expect ~60 counts a cell where a lobe is, enough to see the fold's mass
// (2-20 % of the lobe, in a band of cells along the geometric plane) moved or missing.
constexpr int kChi2Samples = 200000;
// Quadrature of integrands with jumps along the geometric and the shading planes: the harness
// resolves a jump to ~1e-3 of the crossed cells' share; folded and whole integrals measured
// within 2e-6 of each other here.
constexpr double kIntegralTolerance = 1e-3;
// What a drop would lose in each configuration below is at least this (measured 0.024 to 0.21
// of f|cos| over the sphere): the fold has something to restore, far above the quadrature's
// tolerance.
constexpr double kMinFoldedMass = 5e-3;
// f and pdf of a sample against the evaluation at its direction: the microfacet samplers'
// own agreement (rough_dielectric_test.cpp) is a few ulps through exp and the Jacobians.
constexpr float kRelTol = 2e-4f;
// A sampled path weight is a mean of lobe weights <= 1; float rounding of the quotient.
constexpr float kWeightTol = 1e-5f;
// Samples checked one by one for side, f, pdf and weight.
constexpr int kSampleChecks = 20000;

Vec3 dir_theta(float theta_deg, float phi_deg) {
    const float t = deg_to_rad(theta_deg), p = deg_to_rad(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

struct Case {
    std::string name;
    Material m;
    std::vector<Vec3> wos;
};

std::vector<Case> cases() {
    Material diffuse;
    diffuse.kind = BsdfKind::Diffuse;
    diffuse.albedo = Rgb(1.f);
    Material conductor;
    conductor.kind = BsdfKind::Microfacet;
    conductor.alpha = 0.3f;
    conductor.eta = Rgb(1.f);
    conductor.k = Rgb(1000.f); // F ~ 1
    Material glass;
    glass.kind = BsdfKind::Glass;
    glass.roughness = 0.3f;
    glass.ior = 1.5f;
    glass.reflectance = glass.transmittance = Rgb(1.f);
    // ng leans toward +x: the reflections that fall below it, and the transmissions out of
    // the inside that fall below it, leave toward -x (a transmission into the glass cannot
    // leave 70 degrees from the normal, as it would need to come out above it). Every wo is on
    // one side of both normals, as the shading-normal bend leaves it.
    const Vec3 grazing_plus = dir_theta(60.f, 0.f);
    const Vec3 inside = -dir_theta(40.f, 180.f); // refracts out near grazing, toward -x
    return {{"diffuse", diffuse, {grazing_plus, dir_theta(10.f, 90.f)}},
            {"rough conductor", conductor, {grazing_plus, dir_theta(75.f, 20.f)}},
            {"rough glass", glass, {grazing_plus, inside}}};
}

Vec3 tilted_ng() {
    return dir_theta(kTiltDeg, 0.f);
}

} // namespace

TEST_CASE("folded lobes keep the energy a drop loses and create none", "[bsdf][stat]") {
    const Vec3 ng = tilted_ng();
    std::uint64_t seed = 101;
    for (const Case& c : cases()) {
        for (const Vec3& wo : c.wos) {
            INFO(c.name << ", wo " << wo.x << " " << wo.y << " " << wo.z);
            REQUIRE(dot(wo, ng) * wo.z > 0.f);
            const Material& m = c.m;
            auto whole = [&](const Vec3& w) {
                return double(luminance(bsdf_f(m, wo, w))) * std::abs(w.z);
            };
            auto kept = [&](const Vec3& w) {
                return bsdf_detail::lobe_side_agrees(wo, w, ng) ? whole(w) : 0.0;
            };
            auto folded = [&](const Vec3& w) {
                return double(luminance(bsdf_f_folded(m, wo, w, &ng))) * std::abs(w.z);
            };
            const double e_whole = integrate_sphere(whole, 40, 80, 1e-6);
            const double e_kept = integrate_sphere(kept, 40, 80, 1e-6);
            const double e_folded = integrate_sphere(folded, 40, 80, 1e-6);
            INFO("f|cos| over the sphere: whole " << e_whole << ", dropped " << e_kept
                                                  << ", folded " << e_folded);
            REQUIRE(e_whole - e_kept > kMinFoldedMass);
            CHECK(std::abs(e_folded - e_whole) < kIntegralTolerance);

            auto pdf_whole = [&](const Vec3& w) { return bsdf_pdf(m, wo, w); };
            auto pdf_folded = [&](const Vec3& w) { return bsdf_pdf_folded(m, wo, w, &ng); };
            const double p_whole = integrate_sphere(pdf_whole, 40, 80, 1e-6);
            const double p_folded = integrate_sphere(pdf_folded, 40, 80, 1e-6);
            INFO("pdf over the sphere: whole " << p_whole << ", folded " << p_folded);
            CHECK(std::abs(p_folded - p_whole) < kIntegralTolerance);

            auto sample = [&](Vec2 u, float uc) -> std::optional<Vec3> {
                auto s = bsdf_sample_folded(m, wo, u, uc, &ng);
                if (!s) return std::nullopt;
                return s->wi;
            };
            const auto r =
                chi2_test(sample, pdf_folded, kChi2Samples, 40, 80, seed++, kSignificance);
            INFO(r.message);
            CHECK(r.passed);

            Pcg32 rng(seed++, 1);
            int wrong_side = 0, f_off = 0, pdf_off = 0, heavy = 0;
            for (int k = 0; k < kSampleChecks; ++k) {
                const Vec2 u(rng.next_float(), rng.next_float());
                auto s = bsdf_sample_folded(m, wo, u, rng.next_float(), &ng);
                if (!s) continue;
                if (!bsdf_detail::lobe_side_agrees(wo, s->wi, ng)) ++wrong_side;
                const float f = luminance(bsdf_f_folded(m, wo, s->wi, &ng));
                const float pdf = bsdf_pdf_folded(m, wo, s->wi, &ng);
                if (std::abs(luminance(s->f) - f) > kRelTol * f) ++f_off;
                if (std::abs(s->pdf - pdf) > kRelTol * pdf) ++pdf_off;
                // Radiance transport scales a transmission by 1/eta^2 (bsdf.h); the power
                // weight is at most 1.
                if (luminance(s->weight) * s->eta * s->eta > 1.f + kWeightTol) ++heavy;
            }
            CHECK(wrong_side == 0);
            CHECK(f_off == 0);
            CHECK(pdf_off == 0);
            CHECK(heavy == 0);
        }
    }
}
