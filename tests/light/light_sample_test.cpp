// Tests of light sampling: chi-square agreement of sample_li with pdf_li for every non-delta
// light, pdf consistency, exact values of delta lights, one-sidedness, and Monte Carlo irradiance
// against closed forms.
#include "candela/accel/sphere.h"
#include "candela/light/light_sample.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/scene/envmap.h"
#include "candela/scene/interaction.h"
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"

#include "../support/chi2.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

using namespace candela;

namespace {

/// Number of chi-square tests in this file, for the Sidak-corrected per-test significance.
constexpr int kChi2Tests = 10;
/// Family-wise false-failure rate of all chi-square tests in this file.
constexpr double kChi2Alpha = 0.01;
/// Samples per chi-square test: enough that a 1% pdf error in a cell of 1/400 of the mass is
/// visible, while each test stays well under a second.
constexpr int kChi2Samples = 200000;
/// Relative agreement of two float computations of the same pdf by different formulas
/// (sample_li's and pdf_li's); float rounding in dist^2 / (A cos) is ~1e-6 relative, 1e-4 leaves
/// room for the cosine near grazing angles without hiding a wrong formula (which is off by O(1)).
constexpr float kPdfRelTol = 1e-4f;
/// z-score bound for Monte Carlo estimates with fixed seeds: a correct estimator exceeds it with
/// probability ~6e-5.
constexpr double kZBound = 4.0;
/// Largest relative standard error accepted from an irradiance estimator: guards against a
/// degenerate estimate (e.g. mostly zero samples) whose huge error bar would pass any z-test.
constexpr double kMaxRelStdErr = 0.01;

double chi2_significance() {
    return test::sidak_significance(kChi2Alpha, kChi2Tests);
}

/// Ray-parallelogram intersection (double precision): the hit point, or nullopt.
std::optional<Vec3> hit_rect(const Light& l, const Vec3& o, const Vec3& d) {
    Vec3d n(l.n), od(o), dd(d), p(l.p), dx(l.dx), dy(l.dy);
    double denom = dot(dd, n);
    if (denom == 0.0) return std::nullopt;
    double t = dot(p - od, n) / denom;
    if (!(t > 0.0)) return std::nullopt;
    Vec3d q = od + dd * t;
    double s = dot(q - p, dx) / dot(dx, dx), r = dot(q - p, dy) / dot(dy, dy);
    if (std::abs(s) > 0.5 || std::abs(r) > 0.5) return std::nullopt;
    return Vec3(q);
}

/// All intersections of a ray with a triangle (double precision Moller-Trumbore).
std::optional<double> hit_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b,
                                   const Vec3& c) {
    Vec3d od(o), dd(d), p0(a), e1 = Vec3d(b) - p0, e2 = Vec3d(c) - p0;
    Vec3d pv = cross(dd, e2);
    double det = dot(e1, pv);
    if (det == 0.0) return std::nullopt;
    Vec3d tv = od - p0;
    double u = dot(tv, pv) / det;
    if (u < 0.0 || u > 1.0) return std::nullopt;
    Vec3d qv = cross(tv, e1);
    double v = dot(dd, qv) / det;
    if (v < 0.0 || u + v > 1.0) return std::nullopt;
    double t = dot(e2, qv) / det;
    if (!(t > 0.0)) return std::nullopt;
    return t;
}

/// Nearest positive intersection distance of a ray with a sphere (double precision).
std::optional<double> hit_sphere(const Vec3& o, const Vec3& d, const Vec3& c, float r) {
    // Renormalise in double: for a small distant sphere b^2 - c cancels down to ~r^2, and the
    // float direction's length error (~1e-7) would otherwise be amplified by 1/r^2.
    Vec3d oc = Vec3d(o) - Vec3d(c), dd = normalize(Vec3d(d));
    double b = dot(oc, dd), cc = dot(oc, oc) - double(r) * r;
    double disc = b * b - cc;
    if (disc < 0.0) return std::nullopt;
    double sq = std::sqrt(disc);
    double t0 = -b - sq, t1 = -b + sq;
    if (t0 > 0.0) return t0;
    if (t1 > 0.0) return t1;
    return std::nullopt;
}

/// Scene holding a single light and no geometry. Assembled by hand, not through SceneEditor:
/// the sampling functions under test read only the light, which may be a Sphere record with no
/// sphere behind it.
Scene scene_with(const Light& l) {
    Scene s;
    s.source = "test";
    s.materials.push_back(Material{});
    s.lights.push_back(l);
    return s;
}

/// A bent two-triangle strip plus a separate tilted triangle, as an emissive mesh light.
Scene mesh_light_scene(const Rgb& L) {
    Scene s;
    s.source = "test-mesh";
    SceneEditor editor(s);
    Material em;
    em.kind = BsdfKind::Emission;
    em.radiance = L;
    Mesh m;
    m.material = editor.add_material(em);
    m.name = "emitter";
    m.positions = {Vec3(-0.5f, 1.f, -0.5f), Vec3(0.5f, 1.f, -0.5f), Vec3(0.f, 1.4f, 0.3f),
                   Vec3(1.0f, 0.6f, 0.5f),  Vec3(0.8f, 0.3f, 1.f),  Vec3(-0.7f, 0.5f, 0.8f)};
    m.indices = {0, 1, 2, 1, 3, 2, 4, 5, 3};
    editor.add_mesh(std::move(m)); // light 0, with the area CDF
    editor.finalize();
    return s;
}

Light make_sphere(const Vec3& c, float r, const Rgb& L) {
    Light l;
    l.kind = LightKind::Sphere;
    l.p = c;
    l.radius = r;
    l.area = 4.f * kPi * r * r;
    l.L = L;
    l.geom_id = 0;
    return l;
}

/// Sampler and pdf wrappers for directions from ref_p, for the chi-square harness.
test::DirectionSampler direction_sampler(const Scene& scene, const Vec3& ref_p) {
    return [&scene, ref_p](Vec2 u, float) -> std::optional<Vec3> {
        auto s = sample_li(scene, scene.lights[0], ref_p, u);
        if (!s) return std::nullopt;
        return s->wi;
    };
}

void check_chi2(const test::DirectionSampler& sample, const test::DirectionPdf& pdf,
                std::uint64_t seed, double expected_integral) {
    // Integral of the pdf over the sphere: the quadrature's tolerance is 1e-7 in total, but the
    // pdf's float evaluation and its discontinuities at light edges leave ~1e-4.
    constexpr double kIntegralTol = 2e-3;
    test::Chi2Result r =
        test::chi2_test(sample, pdf, kChi2Samples, 20, 40, seed, chi2_significance());
    INFO(r.message);
    CHECK(r.passed);
    CHECK(r.pdf_integral == Approx(expected_integral).margin(kIntegralTol));
}

} // namespace

TEST_CASE("rect light: chi-square of sample_li against pdf_li", "[light][stat]") {
    Scene scene = scene_with(rect_light(Vec3(0.f, 1.f, 0.f), Vec3(0.f, -1.f, 0.f),
                                        Vec3(0.6f, 0.f, 0.f), Vec3(0.f, 0.f, 0.8f), Rgb(10.f)));
    const Light& light = scene.lights[0];
    const Vec3 ref(0.2f, 0.f, 0.1f);
    auto pdf = [&](const Vec3& w) -> float {
        auto q = hit_rect(light, ref, w);
        if (!q) return 0.f;
        return pdf_li(scene, light, ref, w, *q, light.n, 0u);
    };
    auto [zs, zp] = test::zoom_view(direction_sampler(scene, ref), pdf, light.p - ref, 3.0);
    check_chi2(zs, zp, 11, 1.0);
}

TEST_CASE("rect light: one-sided, pdf_li matches sample_li", "[light][quick]") {
    Scene scene = scene_with(rect_light(Vec3(0.f, 1.f, 0.f), Vec3(0.f, -1.f, 0.f),
                                        Vec3(0.6f, 0.f, 0.f), Vec3(0.f, 0.f, 0.8f), Rgb(10.f)));
    const Light& light = scene.lights[0];
    Pcg32 rng(7, 1);
    const Vec3 below(0.3f, -0.5f, 0.2f), above(0.1f, 1.5f, -0.2f);
    for (int i = 0; i < 1000; ++i) {
        Vec2 u(rng.next_float(), rng.next_float());
        auto s = sample_li(scene, light, below, u);
        REQUIRE(s);
        CHECK(!s->is_delta);
        CHECK(s->L == Rgb(10.f));
        CHECK(s->dist == Approx(length(s->p_light - below)).epsilon(kPdfRelTol));
        CHECK(dot(s->n_light, s->wi) < 0.f); // normal faces the reference point
        float p = pdf_li(scene, light, below, s->wi, s->p_light, s->n_light, s->prim);
        CHECK(p == Approx(s->pdf).epsilon(kPdfRelTol));
        // Emission toward the reference point, none backwards.
        CHECK(light_le(light, s->n_light, -s->wi) == Rgb(10.f));
        CHECK(is_black(light_le(light, s->n_light, s->wi)));
        // From behind: nothing is sampled and the pdf is zero.
        CHECK_FALSE(sample_li(scene, light, above, u));
        Vec3 wi_back = normalize(s->p_light - above);
        CHECK(pdf_li(scene, light, above, wi_back, s->p_light, light.n, s->prim) == 0.f);
    }
    // The solid-angle pdf at the centre, seen head-on from distance 1.5: dist^2 / area.
    auto s = sample_li(scene, light, Vec3(0.f, -0.5f, 0.f), Vec2(0.5f, 0.5f));
    REQUIRE(s);
    CHECK(s->pdf == Approx(1.5f * 1.5f / 0.48f).epsilon(kPdfRelTol));
}

TEST_CASE("mesh light: chi-square of sample_li against pdf_li", "[light][stat]") {
    Scene scene = mesh_light_scene(Rgb(3.f));
    const Light& light = scene.lights[0];
    const Mesh& mesh = scene.meshes[0];
    const Vec3 ref(0.1f, -0.2f, 0.2f);
    // Area sampling ignores occlusion, so the density of a direction sums over every triangle
    // the ray crosses.
    auto pdf = [&](const Vec3& w) -> float {
        float sum = 0.f;
        for (std::size_t k = 0; k < mesh.triangle_count(); ++k) {
            const Vec3& a = mesh.positions[mesh.indices[3 * k]];
            const Vec3& b = mesh.positions[mesh.indices[3 * k + 1]];
            const Vec3& c = mesh.positions[mesh.indices[3 * k + 2]];
            auto t = hit_triangle(ref, w, a, b, c);
            if (!t) continue;
            Vec3 q = ref + w * static_cast<float>(*t);
            sum +=
                pdf_li(scene, light, ref, w, q, normalize(cross(b - a, c - a)), std::uint32_t(k));
        }
        return sum;
    };
    check_chi2(direction_sampler(scene, ref), pdf, 12, 1.0);
}

TEST_CASE("mesh light: two-sided, pdf_li matches sample_li", "[light][quick]") {
    Scene scene = mesh_light_scene(Rgb(3.f));
    const Light& light = scene.lights[0];
    Pcg32 rng(8, 1);
    // Reference points on both sides of the triangles.
    for (const Vec3& ref : {Vec3(0.1f, -0.2f, 0.2f), Vec3(0.f, 3.f, 0.f)}) {
        int n_ok = 0;
        for (int i = 0; i < 1000; ++i) {
            auto s = sample_li(scene, light, ref, Vec2(rng.next_float(), rng.next_float()));
            if (!s) continue;
            ++n_ok;
            CHECK(s->L == Rgb(3.f));
            CHECK(dot(s->n_light, s->wi) <= 0.f);
            CHECK(light_le(light, s->n_light, -s->wi) == Rgb(3.f));
            CHECK(light_le(light, -s->n_light, -s->wi) == Rgb(3.f));
            float p = pdf_li(scene, light, ref, s->wi, s->p_light, s->n_light, s->prim);
            CHECK(p == Approx(s->pdf).epsilon(kPdfRelTol));
        }
        CHECK(n_ok == 1000);
    }
}

TEST_CASE("sphere light: chi-square from outside (cone) and inside (area)", "[light][stat]") {
    SECTION("outside, wide cone") {
        Scene scene = scene_with(make_sphere(Vec3(0.3f, 2.f, -0.4f), 1.f, Rgb(2.f)));
        const Light& light = scene.lights[0];
        const Vec3 ref(0.f, 0.f, 0.f);
        auto pdf = [&](const Vec3& w) -> float {
            auto t = hit_sphere(ref, w, light.p, light.radius);
            if (!t) return 0.f;
            Vec3 q = ref + w * static_cast<float>(*t);
            return pdf_li(scene, light, ref, w, q, normalize(q - light.p), 0u);
        };
        auto [zs, zp] = test::zoom_view(direction_sampler(scene, ref), pdf, light.p - ref, 2.0);
        check_chi2(zs, zp, 13, 1.0);
    }
    SECTION("outside, tiny cone (small-angle branch)") {
        Scene scene = scene_with(make_sphere(Vec3(0.f, 0.f, 1.f), 0.01f, Rgb(2.f)));
        const Light& light = scene.lights[0];
        const Vec3 ref(0.f, 0.f, 0.f);
        auto pdf = [&](const Vec3& w) -> float {
            auto t = hit_sphere(ref, w, light.p, light.radius);
            if (!t) return 0.f;
            Vec3 q = ref + w * static_cast<float>(*t);
            return pdf_li(scene, light, ref, w, q, normalize(q - light.p), 0u);
        };
        // Stereographic radius of the cone edge is ~0.005; zoom 90 maps it to ~0.45, inside a
        // bin. (Zoom 100 would put the edge exactly on the bin boundary cos(theta) = 0.6, where
        // tangent samples rounded one ulp outside the cone land in a bin of zero mass.)
        auto [zs, zp] = test::zoom_view(direction_sampler(scene, ref), pdf, light.p - ref, 90.0);
        check_chi2(zs, zp, 14, 1.0);
    }
    SECTION("inside") {
        Scene scene = scene_with(make_sphere(Vec3(0.f, 0.f, 0.f), 1.f, Rgb(2.f)));
        const Light& light = scene.lights[0];
        const Vec3 ref(0.2f, 0.5f, -0.3f);
        auto pdf = [&](const Vec3& w) -> float {
            auto t = hit_sphere(ref, w, light.p, light.radius);
            if (!t) return 0.f;
            Vec3 q = ref + w * static_cast<float>(*t);
            return pdf_li(scene, light, ref, w, q, normalize(q - light.p), 0u);
        };
        check_chi2(direction_sampler(scene, ref), pdf, 15, 1.0);
    }
}

TEST_CASE("sphere light: sampled points are visible points of the sphere", "[light][quick]") {
    // Relative distance of a sampled point from the sphere surface allowed by float rounding.
    constexpr float kOnSphereTol = 1e-5f;
    Pcg32 rng(9, 1);
    for (float d : {1.001f, 1.5f, 10.f, 1000.f}) {
        Scene scene = scene_with(make_sphere(Vec3(0.f, d, 0.f), 1.f, Rgb(1.f)));
        const Light& light = scene.lights[0];
        for (int i = 0; i < 500; ++i) {
            auto s = sample_li(scene, light, Vec3(0.f), Vec2(rng.next_float(), rng.next_float()));
            REQUIRE(s);
            CHECK(std::abs(length(s->p_light - light.p) - 1.f) <= kOnSphereTol * d);
            CHECK(dot(s->n_light, s->wi) <= kOnSphereTol); // faces the reference point
            float p = pdf_li(scene, light, Vec3(0.f), s->wi, s->p_light, s->n_light, s->prim);
            CHECK(p == Approx(s->pdf).epsilon(kPdfRelTol));
        }
    }
}

TEST_CASE("ambient light: chi-square, L and escaped radiance", "[light][stat]") {
    Light l;
    l.kind = LightKind::Ambient;
    l.L = Rgb(0.5f, 1.f, 2.f);
    Scene scene = scene_with(l);
    const Vec3 ref(1.f, 2.f, 3.f);
    auto pdf = [&](const Vec3& w) { return pdf_li(scene, scene.lights[0], ref, w, ref, -w, 0u); };
    check_chi2(direction_sampler(scene, ref), pdf, 16, 1.0);

    Pcg32 rng(10, 1);
    for (int i = 0; i < 1000; ++i) {
        auto s = sample_li(scene, scene.lights[0], ref, Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(s);
        CHECK(s->wi.y > 0.f);
        CHECK(s->L == l.L);
        CHECK(std::isinf(s->dist));
        CHECK(s->pdf == Approx(kInv2Pi));
        CHECK(escaped_radiance(scene, s->wi) == l.L);
        CHECK(escaped_pdf(scene, scene.lights[0], s->wi) == s->pdf);
    }
    CHECK(escaped_radiance(scene, normalize(Vec3(0.3f, -0.1f, 0.2f))) == Rgb(0.f));
    CHECK(escaped_radiance(scene, Vec3(1.f, 0.f, 0.f)) == Rgb(0.f)); // horizon excluded
    CHECK(escaped_pdf(scene, scene.lights[0], Vec3(0.f, -1.f, 0.f)) == 0.f);
}

namespace {

/// A scene whose only light is a small synthetic environment map (8 x 4 keeps the harness's
/// quadrature, which refines along every texel edge, affordable).
Scene env_scene() {
    const int w = 8, h = 4;
    std::vector<Rgb> tex(w * h, Rgb(0.1f, 0.2f, 0.3f));
    tex[1 * w + 2] = Rgb(50.f, 40.f, 30.f); // bright spot
    // Black block: texels (5..6, 3) have an all-black neighbourhood, hence zero density.
    for (int j = 2; j < 4; ++j)
        for (int i = 4; i < 8; ++i)
            tex[j * w + i] = Rgb(0.f);
    tex[3 * w + 0] = Rgb(5.f, 0.f, 0.f); // bottom row: lights up its wrapped neighbour (7, 3)
    Light l;
    l.kind = LightKind::Environment;
    l.L = Rgb(1.f);
    Scene scene = scene_with(l);
    scene.env = std::make_shared<const EnvMap>(w, h, tex, "synthetic");
    return scene;
}

} // namespace

TEST_CASE("environment light: chi-square of the importance sampler", "[light][stat][slow]") {
    Scene scene = env_scene();
    const Vec3 ref(0.f);
    auto pdf = [&](const Vec3& d) { return pdf_li(scene, scene.lights[0], ref, d, ref, -d, 0u); };
    // sample_li skips directions whose bilinear radiance is exactly 0 (part of a texel next to
    // black ones), so the direction density is tested on the map's own sampler; the next test
    // checks sample_li against it sample by sample.
    const EnvMap& env = *scene.env;
    test::DirectionSampler env_sampler = [&env](Vec2 u, float) -> std::optional<Vec3> {
        auto s = env.sample(u);
        if (!s) return std::nullopt;
        return s->wi;
    };
    // The density has the integrable 1/sin(theta) singularity of the lat-long parameterisation
    // at the poles (+-Y). A generic rotation (zoom 1) keeps the poles off the harness's
    // quadrature nodes, where a float direction 1e-17 from the pole would return ~1e16.
    auto [zs, zp] = test::zoom_view(env_sampler, pdf, normalize(Vec3(0.3f, 0.5f, 0.8f)), 1.0);
    check_chi2(zs, zp, 17, 1.0);
}

TEST_CASE("environment light: sample_li agrees with the map and escaped radiance",
          "[light][quick]") {
    Scene scene = env_scene();
    const EnvMap& env = *scene.env;
    const Vec3 ref(0.f);
    Pcg32 rng(11, 1);
    int n_skipped = 0;
    for (int i = 0; i < 2000; ++i) {
        Vec2 u(rng.next_float(), rng.next_float());
        auto es = env.sample(u);
        REQUIRE(es);
        auto s = sample_li(scene, scene.lights[0], ref, u);
        if (!s) {
            CHECK(is_black(es->L));
            ++n_skipped;
            continue;
        }
        CHECK(s->wi == es->wi);
        CHECK(s->pdf == es->pdf);
        CHECK(s->L == escaped_radiance(scene, s->wi));
        CHECK(s->pdf == escaped_pdf(scene, scene.lights[0], s->wi));
        CHECK(std::isinf(s->dist));
        CHECK_FALSE(s->is_delta);
    }
    // Black-radiance samples fall only in the corners of texels bordering the black block,
    // which carry ~0.2% of the density; 40 of 2000 would mean the table is wrong.
    INFO(n_skipped << " of 2000 samples had zero radiance");
    CHECK(n_skipped < 40);
}

TEST_CASE("point and spot lights: inverse square and cone", "[light][quick]") {
    Light pt;
    pt.kind = LightKind::Point;
    pt.p = Vec3(1.f, 1.f, 1.f);
    pt.L = Rgb(1.f, 2.f, 3.f);
    Scene scene = scene_with(pt);
    auto s = sample_li(scene, scene.lights[0], Vec3(1.f, 1.f, 4.f), Vec2(0.3f, 0.7f));
    REQUIRE(s);
    CHECK(s->is_delta);
    CHECK(s->pdf == 1.f);
    CHECK(s->dist == 3.f);
    CHECK(s->wi == Vec3(0.f, 0.f, -1.f));
    CHECK(s->L.x == Approx(1.f / 9.f));
    CHECK(s->L.y == Approx(2.f / 9.f));
    CHECK(s->L.z == Approx(3.f / 9.f));
    CHECK(pdf_li(scene, scene.lights[0], Vec3(0.f), s->wi, pt.p, s->n_light, s->prim) == 0.f);

    Light spot;
    spot.kind = LightKind::Spot;
    spot.p = Vec3(0.f, 2.f, 0.f);
    spot.n = Vec3(0.f, -1.f, 0.f);
    spot.L = Rgb(5.f);
    spot.cos_total = std::cos(deg_to_rad(30.f));
    spot.falloff_exp = 2.f;
    Scene ss = scene_with(spot);
    // On the axis: I / d^2.
    auto a = sample_li(ss, ss.lights[0], Vec3(0.f), Vec2(0.f, 0.f));
    REQUIRE(a);
    CHECK(a->L.x == Approx(5.f / 4.f));
    CHECK(a->is_delta);
    // Off axis inside the cone: I cos^2 / d^2 with cos^2 = 4 / 4.25, d^2 = 4.25.
    auto b = sample_li(ss, ss.lights[0], Vec3(0.5f, 0.f, 0.f), Vec2(0.f, 0.f));
    REQUIRE(b);
    CHECK(b->L.x == Approx(5.0 * (4.0 / 4.25) / 4.25));
    CHECK(b->dist == Approx(std::sqrt(4.25)));
    // Outside the 30 degree cone (45 degrees off axis): no contribution.
    CHECK_FALSE(sample_li(ss, ss.lights[0], Vec3(2.f, 0.f, 0.f), Vec2(0.f, 0.f)));
    // Behind the light.
    CHECK_FALSE(sample_li(ss, ss.lights[0], Vec3(0.f, 3.f, 0.f), Vec2(0.f, 0.f)));
}

TEST_CASE("directional light", "[light][quick]") {
    Light d;
    d.kind = LightKind::Directional;
    d.n = normalize(Vec3(1.f, 1.f, 0.f));
    d.L = Rgb(3.f);
    Scene scene = scene_with(d);
    auto s = sample_li(scene, scene.lights[0], Vec3(5.f, -2.f, 1.f), Vec2(0.9f, 0.1f));
    REQUIRE(s);
    CHECK(s->wi == d.n);
    CHECK(s->L == Rgb(3.f));
    CHECK(std::isinf(s->dist));
    CHECK(s->pdf == 1.f);
    CHECK(s->is_delta);
    CHECK(pdf_li(scene, scene.lights[0], Vec3(0.f), d.n, Vec3(0.f), -d.n, 0u) == 0.f);
    CHECK(escaped_radiance(scene, d.n) == Rgb(0.f)); // a delta light is never hit
}

namespace {

/// Monte Carlo irradiance at (ref, n) from one light by light sampling: mean and standard error.
std::pair<double, double> mc_irradiance(const Scene& scene, const Vec3& ref, const Vec3& n,
                                        int n_samples, std::uint64_t seed) {
    Pcg32 rng(seed, 3);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n_samples; ++i) {
        auto s = sample_li(scene, scene.lights[0], ref, Vec2(rng.next_float(), rng.next_float()));
        double x = 0.0;
        if (s) x = double(s->L.x) * std::max(0.0, double(dot(n, s->wi))) / s->pdf;
        sum += x;
        sum2 += x * x;
    }
    double mean = sum / n_samples;
    double var = std::max(0.0, sum2 / n_samples - mean * mean);
    return {mean, std::sqrt(var / n_samples)};
}

/// Lambert's formula for a uniform polygonal luminaire fully above the horizon of (ref, n):
/// E = L/2 * |sum_i angle_i * dot(n, unit normal of the triangle (ref, v_i, v_i+1))|.
double lambert_polygon_irradiance(const std::vector<Vec3>& verts, const Vec3& ref, const Vec3& n,
                                  double L) {
    double sum = 0.0;
    for (std::size_t i = 0; i < verts.size(); ++i) {
        Vec3d a = Vec3d(verts[i]) - Vec3d(ref),
              b = Vec3d(verts[(i + 1) % verts.size()]) - Vec3d(ref);
        a = normalize(a);
        b = normalize(b);
        Vec3d g = normalize(cross(a, b));
        double angle = std::acos(std::clamp(dot(a, b), -1.0, 1.0));
        sum += angle * dot(g, Vec3d(n));
    }
    return 0.5 * L * std::abs(sum);
}

} // namespace

TEST_CASE("rect light: Monte Carlo irradiance matches Lambert's polygon formula", "[light][stat]") {
    constexpr int kSamples = 200000;
    Light rect = rect_light(Vec3(0.f, 1.f, 0.f), Vec3(0.f, -1.f, 0.f), Vec3(0.6f, 0.f, 0.f),
                            Vec3(0.f, 0.f, 0.8f), Rgb(10.f));
    Scene scene = scene_with(rect);
    std::vector<Vec3> verts = {
        rect.p - rect.dx * 0.5f - rect.dy * 0.5f, rect.p + rect.dx * 0.5f - rect.dy * 0.5f,
        rect.p + rect.dx * 0.5f + rect.dy * 0.5f, rect.p - rect.dx * 0.5f + rect.dy * 0.5f};
    struct Case {
        Vec3 ref, n;
    };
    for (const Case& c : {Case{Vec3(0.1f, 0.f, -0.05f), Vec3(0.f, 1.f, 0.f)},
                          Case{Vec3(0.7f, 0.2f, 0.4f), normalize(Vec3(-0.3f, 1.f, 0.2f))}}) {
        for (const Vec3& v : verts)
            REQUIRE(dot(c.n, v - c.ref) > 0.f); // above the horizon
        double E = lambert_polygon_irradiance(verts, c.ref, c.n, 10.0);
        auto [mean, se] = mc_irradiance(scene, c.ref, c.n, kSamples, 21);
        INFO("closed form E = " << E << ", Monte Carlo = " << mean << " +- " << se);
        CHECK(std::abs(mean - E) <= kZBound * se);
        CHECK(se < kMaxRelStdErr * E);
    }
}

TEST_CASE("sphere light: Monte Carlo irradiance matches pi L (r/d)^2 cos", "[light][stat]") {
    constexpr int kSamples = 200000;
    const float r = 0.5f, d = 3.f;
    Scene scene = scene_with(make_sphere(Vec3(0.f, d, 0.f), r, Rgb(4.f)));
    // A uniformly bright sphere entirely above the horizon irradiates like a point source at
    // its centre: E = pi L sin^2(theta_max) cos(alpha).
    for (float alpha_deg : {0.f, 30.f}) {
        float alpha = deg_to_rad(alpha_deg);
        Vec3 n(std::sin(alpha), std::cos(alpha), 0.f);
        double E = kPi * 4.0 * (double(r) / d) * (double(r) / d) * std::cos(double(alpha));
        auto [mean, se] = mc_irradiance(scene, Vec3(0.f), n, kSamples, 22);
        INFO("alpha = " << alpha_deg << ": closed form E = " << E << ", Monte Carlo = " << mean
                        << " +- " << se);
        // Facing the sphere every sample is nearly equal (se ~ 1e-5 E), so allow for the float
        // rounding of each L cos / pdf (~1e-7 relative) on top of the statistical bound.
        constexpr double kFloatRelFloor = 1e-6;
        CHECK(std::abs(mean - E) <= kZBound * se + kFloatRelFloor * E);
        if (alpha_deg == 0.f) CHECK(se < kMaxRelStdErr * E);
    }
}

TEST_CASE("light_power of each kind", "[light][quick]") {
    Scene scene = scene_with(rect_light(Vec3(0.f), Vec3(0.f, -1.f, 0.f), Vec3(2.f, 0.f, 0.f),
                                        Vec3(0.f, 0.f, 3.f), Rgb(1.f)));
    CHECK(light_power(scene, scene.lights[0]) == Approx(kPi * 6.f));
    Light pt;
    pt.kind = LightKind::Point;
    pt.L = Rgb(2.f);
    CHECK(light_power(scene, pt) == Approx(8.f * kPi));
    Light sp = make_sphere(Vec3(0.f), 2.f, Rgb(1.f));
    CHECK(light_power(scene, sp) == Approx(kPi * 16.f * kPi));
    Light spot;
    spot.kind = LightKind::Spot;
    spot.L = Rgb(1.f);
    spot.cos_total = 0.5f;
    spot.falloff_exp = 0.f;
    CHECK(light_power(scene, spot) == Approx(kPi)); // 2 pi (1 - 1/2)
    spot.falloff_exp = 1.f;
    CHECK(light_power(scene, spot) == Approx(2.f * kPi * (1.f - 0.25f) / 2.f));
}

// ---- Ellipsoid lights ------------------------------------------------------------------------

namespace {

/// A scene whose only geometry is an emissive ellipsoid center + L (unit sphere), and its
/// Sphere light (as the builder makes it).
Scene ellipsoid_light_scene(const Vec3& c, const Mat3d& L, const Rgb& Le) {
    Scene s;
    s.source = "test-ellipsoid";
    SceneEditor editor(s);
    Material m;
    m.kind = BsdfKind::Emission;
    m.radiance = Le;
    editor.add_sphere(make_ellipsoid(c, L, editor.add_material(m))); // light 0
    editor.finalize();
    return s;
}

/// A sheared, rotated, non-uniformly scaled map.
Mat3d test_ellipsoid_map() {
    Mat3d L;
    const double v[3][3] = {{0.8, 0.3, -0.1}, {0.1, 0.35, 0.2}, {-0.2, 0.15, 0.6}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            L.m[i][j] = v[i][j];
    return L;
}

/// First intersection (t > 0) of a ray with the ellipsoid, in double; the hit point.
std::optional<Vec3> hit_ellipsoid(const Sphere& e, const Vec3& o, const Vec3& d) {
    double t = 0.0;
    if (!intersect_sphere_prim_double(e, Vec3d(o), Vec3d(d), 0.0,
                                      std::numeric_limits<double>::infinity(), t))
        return std::nullopt;
    return Vec3(Vec3d(o) + Vec3d(d) * t);
}

/// pdf_li along w from ref at the ray's first hit, 0 for directions that miss (so the
/// chi-square test also checks that the sampler covers exactly the ellipsoid).
test::DirectionPdf ellipsoid_pdf(const Scene& scene, const Vec3& ref) {
    return [&scene, ref](const Vec3& w) -> float {
        const Sphere& e = scene.spheres[0];
        auto q = hit_ellipsoid(e, ref, w);
        if (!q) return 0.f;
        const EllipsoidPoint ep = ellipsoid_point(e, e.to_object * (*q - e.center), -w);
        return pdf_li(scene, scene.lights[0], ref, w, ep.p, ep.n, 0u);
    };
}

} // namespace

TEST_CASE("ellipsoid light: chi-square from outside (near, far) and inside", "[light][stat]") {
    SECTION("outside, near") {
        Scene scene =
            ellipsoid_light_scene(Vec3(0.2f, 1.6f, -0.3f), test_ellipsoid_map(), Rgb(2.f));
        const Vec3 ref(0.f);
        auto [zs, zp] = test::zoom_view(direction_sampler(scene, ref), ellipsoid_pdf(scene, ref),
                                        scene.spheres[0].center - ref, 1.5);
        check_chi2(zs, zp, 41, 1.0);
    }
    SECTION("outside, far (small cone)") {
        Scene scene = ellipsoid_light_scene(Vec3(3.f, 20.f, -4.f), test_ellipsoid_map(), Rgb(2.f));
        const Vec3 ref(0.f);
        auto [zs, zp] = test::zoom_view(direction_sampler(scene, ref), ellipsoid_pdf(scene, ref),
                                        scene.spheres[0].center - ref, 15.0);
        check_chi2(zs, zp, 42, 1.0);
    }
    SECTION("inside") {
        Scene scene = ellipsoid_light_scene(Vec3(0.f), test_ellipsoid_map(), Rgb(2.f));
        const Vec3 ref(0.1f, 0.05f, -0.1f);
        check_chi2(direction_sampler(scene, ref), ellipsoid_pdf(scene, ref), 43, 1.0);
    }
}

TEST_CASE("ellipsoid light: samples are the first hits, pdf_li matches sample_li",
          "[light][quick]") {
    // Relative agreement of a sampled point with the double-precision first hit along its
    // direction: the map's rounding (~map_error ulps) over the distance.
    constexpr float kHitRelTol = 1e-4f;
    Pcg32 rng(44, 1);
    for (const Vec3 ref : {Vec3(0.f), Vec3(0.05f, 1.7f, -0.2f), Vec3(5.f, -3.f, 20.f)}) {
        Scene scene =
            ellipsoid_light_scene(Vec3(0.2f, 1.6f, -0.3f), test_ellipsoid_map(), Rgb(2.f));
        const Sphere& e = scene.spheres[0];
        const Light& light = scene.lights[0];
        int n = 0;
        for (int i = 0; i < 2000; ++i) {
            auto s = sample_li(scene, light, ref, Vec2(rng.next_float(), rng.next_float()));
            if (!s) continue;
            ++n;
            INFO("ref (" << ref.x << ", " << ref.y << ", " << ref.z << ") sample " << i);
            // On the surface, where the ray from ref along wi first meets it.
            auto q = hit_ellipsoid(e, ref, s->wi);
            REQUIRE(q);
            CHECK(length(*q - s->p_light) <= kHitRelTol * (s->dist + 1.f));
            CHECK(s->dist == Approx(length(s->p_light - ref)).epsilon(1e-5));
            // The normal faces the reference point and is the surface normal there.
            CHECK(dot(s->n_light, s->wi) <= 0.f);
            const EllipsoidPoint ep =
                ellipsoid_point(e, e.to_object * (s->p_light - e.center), -s->wi);
            CHECK(std::abs(dot(ep.n, s->n_light)) == Approx(1.f).epsilon(1e-4));
            // pdf_li at the hit the sample describes agrees with the sample's own pdf.
            const float p = pdf_li(scene, light, ref, s->wi, s->p_light, s->n_light, s->prim);
            CHECK(p == Approx(s->pdf).epsilon(kPdfRelTol));
            CHECK(s->p_error.x > 0.f);
        }
        CHECK(n > 1900);
    }
}

TEST_CASE("ellipsoid light: irradiance by light sampling matches ray casting", "[light][stat]") {
    // An estimator that never calls the light choice: cosine-weighted directions from the
    // reference point, E = pi L P(hit). Both estimates are unbiased for the same E.
    constexpr int kSamples = 200000;
    const Rgb Le(3.f);
    for (const Vec3 c : {Vec3(0.3f, 1.5f, 0.2f), Vec3(-2.f, 6.f, 1.f)}) {
        Scene scene = ellipsoid_light_scene(c, test_ellipsoid_map(), Le);
        const Vec3 ref(0.f), n(0.f, 1.f, 0.f);
        auto [mean, se] = mc_irradiance(scene, ref, n, kSamples, 45);
        Pcg32 rng(46, 2);
        const Frame frame(n);
        int hits = 0;
        for (int i = 0; i < kSamples; ++i) {
            const Vec3 w = frame.to_world(
                square_to_cosine_hemisphere(Vec2(rng.next_float(), rng.next_float())));
            hits += hit_ellipsoid(scene.spheres[0], ref, w).has_value();
        }
        const double frac = double(hits) / kSamples;
        const double E_cast = kPi * Le.x * frac;
        const double se_cast = kPi * Le.x * std::sqrt(frac * (1.0 - frac) / kSamples);
        INFO("light sampling " << mean << " +- " << se << ", ray casting " << E_cast << " +- "
                               << se_cast);
        CHECK(std::abs(mean - E_cast) <= kZBound * std::sqrt(se * se + se_cast * se_cast));
        CHECK(se < kMaxRelStdErr * mean);
    }
}

TEST_CASE("ellipsoid light: power follows its area", "[light][quick]") {
    Scene scene = ellipsoid_light_scene(Vec3(0.f), test_ellipsoid_map(), Rgb(1.f));
    const Light& l = scene.lights[0];
    CHECK(l.area == Approx(sphere_area(scene.spheres[0])));
    CHECK(light_power(scene, l) == Approx(kPi * l.area));
    // The area from the quadrature against a Monte Carlo estimate of Nanson's integral.
    Pcg32 rng(47, 3);
    const Sphere& e = scene.spheres[0];
    double sum = 0.0, sum2 = 0.0;
    constexpr int kN = 200000;
    for (int i = 0; i < kN; ++i) {
        const Vec3 x = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
        const double v = 4.0 * kPi * std::abs(double(e.to_world.det())) *
                         double(length(e.to_object.transpose_mul(x)));
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / kN, se = std::sqrt((sum2 / kN - mean * mean) / kN);
    CHECK(std::abs(mean - sphere_area(e)) <= kZBound * se);
}

namespace {

/// A w x h map whose texels hold luminance-only radiance f(d) at their centres' directions.
std::shared_ptr<const EnvMap> map_of(int w, int h, float (*f)(const Vec3&)) {
    const EnvMap grid(w, h, std::vector<Rgb>(std::size_t(w) * std::size_t(h), Rgb(0.f)));
    std::vector<Rgb> tex;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            tex.push_back(Rgb(f(grid.xy_to_direction(float(i) + 0.5f, float(j) + 0.5f))));
    return std::make_shared<const EnvMap>(w, h, tex, "irradiance test");
}

/// Unit normals: the axes both ways and a few generic ones.
std::vector<Vec3> test_normals() {
    std::vector<Vec3> out = {Vec3(1.f, 0.f, 0.f),  Vec3(-1.f, 0.f, 0.f), Vec3(0.f, 1.f, 0.f),
                             Vec3(0.f, -1.f, 0.f), Vec3(0.f, 0.f, 1.f),  Vec3(0.f, 0.f, -1.f)};
    Pcg32 rng(5, 9);
    for (int i = 0; i < 8; ++i)
        out.push_back(square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float())));
    return out;
}

} // namespace

TEST_CASE("light irradiance: ambient and directional against quadrature", "[light][quick]") {
    // Midpoint rule over a 512 x 256 grid in (phi, theta), the horizon on a row boundary: the
    // integrand is smooth on each side of the horizon and of the surface's own horizon, whose
    // kink costs O(cell^2) per crossed cell: some 1e-5 of pi, which 1e-4 of pi bounds several
    // times over.
    constexpr double kQuadratureTol = 1e-4 * kPiD;
    Light ambient;
    ambient.kind = LightKind::Ambient;
    ambient.L = Rgb(0.8f);
    const Scene scene = scene_with(ambient);
    const InfiniteIrradiance amb = infinite_irradiance_model(scene, ambient);
    CHECK(amb.lum == luminance(ambient.L));
    for (const Vec3& n : test_normals()) {
        INFO("n = " << n.x << " " << n.y << " " << n.z);
        const int nphi = 512, ntheta = 256;
        double e = 0.0;
        for (int j = 0; j < ntheta / 2; ++j) { // the upper hemisphere: theta < pi / 2
            const double t0 = kPiD * j / ntheta, t1 = kPiD * (j + 1) / ntheta;
            const double tc = 0.5 * (t0 + t1);
            for (int i = 0; i < nphi; ++i) {
                const double phi = 2.0 * kPiD * (i + 0.5) / nphi;
                const Vec3 d(float(std::sin(tc) * std::cos(phi)), float(std::cos(tc)),
                             float(std::sin(tc) * std::sin(phi)));
                e += std::max(0.0, double(dot(n, d))) * (std::cos(t0) - std::cos(t1)) * 2.0 * kPiD /
                     nphi;
            }
        }
        CHECK(std::abs(light_irradiance(amb, n) - amb.lum * e) <= kQuadratureTol);
    }
    Light sun;
    sun.kind = LightKind::Directional;
    sun.L = Rgb(2.f);
    sun.n = normalize(Vec3(1.f, 2.f, 0.5f));
    const InfiniteIrradiance dir = infinite_irradiance_model(scene, sun);
    CHECK(light_irradiance(dir, sun.n) == Approx(luminance(sun.L)));
    CHECK(light_irradiance(dir, -sun.n) == 0.f);
    CHECK(light_irradiance(dir, Vec3(0.f, 1.f, 0.f)) == Approx(luminance(sun.L) * sun.n.y));
    Light pt;
    pt.kind = LightKind::Point;
    CHECK_THROWS_AS(infinite_irradiance_model(scene, pt), Error);
}

TEST_CASE("light irradiance: an environment map's harmonics are exact where they can be",
          "[light][quick]") {
    // Maps whose radiance has no order above 2 (a constant, a linear function of direction) or
    // none the clamped cosine keeps (one lit hemisphere, whose even orders above 0 vanish):
    // their irradiance is known in closed form, and the harmonics must give it up to the
    // projection's midpoint rule over 32 rows of texels: an error of order (pi / 32)^2 / 24 =
    // 4e-4 times the integrand's second derivative in theta, at most about 8 here (radiance up
    // to 2 times the curvature of the harmonic and of sin(theta)), so about 3e-3, which 3e-3 pi
    // bounds three times over.
    constexpr double kProjectionTol = 3e-3 * kPiD;
    struct Case {
        const char* name;
        float (*radiance)(const Vec3&);
        double (*irradiance)(const Vec3&);
    };
    const Case cases[] = {
        {"constant", [](const Vec3&) { return 0.7f; }, [](const Vec3&) { return 0.7 * kPiD; }},
        // integral of (a . w) max(0, n . w) dw = (2 pi / 3) a . n
        {"linear", [](const Vec3& d) { return 1.f + 0.5f * d.x - 0.3f * d.y + 0.25f * d.z; },
         [](const Vec3& n) {
             return kPiD + 2.0 * kPiD / 3.0 * (0.5 * n.x - 0.3 * n.y + 0.25 * n.z);
         }},
        {"upper hemisphere", [](const Vec3& d) { return d.y > 0.f ? 1.f : 0.f; },
         [](const Vec3& n) { return kPiD * 0.5 * (1.0 + n.y); }},
    };
    Light env;
    env.kind = LightKind::Environment;
    Scene scene = scene_with(env);
    for (const Case& c : cases) {
        scene.env = map_of(64, 32, c.radiance);
        const InfiniteIrradiance m = infinite_irradiance_model(scene, env);
        for (const Vec3& n : test_normals()) {
            INFO(c.name << ", n = " << n.x << " " << n.y << " " << n.z);
            CHECK(std::abs(double(light_irradiance(m, n)) - c.irradiance(n)) <= kProjectionTol);
        }
    }
    // An ambient light and the map of its lit hemisphere give one irradiance.
    scene.env = map_of(64, 32, cases[2].radiance);
    const InfiniteIrradiance m = infinite_irradiance_model(scene, env);
    Light ambient;
    ambient.kind = LightKind::Ambient;
    ambient.L = Rgb(1.f);
    const InfiniteIrradiance amb = infinite_irradiance_model(scene, ambient);
    for (const Vec3& n : test_normals())
        CHECK(std::abs(double(light_irradiance(m, n)) - light_irradiance(amb, n)) <=
              kProjectionTol);
}
