// The irradiance a diffuse floor receives at one point from each kind of finite light, rendered
// with the path integrator at -m 1 (next-event estimation and BSDF sampling under MIS, the
// configuration compared with Cycles) and checked against answers that need no renderer:
// Lambert's contour integral for polygons (rectangles, triangles), pi L (R/d)^2 cos for a sphere
// wholly above the horizon and quadrature for one cut by it, I cos / d^2 for a point light, and
// zero where the geometry says so (an emitter seen from behind, a light in the receiver's plane
// or below it, a light behind a wall). The floor has albedo 1, so the pixel's radiance is E / pi.
#include "../render/render_support.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// Samples per pixel of every render here (16 pixels that all see the same point).
constexpr int kSpp = 4096;
/// Largest relative standard error accepted: with it a 2 % error of the estimate stands 4
/// standard errors out, so the z-test below has the power to see a bias of that size.
constexpr double kMaxRelStdErr = 0.005;
/// Midpoint-rule cells per axis of the sphere quadrature: its error from the horizon's kink
/// is below 1e-5 relative, far under the renders' standard errors.
constexpr int kQuadratureCells = 1500;

/// Relative agreement of the sphere quadrature with the closed form where both apply: the
/// midpoint rule on a smooth integrand is far more accurate; this only guards the quadrature.
constexpr double kQuadratureRelTol = 1e-4;

/// The white floor y = 0 and a camera whose pixels all see its point at the origin.
void floor_scene(SceneEditor& editor, Scene& scene) {
    Material white;
    white.albedo = Rgb(1.f);
    add_floor(scene, 20.f, 0.f, editor.add_material(white));
    scene.camera = camera_looking_down(Vec3(0.f, 0.05f, 0.f), 1e-3f);
}

std::uint32_t emission(SceneEditor& editor, float L) {
    Material m;
    m.kind = BsdfKind::Emission;
    m.radiance = Rgb(L);
    return editor.add_material(m);
}

/// Renders the scene at -m 1 and returns the estimate of E / pi at the origin.
Estimate render_point(const Scene& scene, LightSamplerKind sampler = LightSamplerKind::Auto,
                      IntegratorKind integrator = IntegratorKind::Path) {
    RenderSettings s;
    s.width = s.height = 4;
    s.spp = kSpp;
    s.threads = 0;
    s.quiet = true;
    s.aovs = AovSet::parse("variance");
    s.seed = 40;
    s.max_depth = 1;
    s.integrator = integrator;
    s.light_sampler = sampler;
    return film_estimate(render_film(scene, s));
}

/// Lambert's formula: irradiance at the origin with normal +y from a uniform polygon of
/// radiance L (vertices in order, either winding, wholly in y >= 0):
/// E = L/2 |sum_i gamma_i (y . unit(r_i x r_i+1))|, gamma_i the angle between r_i and r_i+1.
double polygon_irradiance(const std::vector<Vec3d>& v, double L) {
    double sum = 0.0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const Vec3d a = normalize(v[i]), b = normalize(v[(i + 1) % v.size()]);
        const Vec3d c = cross(a, b);
        const double len = length(c);
        if (len == 0.0) continue;
        sum += std::atan2(len, dot(a, b)) * c.y / len;
    }
    return 0.5 * L * std::abs(sum);
}

/// The part of polygon v in the half-space y >= 0 (Sutherland-Hodgman against one plane).
std::vector<Vec3d> clip_above_floor(const std::vector<Vec3d>& v) {
    std::vector<Vec3d> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const Vec3d& a = v[i];
        const Vec3d& b = v[(i + 1) % v.size()];
        if (a.y >= 0.0) out.push_back(a);
        if ((a.y >= 0.0) != (b.y >= 0.0)) out.push_back(a + (b - a) * (a.y / (a.y - b.y)));
    }
    return out;
}

/// Irradiance at the origin (normal +y) from a sphere of radiance L, centre c, radius r, with
/// every direction below the horizon y = 0 hidden: L times the integral of max(0, w.y) over the
/// cone the sphere subtends, by the midpoint rule in (cos theta, phi) about the cone's axis.
double sphere_irradiance_quadrature(const Vec3d& c, double r, double L) {
    const double d = length(c);
    const double cos_max = std::sqrt(1.0 - (r / d) * (r / d));
    const Vec3d axis = c * (1.0 / d);
    // An orthonormal frame about the axis.
    const Vec3d t =
        normalize(cross(std::abs(axis.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0), axis));
    const Vec3d b = cross(axis, t);
    const double dcos = (1.0 - cos_max) / kQuadratureCells, dphi = 2.0 * kPi / kQuadratureCells;
    double sum = 0.0;
    for (int i = 0; i < kQuadratureCells; ++i) {
        const double ct = cos_max + (i + 0.5) * dcos, st = std::sqrt(1.0 - ct * ct);
        for (int j = 0; j < kQuadratureCells; ++j) {
            const double phi = (j + 0.5) * dphi;
            const double wy = ct * axis.y + st * (std::cos(phi) * t.y + std::sin(phi) * b.y);
            sum += std::max(0.0, wy);
        }
    }
    return L * sum * dcos * dphi;
}

/// The rendered estimate agrees with E / pi within the z bound, and is precise enough to see a
/// 2 % error.
void check_radiance(const Estimate& e, double E) {
    const double expected = E / kPi;
    INFO("rendered " << e.mean << " +- " << e.std_err << ", closed form E / pi = " << expected);
    REQUIRE(e.std_err > 0.0);
    CHECK(std::abs(e.mean - expected) <= kZBound * e.std_err);
    CHECK(e.std_err <= kMaxRelStdErr * expected);
}

std::vector<Vec3d> rect_corners(const Vec3& c, const Vec3& dx, const Vec3& dy) {
    return {Vec3d(c - dx * 0.5f - dy * 0.5f), Vec3d(c + dx * 0.5f - dy * 0.5f),
            Vec3d(c + dx * 0.5f + dy * 0.5f), Vec3d(c - dx * 0.5f + dy * 0.5f)};
}

Light point_light(const Vec3& p, float intensity) {
    Light l;
    l.kind = LightKind::Point;
    l.p = p;
    l.L = Rgb(intensity);
    return l;
}

} // namespace

TEST_CASE("closed form: a tilted rectangle beside the point, whole and cut by the horizon",
          "[light][stat]") {
    // Corners from cross(dx, dy): the emitting side faces the origin in both cases.
    struct Case {
        Vec3 c, dx, dy;
        bool crosses_floor;
    };
    const Case cases[] = {
        {Vec3(0.8f, 0.6f, 0.3f), Vec3(0.f, -0.3f, 0.6f), Vec3(0.f, 0.5f, 0.4f), false},
        // Tilted through the floor: a third of it lies below y = 0, hidden by the floor.
        {Vec3(0.7f, 0.15f, -0.2f), Vec3(0.f, 0.f, 0.8f), Vec3(0.3f, 0.9f, 0.f), true},
        // Grazing: 3 m away, 0.05 m above the floor at its lowest, facing the point.
        {Vec3(-3.f, 0.3f, 0.f), Vec3(0.f, 0.f, -1.f), Vec3(0.1f, 0.5f, 0.f), false},
    };
    for (const Case& k : cases) {
        Scene scene;
        SceneEditor editor(scene);
        floor_scene(editor, scene);
        const float L = 7.f;
        add_rect_light(scene, k.c, k.dx, k.dy, Rgb(L));
        editor.finalize();
        std::vector<Vec3d> corners = rect_corners(k.c, k.dx, k.dy);
        REQUIRE(dot(Vec3d(cross(k.dx, k.dy)), Vec3d(0.0) - Vec3d(k.c)) > 0.0); // faces the point
        REQUIRE(std::any_of(corners.begin(), corners.end(),
                            [](const Vec3d& v) { return v.y < 0.0; }) == k.crosses_floor);
        const double E = polygon_irradiance(clip_above_floor(corners), L);
        INFO("rectangle at " << k.c.x << " " << k.c.y << " " << k.c.z);
        check_radiance(render_point(scene), E);
    }
}

TEST_CASE("closed form: a rectangle no ray can meet is gathered by next-event estimation alone",
          "[light][stat]") {
    // An Area record without its panel mesh (SceneEditor::add_light alone): BSDF-sampled rays
    // pass through it, so next-event estimation must keep all of its light. A 2 x 2 m rectangle
    // 0.5 m above the point, facing it, is sampled at about the BSDF's density, and MIS weighted
    // against BSDF samples that never find it the point rendered at 0.37 of its irradiance.
    Scene scene;
    SceneEditor editor(scene);
    floor_scene(editor, scene);
    const float L = 3.f;
    const Vec3 c(0.f, 0.5f, 0.f), dx(2.f, 0.f, 0.f), dy(0.f, 0.f, 2.f);
    editor.add_light(rect_light(c, Vec3(0.f, -1.f, 0.f), dx, dy, Rgb(L)));
    editor.finalize();
    REQUIRE(scene.meshes.size() == 1); // the floor alone: nothing shows the rectangle
    const double E = polygon_irradiance(rect_corners(c, dx, dy), L);
    check_radiance(render_point(scene), E);
}

TEST_CASE("closed form: emitters that cannot light the point give exactly zero", "[light][stat]") {
    Scene scene;
    SceneEditor editor(scene);
    floor_scene(editor, scene);
    // A rectangle above the point facing up, away from it.
    add_rect_light(scene, Vec3(0.f, 1.f, 0.f), Vec3(0.5f, 0.f, 0.f), Vec3(0.f, 0.f, -0.5f),
                   Rgb(9.f));
    // Rectangles in the floor's plane beside the point, one facing up and one down: every
    // direction from the point to them lies in its tangent plane (cos = 0).
    add_rect_light(scene, Vec3(1.f, 0.f, 0.f), Vec3(0.4f, 0.f, 0.f), Vec3(0.f, 0.f, -0.4f),
                   Rgb(9.f));
    add_rect_light(scene, Vec3(-1.f, 0.f, 0.f), Vec3(0.4f, 0.f, 0.f), Vec3(0.f, 0.f, 0.4f),
                   Rgb(9.f));
    // Point lights in the floor's plane and below the floor.
    editor.add_light(point_light(Vec3(0.f, 0.f, 0.7f), 5.f));
    editor.add_light(point_light(Vec3(0.3f, -0.2f, 0.f), 5.f));
    // A sphere light wholly below the floor.
    editor.add_sphere(Sphere{Vec3(0.f, -0.5f, -0.5f), 0.2f, emission(editor, 20.f)});
    // A point light and a sphere light behind a wall (a two-sided quad at x = 2 from y = 0 to
    // 2, z from -2 to 2) that stands between them and the point.
    Mesh wall;
    wall.name = "wall";
    wall.positions = {Vec3(2.f, 0.f, -2.f), Vec3(2.f, 0.f, 2.f), Vec3(2.f, 2.f, 2.f),
                      Vec3(2.f, 2.f, -2.f)};
    wall.indices = {0, 1, 2, 0, 2, 3};
    wall.material = 0; // the floor's white
    editor.add_mesh(wall);
    editor.add_light(point_light(Vec3(2.5f, 0.5f, 0.f), 5.f));
    editor.add_sphere(Sphere{Vec3(2.5f, 1.f, 0.5f), 0.1f, emission(editor, 50.f)});
    editor.finalize();
    for (LightSamplerKind k : {LightSamplerKind::Power, LightSamplerKind::Bvh}) {
        const Estimate e = render_point(scene, k);
        INFO("light sampler " << int(k) << ": " << e.mean << " +- " << e.std_err);
        CHECK(e.mean == 0.0);
    }
    const Estimate d = render_point(scene, LightSamplerKind::Auto, IntegratorKind::Direct);
    CHECK(d.mean == 0.0);
}

TEST_CASE("closed form: a sphere light above the horizon and one cut by it", "[light][stat]") {
    struct Case {
        Vec3 c;
        float r, L;
    };
    const Case cases[] = {
        {Vec3(0.6f, 1.f, -0.4f), 0.25f, 3.f},    // wholly above: pi L (r/d)^2 cos
        {Vec3(-1.5f, 0.1f, 0.5f), 0.3f, 2.f},    // sunk into the floor: quadrature
        {Vec3(0.f, 0.5f, 0.3f), 0.005f, 1000.f}, // tiny and very bright
    };
    for (const Case& k : cases) {
        Scene scene;
        SceneEditor editor(scene);
        floor_scene(editor, scene);
        editor.add_sphere(Sphere{k.c, k.r, emission(editor, k.L)});
        editor.finalize();
        const Vec3d c(k.c);
        const double d = length(c);
        double E = 0.0;
        if (c.y >= k.r) {
            E = kPi * k.L * (k.r / d) * (k.r / d) * (c.y / d);
            // The quadrature must agree with the closed form where both apply.
            CHECK(sphere_irradiance_quadrature(c, k.r, k.L) ==
                  Approx(E).epsilon(kQuadratureRelTol));
        } else {
            E = sphere_irradiance_quadrature(c, k.r, k.L);
        }
        INFO("sphere at " << k.c.x << " " << k.c.y << " " << k.c.z << " radius " << k.r);
        check_radiance(render_point(scene), E);
    }
}

TEST_CASE("closed form: a two-sided triangle seen from either side", "[light][stat]") {
    const Vec3 a(0.5f, 0.2f, -0.6f), b(0.9f, 0.9f, 0.1f), c(0.2f, 0.8f, 0.5f);
    for (bool flip : {false, true}) {
        Scene scene;
        SceneEditor editor(scene);
        floor_scene(editor, scene);
        Mesh tri;
        tri.name = "triangle";
        tri.positions = {a, b, c};
        tri.indices =
            flip ? std::vector<std::uint32_t>{0, 2, 1} : std::vector<std::uint32_t>{0, 1, 2};
        tri.material = emission(editor, 4.f);
        editor.add_mesh(tri);
        editor.finalize();
        const double E = polygon_irradiance({Vec3d(a), Vec3d(b), Vec3d(c)}, 4.0);
        INFO("winding " << (flip ? "reversed" : "as given"));
        check_radiance(render_point(scene), E);
    }
}

TEST_CASE("closed form: lights inside a large dim panel's bounds, and a point light",
          "[light][stat]") {
    // A dim 6 x 6 m panel tilted 30 degrees over the point, facing down: its bounding box holds
    // the small bright sphere and the point light, and one light hierarchy node holds them all.
    // The sphere hides ~1e-3 of the panel's solid angle from the point, a 4e-5 share of E: far
    // below the render's error, so the closed forms are summed as if nothing hid anything.
    Scene scene;
    SceneEditor editor(scene);
    floor_scene(editor, scene);
    const float t = deg_to_rad(30.f);
    const Vec3 pc(0.f, 2.f, 0.f), pdx(6.f, 0.f, 0.f),
        pdy(0.f, 6.f * std::sin(t), 6.f * std::cos(t));
    REQUIRE(dot(cross(pdx, pdy), Vec3(0.f) - pc) > 0.f);
    add_rect_light(scene, pc, pdx, pdy, Rgb(0.05f));
    const Vec3 sc(0.4f, 1.2f, 0.2f);
    const float sr = 0.02f, sL = 400.f;
    editor.add_sphere(Sphere{sc, sr, emission(editor, sL)});
    const Vec3 lp(-0.3f, 0.8f, 0.4f);
    const float I = 0.6f;
    editor.add_light(point_light(lp, I));
    editor.finalize();
    const Vec3d scd(sc), lpd(lp);
    const double E = polygon_irradiance(rect_corners(pc, pdx, pdy), 0.05) +
                     kPi * sL * (sr / length(scd)) * (sr / length(scd)) * (scd.y / length(scd)) +
                     I * (lpd.y / length(lpd)) / length_squared(lpd);
    for (LightSamplerKind k : {LightSamplerKind::Power, LightSamplerKind::Bvh}) {
        INFO("light sampler " << int(k));
        check_radiance(render_point(scene, k), E);
    }
    check_radiance(render_point(scene, LightSamplerKind::Auto, IntegratorKind::Direct), E);
}
