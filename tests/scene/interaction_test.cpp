#include "candela/accel/accel.h"
#include "candela/diagnostics/check.h"
#include "candela/scene/interaction.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

using namespace candela;

namespace {

/// Unit vectors computed in float are unit to a few ulps.
constexpr float kUnitTol = 1e-5f;
/// How far a shadow ray's end, o + d, may lie from its target in the test below, relative to
/// |target|: the target's offset along its normal (the test's error bound, 1e-6 relative), one
/// float step of the offset's rounding away and the roundings of pt - pf and pf + d (each at most
/// 2^-24 relative per component), 1.5e-6 in all, rounded up.
constexpr float kTargetOffsetTol = 2e-6f;

/// Assembled by hand, not through SceneEditor: the mesh names light record 3, which does not
/// exist, so that the test can see the index pass through make_interaction unchanged.
Scene one_triangle_scene(const Vec3& n0, const Vec3& n1, const Vec3& n2) {
    Scene s;
    s.materials.push_back(Material{});
    Mesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
    m.normals = {n0, n1, n2};
    m.indices = {0, 1, 2};
    m.material = 0;
    m.light = 3;
    s.meshes.push_back(m);
    Sphere sp;
    sp.center = Vec3(10.f, 0.f, 0.f);
    sp.radius = 2.f;
    sp.material = 0;
    s.spheres.push_back(sp);
    s.finalize();
    return s;
}

} // namespace

TEST_CASE("triangle interaction: point, normals, frame, ids", "[interaction][quick]") {
    const Vec3 up(0.f, 0.f, 1.f);
    const Scene s = one_triangle_scene(up, normalize(Vec3(1.f, 0.f, 1.f)), up);
    const Ray r{Vec3(0.5f, 0.5f, 3.f), Vec3(0.f, 0.f, -2.f), 0.f, 10.f};
    const Hit h{1.5f, 0.25f, 0.25f, 0, 0};
    const SurfaceInteraction si = make_interaction(s, r, h);
    CHECK(si.p.x == Approx(0.5f));
    CHECK(si.p.y == Approx(0.5f));
    CHECK(si.p.z == Approx(0.f).margin(1e-6));
    CHECK(si.ng == Vec3(0.f, 0.f, 1.f));
    CHECK(std::abs(length(si.ns) - 1.f) < kUnitTol);
    CHECK(si.ns.x > 0.f); // interpolated toward vertex 1's tilted normal
    CHECK(si.frame.n == si.ns);
    CHECK(std::abs(dot(si.frame.s, si.frame.n)) < kUnitTol);
    CHECK(si.wo == Vec3(0.f, 0.f, 1.f));
    CHECK(si.t == 1.5f);
    CHECK(si.light == 3);
    CHECK(si.geom_id == 0);
    CHECK(si.p_error.x > 0.f);
    CHECK(si.p_error.x < 1e-5f);
}

TEST_CASE("triangle interaction: ng is not flipped toward the ray, only toward ns",
          "[interaction][quick]") {
    const Vec3 up(0.f, 0.f, 1.f), down(0.f, 0.f, -1.f);
    // Ray from below: ng stays +z (same side as the stored normals).
    const Scene s_up = one_triangle_scene(up, up, up);
    const Ray below{Vec3(0.5f, 0.5f, -1.f), Vec3(0.f, 0.f, 1.f), 0.f, 10.f};
    const SurfaceInteraction a = make_interaction(s_up, below, Hit{1.f, 0.25f, 0.25f, 0, 0});
    CHECK(a.ng == up);
    CHECK(a.ns == up);
    // Stored normals pointing -z (against the winding): ng follows them, ns stays as stored.
    const Scene s_down = one_triangle_scene(down, down, down);
    const SurfaceInteraction b = make_interaction(s_down, below, Hit{1.f, 0.25f, 0.25f, 0, 0});
    CHECK(b.ng == down);
    CHECK(b.ns == down);
    // Cancelling normals fall back to ng.
    const Scene s_cancel = one_triangle_scene(up, down, Vec3(0.f));
    const SurfaceInteraction c = make_interaction(s_cancel, below, Hit{1.f, 0.5f, 0.f, 0, 0});
    CHECK(c.ns == c.ng);
}

TEST_CASE("sphere interaction is re-projected and outward even from inside",
          "[interaction][quick]") {
    const Scene s = one_triangle_scene(Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1));
    AccelOptions ao;
    ao.kind = AccelKind::Builtin;
    const auto accel = make_accel(s, ao);
    const Ray inside{Vec3(10.f, 0.f, 0.f), Vec3(0.f, 1.f, 0.f), 0.f, 100.f};
    const auto h = accel->intersect(inside);
    REQUIRE(h.has_value());
    REQUIRE(h->geom_id == s.sphere_geom_id());
    const SurfaceInteraction si = make_interaction(s, inside, *h);
    CHECK(si.ng.y == Approx(1.f));
    CHECK(si.ns == si.ng);
    CHECK(std::abs(length(si.p - s.spheres[0].center) - 2.f) <= 4.f * si.p_error.y + 1e-6f);
    CHECK_THROWS_AS(make_interaction(s, inside, Hit{1.f, 0.f, 0.f, s.sphere_geom_id(), 5}), Error);
    CHECK_THROWS_AS(make_interaction(s, inside, Hit{1.f, 0.f, 0.f, 7, 0}), Error);
}

TEST_CASE("spawned rays do not re-hit their own surface", "[interaction][quick]") {
    // A large, far-from-origin tessellated sphere maximises the rounding error of hit points.
    Scene s;
    add_uv_sphere_mesh(s, Vec3(1000.f, -500.f, 250.f), 3.f, 60);
    SceneEditor(s).finalize();
    for (AccelKind k : {AccelKind::Builtin, AccelKind::Embree}) {
        AccelOptions ao;
        ao.kind = k;
        const auto accel = make_accel(s, ao);
        std::mt19937 rng(4);
        std::normal_distribution<float> N(0.f, 1.f);
        int self_hits = 0, spawned = 0, shadow_blocked = 0;
        for (int i = 0; i < 20000; ++i) {
            const Vec3 dir = normalize(Vec3(N(rng), N(rng), N(rng)));
            const Ray r{s.meshes[0].positions[0] * 0.f + Vec3(1000.f, -500.f, 250.f) + dir * 20.f,
                        -dir, 0.f, 1e30f};
            const auto h = accel->intersect(r);
            if (!h) continue;
            const SurfaceInteraction si = make_interaction(s, r, *h);
            // Leave on the outside (the side of wo): nothing else on a convex body can be hit.
            Vec3 w = normalize(Vec3(N(rng), N(rng), N(rng)));
            if (dot(w, si.ng) * dot(si.wo, si.ng) < 0.f) w = -w;
            ++spawned;
            if (accel->intersect(spawn_ray(si, w))) ++self_hits;
            // Shadow ray back to the original ray's origin: unoccluded on a convex body.
            if (accel->occluded(spawn_ray_to(si, r.o, Vec3(0.f), Vec3(0.f)))) ++shadow_blocked;
        }
        INFO(accel->name() << ": spawned " << spawned);
        CHECK(spawned > 19000);
        CHECK(self_hits == 0);
        CHECK(shadow_blocked == 0);
    }
}

TEST_CASE("shadow rays between two surfaces stop short of the target", "[interaction][quick]") {
    // Two parallel quads facing each other; shadow rays between them must be unoccluded,
    // a third quad in between must occlude.
    Scene s;
    SceneEditor editor(s);
    editor.add_material(Material{});
    auto quad = [&](float z) {
        Mesh m;
        m.positions = {Vec3(-1, -1, z), Vec3(1, -1, z), Vec3(1, 1, z), Vec3(-1, 1, z)};
        m.normals = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)};
        m.indices = {0, 1, 2, 0, 2, 3};
        editor.add_mesh(m);
    };
    quad(0.f);
    quad(1.f);
    editor.finalize();
    AccelOptions ao;
    ao.kind = AccelKind::Builtin;
    const auto accel = make_accel(s, ao);
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> U(-0.9f, 0.9f);
    int blocked = 0;
    for (int i = 0; i < 5000; ++i) {
        const Ray down{Vec3(U(rng), U(rng), 0.5f), Vec3(0.f, 0.f, -1.f), 0.f, 10.f};
        const auto h = accel->intersect(down);
        REQUIRE(h.has_value());
        const SurfaceInteraction si = make_interaction(s, down, *h);
        const Vec3 target(U(rng), U(rng), 1.f);
        const Ray sr = spawn_ray_to(si, target, vabs(target) * 1e-6f, Vec3(0.f, 0.f, -1.f));
        // The segment runs from the offset origin toward the target and stops short of it.
        CHECK(sr.tmax == 1.f - kShadowEpsilon);
        CHECK(length(sr.d * sr.tmax) < length(target - si.p));
        CHECK(dot(sr.d, target - sr.o) > 0.f);
        CHECK(length((sr.o + sr.d) - target) <= kTargetOffsetTol * length(target));
        if (accel->occluded(sr)) ++blocked;
    }
    CHECK(blocked == 0);
    // Coincident ends give an invalid (never occluded) ray rather than NaNs.
    SurfaceInteraction si;
    si.p = Vec3(0.f);
    si.ng = Vec3(0.f, 0.f, 1.f);
    const Ray degenerate = spawn_ray_to(si, Vec3(0.f), Vec3(0.f), Vec3(0.f));
    CHECK_FALSE(is_valid_ray(degenerate));
    CHECK_FALSE(accel->occluded(degenerate));
}

TEST_CASE("is_valid_ray rejects every non-finite component, a zero direction and an empty "
          "interval",
          "[interaction][quick]") {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    Ray good;
    good.o = Vec3(1.f, -2.f, 3e30f);
    good.d = Vec3(0.f, 0.f, -1.f);
    good.tmin = 0.f;
    good.tmax = inf;
    CHECK(is_valid_ray(good));
    // Largest finite values: finite, though their squares overflow.
    Ray big = good;
    big.o = Vec3(std::numeric_limits<float>::max());
    big.d = Vec3(std::numeric_limits<float>::max(), 0.f, 0.f);
    CHECK(is_valid_ray(big));
    for (int k = 0; k < 6; ++k)
        for (float bad : {inf, -inf, nan}) {
            Ray r = good;
            float* c = k < 3 ? &r.o.x + k : &r.d.x + (k - 3);
            *c = bad;
            CHECK_FALSE(is_valid_ray(r));
        }
    Ray zero = good;
    zero.d = Vec3(0.f);
    CHECK_FALSE(is_valid_ray(zero));
    Ray empty = good;
    empty.tmin = 2.f;
    empty.tmax = 1.f;
    CHECK_FALSE(is_valid_ray(empty));
    Ray nan_end = good;
    nan_end.tmin = nan;
    CHECK_FALSE(is_valid_ray(nan_end));
    nan_end = good;
    nan_end.tmax = nan;
    CHECK_FALSE(is_valid_ray(nan_end));
}

TEST_CASE("offset_ray_origin moves to the side of w by at least the error bound",
          "[interaction][quick]") {
    const Vec3 p(1.f, 2.f, 3.f), err(1e-4f, 1e-4f, 1e-4f), n(0.f, 0.f, 1.f);
    const Vec3 up = offset_ray_origin(p, err, n, Vec3(0.f, 0.f, 1.f));
    const Vec3 dn = offset_ray_origin(p, err, n, Vec3(0.3f, 0.f, -1.f));
    CHECK(up.z > p.z + 1e-4f);
    CHECK(dn.z < p.z - 1e-4f);
    CHECK(up.x == p.x);
    CHECK(up.y == p.y);
}
