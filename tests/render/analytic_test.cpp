// Renders of scenes with closed-form radiance, checked by a z-test whose bound comes from the
// estimator's own variance (render_support.h). Every test runs with Embree and the builtin BVH.
#include "render_support.h"

#include <catch2/catch.hpp>

using namespace candela;
using namespace candela::test;

namespace {

RenderSettings small_settings(AccelKind accel, int size, int spp) {
    RenderSettings s;
    s.width = s.height = size;
    s.spp = spp;
    s.threads = 0;
    s.quiet = true;
    s.accel.kind = accel;
    s.aovs = AovSet::parse("variance");
    s.seed = 7;
    return s;
}

AccelKind accel_param() {
    return GENERATE(AccelKind::Embree, AccelKind::Builtin);
}

} // namespace

TEST_CASE("furnace: a glowing diffuse sphere seen from inside has radiance Le/(1-a)",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    const float albedo = GENERATE(0.5f, 0.9f);
    const float Le = 1.f;
    const Scene scene = furnace_scene(albedo, Le);

    RenderSettings s = small_settings(accel, 16, 64);
    s.max_depth = 100000; // the hard cap never binds: roulette ends the paths
    Film film = render_film(scene, s);
    Estimate e = film_estimate(film);
    const double expected = Le / (1.0 - albedo);
    INFO("albedo " << albedo << " accel " << accel_kind_name(accel) << ": mean " << e.mean << " +- "
                   << e.std_err << ", expected " << expected);
    REQUIRE(e.std_err > 0.0);
    CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
    // The estimate must be informative: its standard error is a small fraction of the value.
    CHECK(e.std_err < 0.02 * expected);
}

TEST_CASE("diffuse plane under a uniform sky has radiance albedo * L", "[render][stat]") {
    const AccelKind accel = accel_param();
    Scene scene;
    Material m;
    m.albedo = Rgb(0.5f, 0.25f, 0.75f);
    scene.materials.push_back(m);
    add_floor(scene, 1000.f, 0);
    Light sky;
    sky.kind = LightKind::Ambient;
    sky.L = Rgb(2.f);
    scene.lights.push_back(sky);
    scene.camera = camera_looking_down(Vec3(0, 1, 0), 60.f);
    scene.finalize();

    for (bool mis : {true, false}) {
        RenderSettings s = small_settings(accel, 8, 64);
        s.max_depth = 4;
        s.mis = mis;
        Film film = render_film(scene, s);
        Estimate e = film_estimate(film);
        const double expected = luminance(m.albedo * sky.L);
        INFO("mis " << mis << ": mean " << e.mean << " +- " << e.std_err << ", expected "
                    << expected);
        REQUIRE(e.std_err > 0.0);
        CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
        CHECK(e.std_err < 0.02 * expected);
    }
}

namespace {
/// Irradiance at the origin (normal +y) from a uniform polygonal luminaire of radiance L:
/// Lambert's formula E = L/2 * sum_i angle_i * dot(n, unit(v_i x v_{i+1})).
double polygon_irradiance(const std::vector<Vec3d>& verts, double L) {
    double sum = 0.0;
    for (std::size_t i = 0; i < verts.size(); ++i) {
        Vec3d a = normalize(verts[i]), b = normalize(verts[(i + 1) % verts.size()]);
        double angle = std::acos(std::max(-1.0, std::min(1.0, dot(a, b))));
        Vec3d c = normalize(cross(a, b));
        sum += angle * c.y;
    }
    return 0.5 * L * std::abs(sum);
}
} // namespace

TEST_CASE("irradiance from a rectangular light on a plane matches the closed form",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    Scene scene;
    Material m;
    m.albedo = Rgb(0.5f);
    scene.materials.push_back(m);
    add_floor(scene, 10.f, 0);
    // A 1 x 2 light, 1 unit up, shifted off-centre, facing down.
    const Vec3 c(0.3f, 1.f, -0.2f), dx(1.f, 0.f, 0.f), dy(0.f, 0.f, 2.f);
    const float Le = 5.f;
    add_rect_light(scene, c, dx, dy, Rgb(Le));
    // A camera with a tiny field of view sees only the point below it, the origin.
    scene.camera = camera_looking_down(Vec3(0, 0.5f, 0), 1e-3f);
    scene.finalize();
    std::vector<Vec3d> verts;
    for (const Vec3& v : scene.meshes[1].positions)
        verts.push_back(Vec3d(v));
    verts.resize(4);
    const double E = polygon_irradiance(verts, Le);
    const double expected = 0.5 / double(kPi) * E;

    for (bool hemisphere : {false, true}) {
        RenderSettings s = small_settings(accel, 4, 256);
        s.max_depth = 1;
        s.hemisphere = hemisphere;
        s.integrator = IntegratorKind::Direct;
        s.light_samples = 4;
        Film film = render_film(scene, s);
        Estimate e = film_estimate(film);
        INFO("hemisphere " << hemisphere << ": mean " << e.mean << " +- " << e.std_err
                           << ", expected " << expected);
        REQUIRE(e.std_err > 0.0);
        CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
        CHECK(e.std_err < 0.03 * expected);
    }
}
