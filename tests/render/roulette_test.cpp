// Russian roulette: where its test happens decides how heavy the samples that survive it are.
// After a specular or glossy lobe the test waits for the next hit, so that the light the
// scattered ray finds (which next-event estimation cannot reach through such a lobe) is added
// with the throughput the ray carries, never divided by a survival probability. Dividing it
// made the fireflies of mirror and glossy-metal scenes (docs/performance.md).
#include "render_support.h"

#include <catch2/catch.hpp>

#include <string>

using namespace candela;
using namespace candela::test;

namespace {

/// Quiet uniform renders of w x h pixels with the variance channel.
RenderSettings settings(int w, int h, int spp, int max_depth) {
    RenderSettings s;
    s.width = w;
    s.height = h;
    s.spp = spp;
    s.max_depth = max_depth;
    s.quiet = true;
    s.aovs = AovSet::parse("variance");
    return s;
}

} // namespace

TEST_CASE("light seen through a mirror carries no roulette noise", "[render][stat][roulette]") {
    // A grey mirror floor of reflectance rho under a uniform sky of radiance L, seen from above
    // with roulette from the first vertex on (--rr-depth 0): every camera ray reflects once and
    // leaves, so every sample is exactly rho L. A test before the reflected ray is traced would
    // keep the path with probability rho (its throughput) and give L / 1 or 0: a per-sample
    // variance of L^2 rho (1 - rho).
    const float rho = 0.5f, L = 2.f;
    Scene scene;
    SceneEditor editor(scene);
    Material mirror;
    mirror.kind = BsdfKind::Mirror;
    mirror.reflectance = Rgb(rho);
    add_floor(scene, 1000.f, 0.f, editor.add_material(mirror));
    Light sky;
    sky.kind = LightKind::Ambient;
    sky.L = Rgb(L);
    editor.add_light(sky);
    scene.camera = camera_looking_down(Vec3(0, 1, 0), 40.f);
    editor.finalize();

    RenderSettings s = settings(8, 8, 64, 4);
    s.rr_min_depth = 0;
    s.seed = 11;
    const Film film = render_film(scene, s);
    const double roulette_variance = double(L) * L * rho * (1.0 - rho);
    // The only spread left is float rounding of rho * L, far below a millionth of the spread a
    // roulette test before the reflection would add.
    constexpr double kRoundingShare = 1e-6;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            const Rgb mean = film.mean(x, y);
            const Rgb per_sample = film.variance_of_mean(x, y) * float(s.spp);
            INFO("pixel " << x << "," << y << ": mean " << mean.x << ", per-sample variance "
                          << per_sample.x);
            CHECK(mean.x == Approx(rho * L).epsilon(1e-6));
            CHECK(max_component(per_sample) < kRoundingShare * roulette_variance);
        }
}

TEST_CASE("roulette keeps the mean of mirror, glass and metal paths", "[render][stat][roulette]") {
    // materials.dae holds one object of every BSDF kind and an area light. Roulette from the
    // first vertex on (its tests deferred past every specular and glossy lobe) against no
    // roulette at all: the two estimators have one expectation, so their image means agree
    // within the z-bound of their combined standard error.
    Diagnostics diag;
    BuildOptions opt;
    opt.camera_mode = CameraMode::File;
    const Scene scene =
        load_scene(std::string(CANDELA_PROJECT_SCENES) + "/materials.dae", opt, diag);
    const RenderSettings s = settings(32, 24, 512, 8);
    RenderSettings with = s, without = s;
    with.rr_min_depth = 0;
    with.seed = 3;
    without.rr_min_depth = s.max_depth + 1; // never reached: no roulette
    without.seed = 5;
    const Estimate a = film_estimate(render_film(scene, with));
    const Estimate b = film_estimate(render_film(scene, without));
    const double se = std::sqrt(a.std_err * a.std_err + b.std_err * b.std_err);
    INFO("roulette " << a.mean << " +- " << a.std_err << ", none " << b.mean << " +- "
                     << b.std_err);
    REQUIRE(se > 0.0);
    CHECK(std::abs(a.mean - b.mean) < kZBound * se);
    // Informative: a bias of 2 % of the image would be seen.
    CHECK(kZBound * se < 0.02 * b.mean);
}
