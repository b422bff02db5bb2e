// The light tree and the bvh light choice: exact probabilities at every shading point, and no
// light that can light a point left unreachable there.
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
#include "candela/light/light_tree.h"
#include "candela/math/constants.h"
#include "candela/sampling/rng.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;

namespace {

Vec3 random_in(Pcg32& rng, float lo, float hi) {
    auto r = [&] { return lo + (hi - lo) * rng.next_float(); };
    return Vec3(r(), r(), r());
}

/// `n` finite lights of every kind without geometry (point, spot, rectangle, sphere) scattered
/// through [-10, 10]^3, powers over nine decades, and an ambient and a directional light.
Scene many_light_scene(std::size_t n, std::uint64_t seed) {
    Pcg32 rng(seed, 5);
    Scene scene;
    scene.source = "many-lights";
    for (std::size_t k = 0; k < n; ++k) {
        Light l;
        l.p = random_in(rng, -10.f, 10.f);
        l.L = Rgb(float(std::pow(10.0, 9.0 * rng.next_float() - 4.0)));
        switch (k % 4) {
        case 0:
            l.kind = LightKind::Point;
            break;
        case 1:
            l.kind = LightKind::Spot;
            l.n = normalize(random_in(rng, -1.f, 1.f) + Vec3(0.f, 0.f, 1e-3f));
            l.cos_total = 0.2f + 0.7f * rng.next_float();
            break;
        case 2:
            l.kind = LightKind::Area;
            l.dx = random_in(rng, -1.f, 1.f);
            l.dy = normalize(cross(l.dx, Vec3(0.3f, 1.f, 0.1f)));
            l.n = normalize(cross(l.dx, l.dy));
            break;
        default:
            l.kind = LightKind::Sphere;
            l.radius = 0.1f + rng.next_float();
            Sphere sphere;
            sphere.center = l.p;
            sphere.radius = l.radius;
            l.geom_id = std::uint32_t(scene.spheres.size());
            scene.spheres.push_back(sphere);
            break;
        }
        scene.lights.push_back(l);
    }
    Light amb;
    amb.kind = LightKind::Ambient;
    amb.L = Rgb(0.1f);
    scene.lights.push_back(amb);
    Light sun;
    sun.kind = LightKind::Directional;
    sun.n = Vec3(0.f, 1.f, 0.f);
    sun.L = Rgb(2.f);
    scene.lights.push_back(sun);
    return scene;
}

/// The tree over the first `n` lights of `scene`.
LightTree tree_of_first(const Scene& scene, std::uint32_t n) {
    std::vector<std::uint32_t> index;
    std::vector<LightCone> cones;
    for (std::uint32_t k = 0; k < n; ++k) {
        index.push_back(k);
        cones.push_back(light_cone(scene, scene.lights[k], light_power(scene, scene.lights[k])));
    }
    return LightTree(index, cones);
}

} // namespace

TEST_CASE("light tree: every value of u chooses as units() says", "[light][quick]") {
    // A tree over 40 lights and a small range, enumerated value by value at random points: the
    // values choosing each light are exactly units(p, n, light), so the realised probability
    // of every light is the one the MIS weights divide by.
    const Scene scene = many_light_scene(40, 3);
    const LightTree tree = tree_of_first(scene, 40);
    REQUIRE(tree.node_count() == 79);
    Pcg32 rng(9, 1);
    constexpr std::uint32_t kRange = 5000;
    for (int trial = 0; trial < 40; ++trial) {
        const Vec3 p = random_in(rng, -12.f, 12.f);
        const Vec3 n = trial % 4 == 0 ? Vec3(0.f) : normalize(random_in(rng, -1.f, 1.f));
        std::vector<std::uint32_t> count(40, 0);
        std::uint32_t none = 0;
        for (std::uint32_t u = 0; u < kRange; ++u) {
            std::uint32_t units = 0;
            const std::int64_t k = tree.sample(p, n, u, kRange, &units);
            if (k < 0) {
                ++none;
                continue;
            }
            REQUIRE(k < 40);
            ++count[std::size_t(k)];
            CHECK(units == tree.units(p, n, std::uint32_t(k), kRange));
        }
        std::uint32_t total = none;
        for (std::uint32_t k = 0; k < 40; ++k) {
            INFO("trial " << trial << ", light " << k);
            CHECK(count[k] == tree.units(p, n, k, kRange));
            total += count[k];
        }
        CHECK(total == kRange);
    }
}

TEST_CASE("light tree: a light that lights a point is reachable there", "[light][quick]") {
    // The importance bounds are conservative: wherever a light's sample carries radiance toward
    // a point (and the surface there faces it), the tree gives that light a positive range.
    const Scene scene = many_light_scene(60, 4);
    const LightTree tree = tree_of_first(scene, 60);
    Pcg32 rng(10, 2);
    int lit = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vec3 p = random_in(rng, -12.f, 12.f);
        const Vec3 n = normalize(random_in(rng, -1.f, 1.f));
        for (std::uint32_t k = 0; k < 60; ++k) {
            const auto s =
                sample_li(scene, scene.lights[k], p, Vec2(rng.next_float(), rng.next_float()));
            if (!s || is_black(s->L) || !(std::abs(dot(s->wi, n)) > 0.f)) continue;
            ++lit;
            INFO("trial " << trial << ", light " << k << " ("
                          << light_kind_name(scene.lights[k].kind) << ")");
            CHECK(tree.units(p, n, k, kProbabilityUnits) > 0);
        }
    }
    CHECK(lit > 1000); // the check above ran often enough to mean something
}

TEST_CASE("bvh light choice: pmf is the realised probability at every point", "[light][quick]") {
    // All 2^23 units of the uniform at a few points: the units choosing each light are its
    // pmf(p, n, light) * 2^23, and every choice reports that pmf.
    const Scene scene = many_light_scene(24, 6);
    const LightChooser sampler(scene, LightSamplerKind::Bvh);
    REQUIRE(sampler.kind() == LightSamplerKind::Bvh);
    REQUIRE(LightChooser(scene, LightSamplerKind::Auto).kind() == LightSamplerKind::Bvh);
    REQUIRE(LightChooser(scene, LightSamplerKind::Power).kind() == LightSamplerKind::Power);
    Pcg32 rng(12, 3);
    const std::size_t n = scene.lights.size();
    for (int trial = 0; trial < 2; ++trial) {
        const Vec3 p = random_in(rng, -12.f, 12.f);
        const Vec3 nrm = normalize(random_in(rng, -1.f, 1.f));
        std::vector<std::uint32_t> count(n, 0);
        for (std::uint32_t v = 0; v < kProbabilityUnits; ++v) {
            const auto c = sampler.sample({p, nrm}, v << 9);
            if (!c) continue;
            ++count[c->index];
            if (v % 997 == 0) CHECK(c->pmf == sampler.pmf({p, nrm}, c->index));
        }
        double sum = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
            INFO("trial " << trial << ", light " << k);
            CHECK(double(sampler.pmf({p, nrm}, k)) == std::ldexp(double(count[k]), -23));
            sum += sampler.pmf({p, nrm}, k);
            // The floor: every finite light at least 1/64 of an even share of its group.
            if (!scene.lights[k].is_infinite()) CHECK(sampler.pmf({p, nrm}, k) > 0.f);
        }
        CHECK(sum <= 1.0);
        // Three shares: the finite lights, the ambient light, the sun. The two infinite lights
        // split theirs by the orientation (each split rounds down: a unit each at most is lost),
        // and with no orientation they take their fixed shares (to a unit each).
        REQUIRE(sampler.split().active());
        CHECK(std::abs(double(sampler.pmf({p, nrm}, n - 1)) + sampler.pmf({p, nrm}, n - 2) -
                       2.0 / 3.0) <= 4.0 * 0x1p-23);
        const Vec3 none(0.f);
        CHECK(std::abs(double(sampler.pmf({p, none}, n - 1)) + sampler.pmf({p, none}, n - 2) -
                       2.0 / 3.0) <= 2.0 * 0x1p-23);
    }
    // One light: no table and no tree.
    Scene one = many_light_scene(1, 7);
    one.lights.resize(1);
    const LightChooser single(one, LightSamplerKind::Bvh);
    CHECK(single.kind() == LightSamplerKind::Power);
    CHECK(single.bvh() == nullptr);
    CHECK(single.sample({}, 123u)->pmf == 1.f);
}
