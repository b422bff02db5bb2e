// Tests of power-proportional light selection.
#include "candela/light/light_sampler.h"
#include "candela/light/light_sampling.h"
#include "candela/sampling/rng.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
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

/// Expected selection probabilities of finite lights only: power with the floor mixed in.
std::vector<double> floored(const std::vector<double>& power) {
    double sum = 0.0;
    double m = 0.0;
    for (double p : power) {
        sum += p;
        m += p > 0.0;
    }
    std::vector<double> out;
    for (double p : power)
        out.push_back(p > 0.0 ? (1.0 - kLightFloorShare) * p / sum + kLightFloorShare / m : 0.0);
    return out;
}

TEST_CASE("light sampler: picks lights proportionally to power", "[light][stat]") {
    // z-score bound on each binomial count with a fixed seed (false failure ~6e-5 per light).
    constexpr double kZBound = 4.0;
    // Probabilities are rounded to units of 2^-23; the largest absorbs the others' rounding.
    constexpr double kPmfTol = 4.0 * 0x1p-23;
    Scene scene;
    scene.source = "test";
    scene.lights.push_back(point_light(1.f)); // power 4 pi
    scene.lights.push_back(point_light(3.f)); // 12 pi
    Light rect;
    rect.kind = LightKind::Area;
    rect.L = Rgb(1.f);
    rect.n = Vec3(0.f, -1.f, 0.f);
    rect.dx = Vec3(1.f, 0.f, 0.f);
    rect.dy = Vec3(0.f, 0.f, 1.f);
    scene.lights.push_back(rect);             // pi
    scene.lights.push_back(point_light(0.f)); // 0: never chosen
    scene.lights.push_back(point_light(2.f)); // 8 pi
    const std::vector<double> expected = floored({4.0, 12.0, 1.0, 0.0, 8.0});

    LightSampler sampler(scene);
    REQUIRE(sampler.size() == 5);
    for (std::size_t k = 0; k < expected.size(); ++k)
        CHECK(sampler.pmf(k) == Approx(expected[k]).margin(kPmfTol));
    CHECK(sampler.pmf(5) == 0.f);

    constexpr int kDraws = 200000;
    std::vector<int> count(expected.size(), 0);
    Pcg32 rng(42, 7);
    for (int i = 0; i < kDraws; ++i) {
        auto c = sampler.sample(rng.next_u32(), Vec3(0.f), Vec3(0.f));
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
}

TEST_CASE("light sampler: every light's realised probability is its pmf", "[light][quick]") {
    // Scenes of 2 to 200 point lights with powers over nine decades: the 32-bit uniforms that
    // choose each light, counted from the alias table's thresholds, are pmf * 2^32 exactly.
    Pcg32 rng(7, 3);
    for (std::size_t n : {2u, 3u, 17u, 64u, 200u}) {
        Scene scene;
        scene.source = "lights";
        for (std::size_t k = 0; k < n; ++k)
            scene.lights.push_back(point_light(float(std::pow(10.0, 9.0 * rng.next_float()))));
        const LightSampler sampler(scene);
        const AliasTable& t = sampler.table();
        std::vector<std::uint64_t> count(n, 0);
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t b = t.bucket_begin(i), e = t.bucket_begin(i + 1);
            count[i] += t.threshold(i) - b;
            count[t.alias(i)] += e - t.threshold(i);
            if (t.threshold(i) > b)
                CHECK(sampler.sample(std::uint32_t(b), Vec3(0.f), Vec3(0.f))->index == i);
            if (e > t.threshold(i))
                CHECK(sampler.sample(std::uint32_t(e - 1), Vec3(0.f), Vec3(0.f))->index ==
                      t.alias(i));
        }
        for (std::size_t k = 0; k < n; ++k) {
            INFO(n << " lights, light " << k);
            CHECK(double(sampler.pmf(k)) == std::ldexp(double(count[k]), -32));
            // The floor: never below 1/64 of a uniform share (less one unit of rounding).
            CHECK(double(sampler.pmf(k)) >= kLightFloorShare / double(n) - 0x1p-23);
        }
    }
}

TEST_CASE("light sampler: infinite lights weigh the same in a scene of any size",
          "[light][quick]") {
    // A lamp in a room and a sun: the sun's share must not grow with the ground's width.
    Light sun;
    sun.kind = LightKind::Directional;
    sun.L = Rgb(1.f);
    sun.n = Vec3(0.f, 1.f, 0.f);
    for (float half_width : {10.f, 500.f, 5e4f}) {
        Scene scene;
        scene.source = "room";
        scene.bounds.grow(Vec3(-half_width, 0.f, -half_width));
        scene.bounds.grow(Vec3(half_width, 3.f, half_width));
        scene.lights = {point_light(10.f), sun};
        const LightSampler sampler(scene);
        INFO("ground half-width " << half_width);
        // One share for the finite lights, one per emitting infinite light.
        CHECK(sampler.pmf(0) == 0.5f);
        CHECK(sampler.pmf(1) == 0.5f);
        CHECK(negligible_light_warnings(scene).empty());
    }
    // A lamp 1e-9 of another's power: chosen at the floor share and reported.
    Scene weak;
    weak.source = "weak";
    weak.lights = {point_light(1.f), point_light(1e-9f)};
    const LightSampler sampler(weak);
    CHECK(double(sampler.pmf(1)) >= kLightFloorShare / 2.0 - 0x1p-23);
    const std::vector<std::string> w = negligible_light_warnings(weak);
    REQUIRE(w.size() == 1);
    CHECK(w[0].find("light 1 (point)") != std::string::npos);
}

TEST_CASE("light sampler: empty, all-zero and inconsistent scenes", "[light][quick]") {
    Scene empty;
    LightSampler none(empty);
    CHECK_FALSE(none.sample(0u, Vec3(0.f), Vec3(0.f)));
    CHECK(none.pmf(0) == 0.f);

    Scene dark;
    dark.lights = {point_light(0.f), point_light(0.f), point_light(0.f), point_light(0.f)};
    LightSampler uniform(dark);
    for (std::size_t k = 0; k < 4; ++k)
        CHECK(uniform.pmf(k) == Approx(0.25f));
    CHECK(uniform.sample(0x9999999au, Vec3(0.f), Vec3(0.f))->index == 2);

    Scene bad;
    bad.source = "bad.dae";
    Light mesh_light;
    mesh_light.kind = LightKind::Mesh;
    mesh_light.L = Rgb(1.f);
    mesh_light.geom_id = 3; // no such mesh
    mesh_light.tri_choice = UnitCdf(std::vector<std::uint32_t>{UnitCdf::kUnits});
    mesh_light.tri_area_per_pmf = {1.f};
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
