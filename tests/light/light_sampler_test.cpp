// Tests of power-proportional light selection.
#include "candela/light/light_sampler.h"
#include "candela/light/light_sampling.h"
#include "candela/sampling/rng.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;

namespace {

Light point_light(float intensity) {
    Light l;
    l.kind = LightKind::Point;
    l.L = Rgb(intensity);
    return l;
}

} // namespace

TEST_CASE("light sampler: picks lights proportionally to power", "[light][stat]") {
    // z-score bound on each binomial count with a fixed seed (false failure ~6e-5 per light).
    constexpr double kZBound = 4.0;
    // pmf values are float quotients of float powers: 1e-6 relative covers their rounding.
    constexpr float kPmfTol = 1e-6f;
    Scene scene;
    scene.source = "test";
    scene.lights.push_back(point_light(1.f)); // power 4 pi
    scene.lights.push_back(point_light(3.f)); // 12 pi
    Light rect;
    rect.kind = LightKind::Rect;
    rect.L = Rgb(1.f);
    rect.n = Vec3(0.f, -1.f, 0.f);
    rect.dx = Vec3(1.f, 0.f, 0.f);
    rect.dy = Vec3(0.f, 0.f, 1.f);
    scene.lights.push_back(rect);             // pi
    scene.lights.push_back(point_light(0.f)); // 0: never chosen
    scene.lights.push_back(point_light(2.f)); // 8 pi
    const std::vector<double> expected = {4.0 / 25.0, 12.0 / 25.0, 1.0 / 25.0, 0.0, 8.0 / 25.0};

    LightSampler sampler(scene);
    REQUIRE(sampler.size() == 5);
    for (std::size_t k = 0; k < expected.size(); ++k)
        CHECK(sampler.pmf(k) == Approx(expected[k]).margin(kPmfTol));
    CHECK(sampler.pmf(5) == 0.f);

    constexpr int kDraws = 200000;
    std::vector<int> count(expected.size(), 0);
    Pcg32 rng(42, 7);
    for (int i = 0; i < kDraws; ++i) {
        auto c = sampler.sample(rng.next_float());
        REQUIRE(c);
        REQUIRE(c->index < expected.size());
        CHECK(c->pmf == sampler.pmf(c->index));
        ++count[c->index];
    }
    for (std::size_t k = 0; k < expected.size(); ++k) {
        double mean = kDraws * expected[k];
        double sd = std::sqrt(kDraws * expected[k] * (1.0 - expected[k]));
        INFO("light " << k << ": " << count[k] << " picks, expected " << mean << " +- " << sd);
        CHECK(std::abs(count[k] - mean) <= kZBound * sd);
    }
    CHECK(count[3] == 0);
    // The ends of [0, 1).
    CHECK(sampler.sample(0.f)->index == 0);
    CHECK(sampler.sample(std::nextafter(1.f, 0.f))->index == 4);
}

TEST_CASE("light sampler: empty, all-zero and inconsistent scenes", "[light][quick]") {
    Scene empty;
    LightSampler none(empty);
    CHECK_FALSE(none.sample(0.5f));
    CHECK(none.pmf(0) == 0.f);

    Scene dark;
    dark.lights = {point_light(0.f), point_light(0.f), point_light(0.f), point_light(0.f)};
    LightSampler uniform(dark);
    for (std::size_t k = 0; k < 4; ++k)
        CHECK(uniform.pmf(k) == Approx(0.25f));
    CHECK(uniform.sample(0.6f)->index == 2);

    Scene bad;
    bad.source = "bad.dae";
    Light mesh_light;
    mesh_light.kind = LightKind::Mesh;
    mesh_light.L = Rgb(1.f);
    mesh_light.geom_id = 3; // no such mesh
    mesh_light.tri_cdf = {1.f};
    bad.lights.push_back(mesh_light);
    CHECK_THROWS_AS(LightSampler(bad), Error);

    Scene no_env;
    Light env;
    env.kind = LightKind::Environment;
    no_env.lights.push_back(env);
    CHECK_THROWS_AS(LightSampler(no_env), Error);

    Scene negative;
    negative.lights.push_back(point_light(-1.f));
    CHECK_THROWS_AS(LightSampler(negative), Error);
}
