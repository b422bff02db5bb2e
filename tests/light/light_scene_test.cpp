// Light sampling on the lights the scene builder produces from candela's own scenes and (when
// present) the CS184 scenes.
#include "../support/cs184.h"
#include "candela/io/collada.h"
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
#include "candela/sampling/rng.h"
#include "candela/scene/builder.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>

using namespace candela;

namespace {

Scene load_path(const std::string& path) {
    Diagnostics diag;
    return load_scene(path, BuildOptions{}, diag);
}

/// sample_li and pdf_li agree on every light of each scene, seen from `ref` (or the centre of
/// the bounds), and the light choice's pmf sums to one.
void check_scene_lights(const std::vector<std::string>& paths) {
    // sample_li's and pdf_li's float evaluations of the same density agree to ~1e-6 relative.
    constexpr float kPdfRelTol = 1e-4f;
    // Sum of a handful of float pmfs that each carry ~1e-7 relative rounding.
    constexpr double kPmfSumTol = 1e-5;
    // A normalised float direction is unit to a few ulps.
    constexpr float kUnitTol = 1e-5f;
    for (const std::string& name : paths) {
        INFO(name);
        Scene scene = load_path(name);
        REQUIRE(!scene.lights.empty());
        LightChooser sampler(scene);
        REQUIRE(sampler.size() == scene.lights.size());
        // A point in the middle of the box sees every light. With no orientation every light
        // takes its fixed share (the infinite lights' too).
        const Vec3 ref = scene.bounds.center();
        double pmf_sum = 0.0;
        for (std::size_t k = 0; k < sampler.size(); ++k)
            pmf_sum += sampler.pmf({ref, Vec3(0.f)}, k);
        CHECK(pmf_sum == Approx(1.0).margin(kPmfSumTol));

        Pcg32 rng(31, 4);
        for (std::size_t k = 0; k < scene.lights.size(); ++k) {
            const Light& light = scene.lights[k];
            INFO("light " << k << " (" << light_kind_name(light.kind) << ")");
            int n_ok = 0;
            for (int i = 0; i < 200; ++i) {
                auto s = sample_li(scene, light, ref, Vec2(rng.next_float(), rng.next_float()));
                if (!s) continue;
                ++n_ok;
                CHECK(is_finite(s->L));
                CHECK(std::abs(length(s->wi) - 1.f) < kUnitTol);
                CHECK(s->is_delta == light.is_delta());
                CHECK(std::isfinite(s->pdf));
                CHECK(s->pdf > 0.f);
                if (!s->is_delta && !light.is_infinite()) {
                    float p = pdf_li(scene, light, ref, s->wi, s->p_light, s->n_light, s->prim);
                    CHECK(p == Approx(s->pdf).epsilon(kPdfRelTol));
                    CHECK(light_le(light, s->n_light, -s->wi) == light.L);
                }
            }
            CHECK(n_ok == 200);
        }
    }
}

/// Floor irradiance under the scene's rectangle light by light sampling against Lambert's
/// polygon formula.
void check_floor_irradiance(const Scene& scene) {
    // z-score bound with a fixed seed (false failure ~6e-5).
    constexpr double kZBound = 4.0;
    constexpr int kSamples = 100000;
    const Light* rect = nullptr;
    for (const Light& l : scene.lights)
        if (l.kind == LightKind::Area) rect = &l;
    REQUIRE(rect);
    // Just above the centre of the floor, facing up (the offset only keeps the point off the
    // floor plane; the closed form is evaluated at the same point).
    constexpr float kAboveFloor = 1e-3f;
    const Vec3 ref(scene.bounds.center().x, scene.bounds.lo.y + kAboveFloor,
                   scene.bounds.center().z);
    const Vec3 n(0.f, 1.f, 0.f);
    Vec3 v[4] = {
        rect->p - rect->dx * 0.5f - rect->dy * 0.5f, rect->p + rect->dx * 0.5f - rect->dy * 0.5f,
        rect->p + rect->dx * 0.5f + rect->dy * 0.5f, rect->p - rect->dx * 0.5f + rect->dy * 0.5f};
    double sum_angles = 0.0;
    for (int i = 0; i < 4; ++i) {
        Vec3d a = normalize(Vec3d(v[i]) - Vec3d(ref));
        Vec3d b = normalize(Vec3d(v[(i + 1) % 4]) - Vec3d(ref));
        sum_angles += std::acos(std::clamp(dot(a, b), -1.0, 1.0)) * normalize(cross(a, b)).y;
    }
    const double E = 0.5 * rect->L.y * std::abs(sum_angles);

    Pcg32 rng(77, 5);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < kSamples; ++i) {
        auto s = sample_li(scene, *rect, ref, Vec2(rng.next_float(), rng.next_float()));
        double x = s ? s->L.y * std::max(0.f, dot(n, s->wi)) / s->pdf : 0.0;
        sum += x;
        sum2 += x * x;
    }
    double mean = sum / kSamples;
    double se = std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples);
    INFO("Lambert E = " << E << ", Monte Carlo = " << mean << " +- " << se);
    CHECK(E > 0.0);
    CHECK(std::abs(mean - E) <= kZBound * se);
}

} // namespace

TEST_CASE("light sampling on built CS184 scenes", "[light][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    check_scene_lights({test::cs184_scene("CBempty.dae"),
                        test::cs184_scene("CBspheres_lambertian.dae"),
                        test::cs184_scene("CBgems.dae")});
}

TEST_CASE("light sampling on built own scenes", "[light][quick]") {
    // Rectangle (cornell-spheres), rectangle and sphere light (materials), mesh, point, spot,
    // directional and ambient lights (lights).
    check_scene_lights({test::project_scene("cornell-spheres.dae"),
                        test::project_scene("materials.dae"), test::project_scene("lights.dae")});
}

TEST_CASE("CB area light: floor irradiance matches Lambert's formula", "[light][stat]") {
    CANDELA_SKIP_WITHOUT_CS184();
    check_floor_irradiance(load_path(test::cs184_scene("CBspheres_lambertian.dae")));
}

TEST_CASE("own Cornell box area light: floor irradiance matches Lambert's formula",
          "[light][stat]") {
    check_floor_irradiance(load_path(test::project_scene("cornell-spheres.dae")));
}
