// The rough dielectric (Walter et al. 2007) and visible-normal sampling (Heitz & d'Eon 2014):
// chi-square of the visible-normal sampler and of both rough dielectrics (glass and the
// transmission-only refraction) against their pdfs, from outside and inside, at several
// roughnesses and angles; sampled f and pdf against bsdf_f and bsdf_pdf; the generalised
// reciprocity of the BTDF; the smooth threshold; finite values in degenerate configurations.
#include "../support/chi2.h"
#include "candela/bsdf/bsdf.h"
#include "candela/sampling/rng.h"

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <vector>

using namespace candela;
using candela::test::chi2_test;
using candela::test::sidak_significance;

namespace {

// Chi-square tests in this file, the hidden [slow] ones included (each CHECKed once): visible
// normals 3 alphas x 4 angles; rough glass 3 alphas x 4 angles x 2 sides plus a second
// (transmission) view of every narrow lobe that refracts (4 outside + 2 inside); rough
// refraction 2 alphas x 3 angles x 2 sides. The default run does fewer, so its family-wise
// rate is below the stated one.
constexpr int kNumChi2Tests = 12 + 24 + 6 + 12;
// Family-wise false-failure rate 1% over the file (Sidak).
const double kSignificance = sidak_significance(0.01, kNumChi2Tests);
// Samples per chi-square test: 40 x 80 cells then expect ~150 counts where the lobe is, enough
// to see a 10% error in a cell of 1/1000 of the mass at this significance.
constexpr int kChi2Samples = 500000;
// Integral of the pdf over the sphere: at most 1 (failed samples carry the rest); lobes cut by
// the horizon are resolved by the harness to ~1e-4.
constexpr double kIntegralTolerance = 2e-3;
// Relative agreement of two float evaluations of the same quantity along different paths (the
// sampled h against the h recomputed from wo and wi): a few ulps through exp, erfc and the
// refraction Jacobian.
constexpr float kRelTol = 2e-4f;
// The same float expression evaluated at two call sites: identical unless the compiler contracts
// or reorders differently (a few ulps).
constexpr double kSameEvalTol = 1e-6;
// Directions closer to the horizon than this are left out of the reciprocity check.
constexpr float kGrazingCos = 0.05f;
// Reciprocity of two float evaluation orders. Near the critical angle glass's 1 - F comes from
// sqrt(1 - sin^2) of a number close to 1, and far in a narrow lobe's tail D is exp of a large
// argument; measured over 8e6 random pairs (alpha 0.05 and 0.4, both materials), the orders
// differ by at most 8.3e-4 relative where f > 0.01 and by 8.1e-4 absolute elsewhere. A wrong
// formula differs by O(1) at the lobe's peak, where f is O(1) to O(1/alpha^2).
constexpr float kReciprocityRelTol = 2e-3f;
constexpr float kNegligibleF = 1e-3f;
// Narrow lobes are magnified for the chi-square cells: alpha below this gets a zoomed view.
constexpr float kZoomBelowAlpha = 0.2f;

Vec3 dir_theta(float theta_deg, float phi_deg = 30.f) {
    float t = deg_to_rad(theta_deg), p = deg_to_rad(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

Material rough(BsdfKind kind, float alpha, float ior = 1.5f) {
    Material m;
    m.kind = kind;
    m.roughness = alpha;
    m.ior = ior;
    m.reflectance = Rgb(0.9f, 0.8f, 0.7f);
    m.transmittance = Rgb(0.6f, 0.7f, 0.95f);
    return m;
}

/// n of the side of direction w (+z outside is vacuum, the inside has m.ior).
float index_of_side(const Material& m, const Vec3& w) {
    return w.z > 0.f ? 1.f : m.ior;
}

/// The smooth refraction direction of wo (the axis of the transmission lobe), if any.
std::optional<Vec3> smooth_refraction(const Material& m, const Vec3& wo) {
    const bool entering = wo.z > 0.f;
    Vec3 wt;
    if (!refract(wo, Vec3(0.f, 0.f, entering ? 1.f : -1.f), entering ? m.ior : 1.f / m.ior, &wt))
        return std::nullopt;
    return wt;
}

/// Chi-square of the rough dielectric's sampler from wo. half = 0 tests the whole sphere;
/// half = +1 (-1) tests only the half space of wo (the other one): samples elsewhere count as
/// failures and the pdf is 0 there, so the harness's failure cell checks the mass of the rest.
/// Two narrow lobes cannot both be magnified in one view; one view per half tests each.
candela::test::Chi2Result run_chi2(const Material& m, const Vec3& wo, const Vec3* zoom_axis,
                                   double zoom, std::uint64_t seed, float half = 0.f) {
    auto in_half = [wo, half](const Vec3& wi) { return half == 0.f || wi.z * wo.z * half > 0.f; };
    auto sample = [m, wo, in_half](Vec2 u, float uc) -> std::optional<Vec3> {
        auto s = bsdf_sample(m, wo, u, uc);
        if (!s || !in_half(s->wi)) return std::nullopt;
        return s->wi;
    };
    auto pdf = [m, wo, in_half](const Vec3& wi) { return in_half(wi) ? bsdf_pdf(m, wo, wi) : 0.f; };
    if (!zoom_axis) return chi2_test(sample, pdf, kChi2Samples, 40, 80, seed, kSignificance);
    auto [zs, zp] = candela::test::zoom_view(sample, pdf, *zoom_axis, zoom);
    return chi2_test(zs, zp, kChi2Samples, 40, 80, seed, kSignificance);
}

} // namespace

TEST_CASE("chi2: Beckmann visible normals", "[bsdf][stat]") {
    std::uint64_t seed = 500;
    for (float alpha : {0.05f, 0.3f, 0.8f})
        for (float theta : {0.f, 40.f, 70.f, 89.f}) {
            const Vec3 wo = dir_theta(theta, 70.f);
            auto sample = [&](Vec2 u, float) -> std::optional<Vec3> {
                return sample_beckmann_visible(wo, alpha, u);
            };
            auto pdf = [&](const Vec3& m) { return beckmann_visible_pdf(m, wo, alpha); };
            const double zoom = std::max(1.0, 0.5 / double(alpha));
            auto [zs, zp] = candela::test::zoom_view(sample, pdf, Vec3(0.f, 0.f, 1.f), zoom);
            auto r = chi2_test(zs, zp, kChi2Samples, 40, 80, seed++, kSignificance);
            INFO("alpha " << alpha << ", theta_o " << theta << ": " << r.message);
            CHECK(r.passed);
            // Visible normals are a proper density: every sample is valid, the pdf integrates
            // to 1 (the projected areas of the visible microfacets and the macrosurface agree).
            CHECK(r.pdf_integral == Approx(1.0).margin(kIntegralTolerance));
        }
}

namespace {

// The chi-square matrices below run partly in the default suite (the corners: the narrowest
// and widest lobe at normal and oblique incidence) and completely under the hidden [slow] tag
// (`candela_tests "[slow]"`): each test draws 500k samples of a sampler that inverts a CDF
// numerically, and the full matrices take about a minute.
constexpr float kGlassAlphas[] = {0.05f, 0.25f, 0.8f};
constexpr float kGlassThetas[] = {0.f, 30.f, 60.f, 80.f};

bool glass_case_is_quick(int ai, int ti) {
    return (ai == 0 || ai == 2) && (ti == 0 || ti == 2);
}

/// Rough glass at kGlassAlphas[ai], kGlassThetas[ti], from both sides.
void rough_glass_chi2(int ai, int ti) {
    const float alpha = kGlassAlphas[ai], theta = kGlassThetas[ti];
    for (float side : {1.f, -1.f}) {
        // A seed per configuration, the same in the quick and the full run.
        std::uint64_t seed =
            600 + 20 * std::uint64_t(ai) + 4 * std::uint64_t(ti) + (side > 0.f ? 0u : 2u);
        const Material m = rough(BsdfKind::Glass, alpha);
        Vec3 wo = dir_theta(theta);
        wo.z *= side;
        const double zoom = 0.5 / double(alpha);
        const Vec3 mirror(-wo.x, -wo.y, wo.z);
        INFO("alpha " << alpha << ", theta_o " << theta << ", side " << side);
        const bool narrow = alpha < kZoomBelowAlpha;
        // Narrow lobes: the reflected half magnified about the mirror direction...
        auto r = run_chi2(m, wo, narrow ? &mirror : nullptr, zoom, seed, narrow ? 1.f : 0.f);
        INFO(r.message);
        CHECK(r.passed);
        CHECK(r.pdf_integral <= 1.0 + kIntegralTolerance);
        // ...and the transmitted half about the refraction direction, when there is one (under
        // total internal reflection the few transmitted samples are counted by the first
        // view's failure cell).
        std::optional<Vec3> t = smooth_refraction(m, wo);
        if (narrow && t) {
            auto rt = run_chi2(m, wo, &*t, zoom, seed + 1, -1.f);
            INFO("transmission view: " << rt.message);
            CHECK(rt.passed);
        }
    }
}

/// Rough refraction at alpha 0.1 (ai = 0) or 0.5 (ai = 1) and the k-th angle, both sides.
void rough_refraction_chi2(int ai, int k) {
    const float alpha = ai == 0 ? 0.1f : 0.5f;
    for (float side : {1.f, -1.f}) {
        const std::uint64_t seed =
            700 + 10 * std::uint64_t(ai) + 2 * std::uint64_t(k) + (side > 0.f ? 0u : 1u);
        const Material m = rough(BsdfKind::Refraction, alpha);
        // From inside, angles below the critical angle (41.8 degrees): beyond it a narrow
        // lobe refracts (almost) nothing and the test would have nothing to see.
        const float theta = side > 0.f ? std::array<float, 3>{0.f, 45.f, 80.f}[std::size_t(k)]
                                       : std::array<float, 3>{0.f, 25.f, 40.f}[std::size_t(k)];
        Vec3 wo = dir_theta(theta);
        wo.z *= side;
        std::optional<Vec3> t = smooth_refraction(m, wo);
        const Vec3 axis = t ? *t : Vec3(0.f, 0.f, -side);
        INFO("alpha " << alpha << ", theta_o " << theta << ", side " << side);
        auto r =
            run_chi2(m, wo, alpha < kZoomBelowAlpha ? &axis : nullptr, 0.5 / double(alpha), seed);
        INFO(r.message);
        CHECK(r.passed);
        CHECK(r.pdf_integral <= 1.0 + kIntegralTolerance);
    }
}

} // namespace

TEST_CASE("chi2: rough glass from outside and inside", "[bsdf][stat]") {
    for (int ai = 0; ai < 3; ++ai)
        for (int ti = 0; ti < 4; ++ti)
            if (glass_case_is_quick(ai, ti)) rough_glass_chi2(ai, ti);
}

TEST_CASE("chi2: rough glass, every roughness and angle", "[.][slow][bsdf][stat]") {
    for (int ai = 0; ai < 3; ++ai)
        for (int ti = 0; ti < 4; ++ti)
            if (!glass_case_is_quick(ai, ti)) rough_glass_chi2(ai, ti);
}

TEST_CASE("chi2: rough transmission-only dielectric", "[bsdf][stat]") {
    for (int ai = 0; ai < 2; ++ai)
        for (int k = 0; k < 2; ++k)
            rough_refraction_chi2(ai, k);
}

TEST_CASE("chi2: rough transmission-only dielectric at grazing angles", "[.][slow][bsdf][stat]") {
    for (int ai = 0; ai < 2; ++ai)
        rough_refraction_chi2(ai, 2);
}

TEST_CASE("chi2 has power against a wrong rough-glass transmission Jacobian", "[bsdf][stat]") {
    // Samples of ior 1.5 tested against the pdf of ior 1.6: the transmission lobe moves and
    // widens by a few percent, which the test must see.
    const Material sampled = rough(BsdfKind::Glass, 0.3f, 1.5f);
    const Material claimed = rough(BsdfKind::Glass, 0.3f, 1.6f);
    const Vec3 wo = dir_theta(40.f);
    auto sample = [&](Vec2 u, float uc) -> std::optional<Vec3> {
        auto s = bsdf_sample(sampled, wo, u, uc);
        if (!s) return std::nullopt;
        return s->wi;
    };
    auto pdf = [&](const Vec3& wi) { return bsdf_pdf(claimed, wo, wi); };
    auto r = chi2_test(sample, pdf, kChi2Samples, 40, 80, 800, kSignificance);
    INFO(r.message);
    CHECK_FALSE(r.passed);
}

TEST_CASE("rough dielectric: sampled f and pdf are bsdf_f and bsdf_pdf", "[bsdf][quick]") {
    Pcg32 rng(21, 3);
    for (BsdfKind kind : {BsdfKind::Glass, BsdfKind::Refraction})
        for (float alpha : {0.002f, 0.05f, 0.3f, 1.2f})
            for (float ior : {1.5f, 1.f / 1.33f, 2.4f}) {
                const Material m = rough(kind, alpha, ior);
                REQUIRE(m.is_rough_dielectric());
                int reflected = 0, transmitted = 0;
                for (int i = 0; i < 5000; ++i) {
                    const Vec3 wo =
                        square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
                    auto s = bsdf_sample(m, wo, Vec2(rng.next_float(), rng.next_float()),
                                         rng.next_float());
                    if (!s) continue;
                    INFO("kind " << bsdf_kind_name(kind) << " alpha " << alpha << " ior " << ior);
                    REQUIRE(std::abs(length(s->wi) - 1.f) < 1e-5f);
                    REQUIRE((s->flags & kGlossy));
                    REQUIRE_FALSE((s->flags & kSpecular));
                    // The sample's f and pdf come from the same evaluation as bsdf_f and
                    // bsdf_pdf on the same (wo, wi): equal up to the compiler's rounding.
                    REQUIRE(s->pdf == Approx(bsdf_pdf(m, wo, s->wi)).epsilon(kSameEvalTol));
                    const Rgb f = bsdf_f(m, wo, s->wi);
                    for (int c = 0; c < 3; ++c)
                        REQUIRE(s->f[c] == Approx(f[c]).epsilon(kSameEvalTol));
                    if (s->flags & kReflection) {
                        ++reflected;
                        REQUIRE(kind == BsdfKind::Glass);
                        REQUIRE(s->wi.z * wo.z > 0.f);
                        REQUIRE(s->eta == 1.f);
                    } else {
                        ++transmitted;
                        REQUIRE((s->flags & kTransmission));
                        REQUIRE(s->wi.z * wo.z < 0.f);
                        REQUIRE(
                            s->eta ==
                            Approx(index_of_side(m, s->wi) / index_of_side(m, wo)).epsilon(1e-6));
                    }
                }
                CHECK(transmitted > 0);
                if (kind == BsdfKind::Glass) CHECK(reflected > 0);
            }
}

TEST_CASE("rough dielectric: f(wo, wi) / n(wo)^2 is symmetric", "[bsdf][quick]") {
    // The radiance BTDF is not symmetric; f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2 is (Veach's
    // thesis, eq. 5.21, in candela's 1/eta^2 convention). Reflection is symmetric as it is.
    Pcg32 rng(22, 5);
    for (BsdfKind kind : {BsdfKind::Glass, BsdfKind::Refraction})
        for (float alpha : {0.05f, 0.4f}) {
            Material m = rough(kind, alpha, 1.45f);
            m.reflectance = m.transmittance = Rgb(1.f);
            int nonzero = 0;
            for (int i = 0; i < 20000; ++i) {
                const Vec3 a = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
                const Vec3 b = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
                // Near grazing, 1/|cos| and Lambda amplify the float rounding of the two
                // evaluation orders beyond kRelTol; the formula is tested away from it.
                if (std::abs(a.z) < kGrazingCos || std::abs(b.z) < kGrazingCos) continue;
                const float na = index_of_side(m, a), nb = index_of_side(m, b);
                const float fab = bsdf_f(m, a, b).y / (na * na);
                const float fba = bsdf_f(m, b, a).y / (nb * nb);
                INFO("a = (" << a.x << ", " << a.y << ", " << a.z << "), b = (" << b.x << ", "
                             << b.y << ", " << b.z << "), fab " << fab << ", fba " << fba
                             << ", kind " << bsdf_kind_name(kind) << ", alpha " << alpha);
                REQUIRE(fab == Approx(fba).epsilon(kReciprocityRelTol).margin(kNegligibleF));
                nonzero += fab > 0.f;
            }
            // Not vacuous: even the narrow transmission-only lobe is met by a few hundred pairs.
            CHECK(nonzero > 100);
        }
}

TEST_CASE("rough dielectric: thresholds, delta status and transmission", "[bsdf][quick]") {
    Material smooth = rough(BsdfKind::Glass, 0.f);
    CHECK(smooth.is_delta());
    CHECK_FALSE(smooth.is_rough_dielectric());
    CHECK(smooth.has_transmission());
    Material below = rough(BsdfKind::Glass, 0.5f * kMinDielectricRoughness);
    CHECK(below.is_delta());
    Material at = rough(BsdfKind::Refraction, kMinDielectricRoughness);
    CHECK_FALSE(at.is_delta());
    CHECK(at.has_transmission());
    // Index-matched: the interface is invisible whatever its roughness (a delta).
    Material matched = rough(BsdfKind::Glass, 0.3f, 1.f + 0.5f * kMinRoughIndexGap);
    CHECK(matched.is_delta());
    Material diffuse;
    CHECK_FALSE(diffuse.has_transmission());
    Material conductor;
    conductor.kind = BsdfKind::Microfacet;
    CHECK_FALSE(conductor.is_delta());
    CHECK_FALSE(conductor.has_transmission());
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    CHECK(mirror.is_delta());
    // A smooth dielectric keeps its delta behaviour; a rough one has a density.
    const Vec3 wo = dir_theta(30.f);
    const Vec3 wt = *smooth_refraction(smooth, wo);
    CHECK(bsdf_pdf(smooth, wo, wt) == 0.f);
    CHECK(bsdf_pdf(rough(BsdfKind::Glass, 0.2f), wo, wt) > 0.f);
    CHECK(bsdf_f(rough(BsdfKind::Glass, 0.2f), wo, wt).y > 0.f);
}

TEST_CASE("rough dielectric: no NaN or Inf in degenerate configurations", "[bsdf][quick]") {
    std::vector<Material> mats;
    for (BsdfKind kind : {BsdfKind::Glass, BsdfKind::Refraction})
        for (float alpha : {kMinDielectricRoughness, 0.01f, 0.5f, 4.f})
            for (float ior : {1.0011f, 1.5f, 0.5f, 10.f})
                mats.push_back(rough(kind, alpha, ior));
    const std::vector<Vec3> dirs = {Vec3(0, 0, 1),
                                    Vec3(0, 0, -1),
                                    Vec3(1, 0, 0),
                                    Vec3(1, 0, 1e-8f),
                                    Vec3(1, 0, -1e-8f),
                                    normalize(Vec3(1, 1, 1e-4f)),
                                    normalize(Vec3(1, 1, -1e-4f)),
                                    normalize(Vec3(1, 0, 1)),
                                    normalize(Vec3(-1, 0, -1)),
                                    normalize(Vec3(0.2f, 0, -1))};
    const Vec2 us[] = {Vec2(0, 0), Vec2(0.99999994f, 0.99999994f), Vec2(0.5f, 0.5f),
                       Vec2(0.99999994f, 0.f), Vec2(0.f, 0.99999994f)};
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
                }
        }
}
