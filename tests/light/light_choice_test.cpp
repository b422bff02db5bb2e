// Tests of light choice: the power and bvh rules, the infinite lights' split, spread_within.
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
#include "candela/sampling/rng.h"
#include "candela/scene/envmap.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
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

TEST_CASE("light choice: picks lights proportionally to power", "[light][stat]") {
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

    LightChooser sampler(scene);
    REQUIRE(sampler.size() == 5);
    for (std::size_t k = 0; k < expected.size(); ++k)
        CHECK(sampler.pmf({}, k) == Approx(expected[k]).margin(kPmfTol));
    CHECK(sampler.pmf({}, 5) == 0.f);

    constexpr int kDraws = 200000;
    std::vector<int> count(expected.size(), 0);
    Pcg32 rng(42, 7);
    for (int i = 0; i < kDraws; ++i) {
        auto c = sampler.sample({}, rng.next_u32());
        REQUIRE(c);
        REQUIRE(c->index < expected.size());
        CHECK(c->pmf == sampler.pmf({}, c->index));
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

TEST_CASE("light choice: every light's realised probability is its pmf", "[light][quick]") {
    // Scenes of 2 to 200 point lights with powers over nine decades: the 32-bit uniforms that
    // choose each light are one interval of pmf * 2^32 values, the intervals tile [0, 2^32) in
    // order, and the values at both ends of each choose that light.
    Pcg32 rng(7, 3);
    for (std::size_t n : {2u, 3u, 17u, 64u, 200u}) {
        Scene scene;
        scene.source = "lights";
        for (std::size_t k = 0; k < n; ++k)
            scene.lights.push_back(point_light(float(std::pow(10.0, 9.0 * rng.next_float()))));
        const LightChooser sampler(scene);
        std::uint64_t next = 0;
        for (std::size_t k = 0; k < n; ++k) {
            INFO(n << " lights, light " << k);
            const auto [first, end] = sampler.power()->u_interval(k);
            CHECK(first == next);
            next = end;
            CHECK(double(sampler.pmf({}, k)) == std::ldexp(double(end - first), -32));
            // The floor: never below 1/64 of a uniform share (less one unit of rounding).
            CHECK(double(sampler.pmf({}, k)) >= kLightFloorShare / double(n) - 0x1p-23);
            REQUIRE(end > first);
            CHECK(sampler.sample({}, std::uint32_t(first))->index == k);
            CHECK(sampler.sample({}, std::uint32_t(end - 1))->index == k);
        }
        CHECK(next == (std::uint64_t(1) << 32));
    }
}

TEST_CASE("light choice: a choice says where u fell, and spread_within makes it uniform",
          "[light][quick]") {
    // Three lights under power selection: the first value of u choosing a light is in unit 0 of
    // its interval, the last in its last unit, and spread over the light they give the ends of
    // [0, 2^32), rising with u in between.
    Scene scene;
    scene.source = "lights";
    for (float power : {1.f, 30.f, 4.f})
        scene.lights.push_back(point_light(power));
    const LightChooser sampler(scene);
    for (std::size_t k = 0; k < 3; ++k) {
        INFO("light " << k);
        const auto [first, end] = sampler.power()->u_interval(k);
        const auto spread = [&](std::uint64_t u, std::uint32_t fill) {
            const auto c = sampler.sample({}, std::uint32_t(u));
            REQUIRE(c);
            CHECK(c->index == k);
            CHECK(std::uint64_t(c->units) << 9 == end - first);
            return spread_within(c->offset, c->units, std::uint32_t(u), fill);
        };
        CHECK(spread(first, 0u) == 0u);
        CHECK(spread(end - 1, 0xFFFFFFFFu) == 0xFFFFFFFFu);
        const std::uint32_t mid = spread((first + end) / 2, 0u);
        CHECK(spread(first, 0xFFFFFFFFu) < mid);
        CHECK(mid < spread(end - 1, 0u));
    }
    // The spread itself: a whole-range choice gives u back; otherwise the place sets the high
    // part and the fill the rest.
    for (std::uint32_t u : {0u, 1u, 511u, 0x12345678u, 0xFFFFFFFFu})
        CHECK(spread_within(u >> 9, 1u << 23, u, 0xABCDEF01u) == u);
    CHECK(spread_within(0u, 1u, 0u, 0u) == 0u);
    CHECK(spread_within(0u, 1u, 256u, 0u) == 0x80000000u);
    CHECK(spread_within(3u, 4u, 511u, 0xFFFFFFFFu) == 0xFFFFFFFFu);
    CHECK(spread_within(2u, 4u, 0u, 0u) == 0x80000000u);
    // Exactly uniform: with 3 units every output value comes from exactly 3 * 2^9 (place, fill)
    // pairs; count the pairs landing on a few outputs by inverting the map.
    const std::uint64_t span = 3u << 9;
    for (std::uint64_t out : {0ull, 1ull, 0x5555'5555ull, 0xFFFF'FFFFull}) {
        // Inputs x = place * 2^32 + fill in [out * span, (out + 1) * span) map to out.
        std::uint64_t hits = 0;
        for (std::uint64_t x = out * span; x < (out + 1) * span; x += 97) {
            const auto place = std::uint32_t(x >> 32), fill = std::uint32_t(x);
            hits += spread_within(place >> 9, 3u, place & 511u, fill) == out;
        }
        CHECK(hits == (span + 96) / 97);
        // ... and the inputs on either side of that range map to its neighbours.
        const auto at = [](std::uint64_t x) {
            const auto place = std::uint32_t(x >> 32);
            return spread_within(place >> 9, 3u, place & 511u, std::uint32_t(x));
        };
        if (out > 0) CHECK(at(out * span - 1) == out - 1);
        if (out < 0xFFFF'FFFFull) CHECK(at((out + 1) * span) == out + 1);
    }

    // Under bvh selection a light is chosen from the floor, the tree or (infinite lights) its
    // own interval: given the choice, the spread place is uniform. Twelve point lights in a
    // row and a sun, from a point among them: the spread place's mean and second moment per
    // chosen light against a uniform's (1/2 and 1/3), to kZBound standard errors.
    Scene row;
    row.source = "row";
    for (int k = 0; k < 12; ++k) {
        Light l = point_light(float(1 + k % 4));
        l.p = Vec3(float(k), 1.f, 0.f);
        row.lights.push_back(l);
    }
    Light sun;
    sun.kind = LightKind::Directional;
    sun.L = Rgb(1.f);
    sun.n = Vec3(0.f, 1.f, 0.f);
    row.lights.push_back(sun);
    const LightChooser tree(row, LightSamplerKind::Bvh);
    REQUIRE(tree.kind() == LightSamplerKind::Bvh);
    constexpr int kDraws = 200000;
    // Standard errors allowed: the 26 checks below would all pass by chance with probability
    // 99.8 % for a uniform place (the seed is fixed, so the outcome is too).
    constexpr double kZBound = 4.0;
    std::vector<double> sum(row.lights.size(), 0.0), sum2(row.lights.size(), 0.0);
    std::vector<int> count(row.lights.size(), 0);
    Pcg32 u(11, 5);
    const Vec3 p(3.5f, 0.f, 0.f), n(0.f, 1.f, 0.f);
    for (int i = 0; i < kDraws; ++i) {
        const std::uint32_t value = u.next_u32();
        const auto choice = tree.sample({p, n}, value);
        REQUIRE(choice);
        const double r = std::ldexp(
            double(spread_within(choice->offset, choice->units, value, u.next_u32())), -32);
        sum[choice->index] += r;
        sum2[choice->index] += r * r;
        ++count[choice->index];
    }
    for (std::size_t k = 0; k < row.lights.size(); ++k) {
        INFO("light " << k << ", chosen " << count[k] << " times");
        REQUIRE(count[k] > 100);
        const double mean = sum[k] / count[k];
        CHECK(std::abs(mean - 0.5) <= kZBound * std::sqrt(1.0 / 12.0 / count[k]));
        // The second moment of a uniform is 1/3; its estimate's variance is (1/5 - 1/9) / N.
        CHECK(std::abs(sum2[k] / count[k] - 1.0 / 3.0) <=
              kZBound * std::sqrt((1.0 / 5.0 - 1.0 / 9.0) / count[k]));
    }
}

TEST_CASE("light choice: infinite lights weigh the same in a scene of any size", "[light][quick]") {
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
        const LightChooser sampler(scene);
        INFO("ground half-width " << half_width);
        // One share for the finite lights, one per emitting infinite light.
        CHECK(sampler.pmf({}, 0) == 0.5f);
        CHECK(sampler.pmf({}, 1) == 0.5f);
        CHECK(negligible_light_warnings(scene).empty());
    }
    // A lamp 1e-9 of another's power: chosen at the floor share and reported.
    Scene weak;
    weak.source = "weak";
    weak.lights = {point_light(1.f), point_light(1e-9f)};
    const LightChooser sampler(weak);
    CHECK(double(sampler.pmf({}, 1)) >= kLightFloorShare / 2.0 - 0x1p-23);
    const std::vector<std::string> w = negligible_light_warnings(weak);
    REQUIRE(w.size() == 1);
    CHECK(w[0].find("light 1 (point)") != std::string::npos);
}

namespace {

/// A lamp, a sun, an ambient light and an environment map (8 x 4, a bright texel, a dim rest).
Scene sky_scene() {
    Scene scene;
    scene.source = "sky";
    scene.lights.push_back(point_light(2.f));
    Light sun;
    sun.kind = LightKind::Directional;
    sun.L = Rgb(3.f);
    sun.n = normalize(Vec3(0.6f, 0.8f, 0.f));
    scene.lights.push_back(sun);
    Light ambient;
    ambient.kind = LightKind::Ambient;
    ambient.L = Rgb(0.5f);
    scene.lights.push_back(ambient);
    std::vector<Rgb> tex(8 * 4, Rgb(0.2f));
    tex[1 * 8 + 5] = Rgb(40.f);
    scene.env = std::make_shared<const EnvMap>(8, 4, tex, "sky");
    Light env;
    env.kind = LightKind::Environment;
    env.L = Rgb(1.f);
    scene.lights.push_back(env);
    return scene;
}

} // namespace

TEST_CASE("light choice: infinite lights split their share by the irradiance at the point",
          "[light][quick]") {
    // All 2^23 units of the uniform at several orientations, under both rules: the units that
    // choose each light are its pmf({p, n}, light) * 2^23, every choice reports that pmf, the
    // lamp's share does not move, and the three infinite lights share theirs (3/4 of the
    // choice: one share each beside one for the lamp) in proportion to the irradiance each gives
    // the orientation, with the floor of light_choice.h mixed in.
    const Scene scene = sky_scene();
    const Vec3 sun = scene.lights[1].n;
    const double f = kLightFloorShare;
    for (LightSamplerKind kind : {LightSamplerKind::Power, LightSamplerKind::Bvh}) {
        const LightChooser sampler(scene, kind);
        REQUIRE(sampler.kind() == kind);
        REQUIRE(sampler.split().active());
        const Vec3 p(0.3f, 1.f, -0.2f);
        const float lamp = sampler.pmf({p, Vec3(0.f)}, 0);
        std::vector<InfiniteIrradiance> models;
        for (std::size_t k = 1; k < 4; ++k)
            models.push_back(infinite_irradiance_model(scene, scene.lights[k]));
        // The range the infinite lights share: the three shares of the fixed split.
        double range = 0.0;
        for (std::size_t k = 1; k < 4; ++k)
            range += std::ldexp(double(sampler.pmf({p, Vec3(0.f)}, k)), 23);
        CHECK(std::abs(range - 0.75 * 0x1p23) <= 3.0);
        const Vec3 sideways = normalize(Vec3(-0.8f, 0.6f, 0.3f));
        for (const Vec3& n :
             {Vec3(0.f), Vec3(0.f, 1.f, 0.f), sun, -sun, Vec3(0.f, -1.f, 0.f), sideways}) {
            INFO((kind == LightSamplerKind::Power ? "power" : "bvh")
                 << ", orientation " << n.x << " " << n.y << " " << n.z);
            std::vector<std::uint32_t> count(4, 0);
            for (std::uint32_t v = 0; v < kProbabilityUnits; ++v) {
                const auto c = sampler.sample({p, n}, v << 9);
                if (!c) continue;
                ++count[c->index];
                if (v % 997 == 0) CHECK(c->pmf == sampler.pmf({p, n}, c->index));
            }
            for (std::size_t k = 0; k < 4; ++k)
                CHECK(double(sampler.pmf({p, n}, k)) == std::ldexp(double(count[k]), -23));
            CHECK(sampler.pmf({p, n}, 0) == lamp);
            if (n.x == 0.f && n.y == 0.f && n.z == 0.f) continue; // the fixed split, above
            double total = 0.0;
            for (const InfiniteIrradiance& m : models)
                total += light_irradiance(m, n);
            REQUIRE(total > 0.0);
            double taken = 0.0;
            for (std::size_t k = 1; k < 4; ++k) {
                const double units = std::ldexp(double(sampler.pmf({p, n}, k)), 23);
                const double share =
                    (1.0 - f) * light_irradiance(models[k - 1], n) / total + f / 3.0;
                CHECK(units == std::floor(share * range));
                CHECK(units >= std::floor(f / 3.0 * range)); // never below the floor
                taken += units;
            }
            CHECK(taken <= range); // each share rounds down: under a unit each is left unchosen
            CHECK(taken > range - 3.0);
        }
        // Facing away from the sun, it gets the floor alone; a surface facing down gets no
        // ambient light (the ambient light fills the upper hemisphere) and the floor alone.
        CHECK(std::ldexp(double(sampler.pmf({p, -sun}, 1)), 23) == std::floor(f / 3.0 * range));
        CHECK(std::ldexp(double(sampler.pmf({p, Vec3(0.f, -1.f, 0.f)}, 2)), 23) ==
              std::floor(f / 3.0 * range));
        CHECK(sampler.pmf({p, sun}, 1) > sampler.pmf({p, -sun}, 1));
    }
    // One infinite light beside the lamp: its share is fixed, as before.
    Scene two = sky_scene();
    two.lights.resize(2);
    CHECK_FALSE(LightChooser(two).split().active());
    // `candela info` says which rule holds.
    CHECK(describe_light_selection(scene, LightSamplerKind::Auto) ==
          "power (auto: 1 finite light, 3 infinite lights split by orientation)");
    CHECK(describe_light_selection(two, LightSamplerKind::Auto) == "power (auto: 1 finite light)");
}

TEST_CASE("light choice: a split whose directional light is weighed by the BSDF stays exact",
          "[light][quick]") {
    // weigh_directional() replaces the sun's irradiance by a weight of the caller's (what a
    // glossy BSDF reflects of it) and the total by the new sum; sample() and pmf() given those
    // shares must still agree unit for unit, under both rules, and the other infinite lights
    // keep their irradiance. The weights here stand for a glint (100 times the irradiance), a
    // lobe turned away (0) and one equal to the irradiance (no change).
    const Scene scene = sky_scene();
    REQUIRE(scene.lights[1].kind == LightKind::Directional);
    const Vec3 sun = scene.lights[1].n;
    const Vec3 p(0.3f, 1.f, -0.2f);
    const Vec3 n = normalize(Vec3(0.2f, 1.f, -0.3f));
    for (LightSamplerKind kind : {LightSamplerKind::Power, LightSamplerKind::Bvh}) {
        const LightChooser sampler(scene, kind);
        REQUIRE(sampler.split().has_directional());
        const InfiniteShares plain = sampler.split().shares(n);
        REQUIRE(plain.total > 0.0);
        for (const float scale : {100.f, 0.f, 1.f}) {
            INFO((kind == LightSamplerKind::Power ? "power" : "bvh") << ", weight x" << scale);
            InfiniteShares shares = plain;
            int calls = 0;
            sampler.split().weigh_directional(shares, [&](const Vec3& dir, float lum) {
                ++calls;
                CHECK(dir == sun);
                return scale * lum * std::max(0.f, dot(n, dir));
            });
            CHECK(calls == 1);
            double total = 0.0;
            for (std::size_t slot = 0; slot < 3; ++slot)
                total += double(shares.irradiance[slot]);
            CHECK(shares.total == total);
            std::vector<std::uint32_t> count(4, 0);
            for (std::uint32_t v = 0; v < kProbabilityUnits; ++v) {
                const auto c = sampler.sample({p, n, &shares}, v << 9);
                if (!c) continue;
                ++count[c->index];
                if (v % 997 == 0) CHECK(c->pmf == sampler.pmf({p, n, &shares}, c->index));
            }
            for (std::size_t k = 0; k < 4; ++k)
                CHECK(double(sampler.pmf({p, n, &shares}, k)) == std::ldexp(double(count[k]), -23));
            // The lamp's share does not move; the sun's follows its weight.
            CHECK(sampler.pmf({p, n, &shares}, 0) == sampler.pmf({p, n}, 0));
            if (scale == 1.f) CHECK(sampler.pmf({p, n, &shares}, 1) == sampler.pmf({p, n}, 1));
            if (scale == 100.f) CHECK(sampler.pmf({p, n, &shares}, 1) > sampler.pmf({p, n}, 1));
            if (scale == 0.f) CHECK(sampler.pmf({p, n, &shares}, 1) < sampler.pmf({p, n}, 1));
        }
        // The fixed split (no orientation) is left as it is.
        InfiniteShares fixed = sampler.split().shares(Vec3(0.f));
        sampler.split().weigh_directional(fixed, [](const Vec3&, float) { return 1e6f; });
        CHECK(fixed.total == 0.0);
    }
    // Without a directional light in the split there is nothing to weigh.
    Scene skies = sky_scene();
    skies.lights.erase(skies.lights.begin() + 1);
    CHECK_FALSE(LightChooser(skies).split().has_directional());
}

TEST_CASE("light choice: the receiving orientation", "[light][quick]") {
    const Vec3 ns = normalize(Vec3(0.2f, 1.f, 0.1f));
    CHECK(receiving_normal(ns, Vec3(0.f, 1.f, 0.f), false) == ns);
    CHECK(receiving_normal(ns, Vec3(0.f, -1.f, 0.f), false) == -ns);
    CHECK(receiving_normal(ns, Vec3(0.f, -1.f, 0.f), true) == Vec3(0.f));
}

TEST_CASE("light choice: empty, all-zero and inconsistent scenes", "[light][quick]") {
    Scene empty;
    LightChooser none(empty);
    CHECK_FALSE(none.sample({}, 0u));
    CHECK(none.pmf({}, 0) == 0.f);

    Scene dark;
    dark.lights = {point_light(0.f), point_light(0.f), point_light(0.f), point_light(0.f)};
    LightChooser uniform(dark);
    for (std::size_t k = 0; k < 4; ++k)
        CHECK(uniform.pmf({}, k) == Approx(0.25f));
    CHECK(uniform.sample({}, 0x9999999au)->index == 2);

    Scene bad;
    bad.source = "bad.dae";
    Light mesh_light;
    mesh_light.kind = LightKind::Mesh;
    mesh_light.L = Rgb(1.f);
    mesh_light.geom_id = 3; // no such mesh
    mesh_light.tri_choice = UnitCdf(std::vector<std::uint32_t>{UnitCdf::kUnits});
    mesh_light.tri_area_per_pmf = {1.f};
    bad.lights.push_back(mesh_light);
    CHECK_THROWS_AS(LightChooser(bad), Error);

    Scene no_env;
    Light env;
    env.kind = LightKind::Environment;
    no_env.lights.push_back(env);
    CHECK_THROWS_AS(LightChooser(no_env), Error);

    Scene negative;
    negative.lights.push_back(point_light(-1.f));
    CHECK_THROWS_AS(LightChooser(negative), Error);
}
