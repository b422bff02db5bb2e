#include "candela/accel/brute.h"
#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/procedural.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

using namespace candela;

namespace {

/// Float MT against double MT: t agrees to this relative error away from edges. The float
/// computation of t carries a relative error of a few dozen ulps for well-conditioned hits.
constexpr double kMtVsDoubleRelTol = 1e-4;
/// Rays whose double-precision barycentrics are this close to an edge may legitimately be
/// decided differently in float; they are excluded from the hit/miss comparison.
constexpr double kEdgeMargin = 1e-4;
/// Float errors of t and of the barycentrics grow like 1/|cos(d, n)|; rays closer than ~3
/// degrees to the triangle's plane are excluded so that the tolerances above bound the error.
constexpr double kMinConditioning = 0.05;

Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> N(0.f, 1.f);
    Vec3 v;
    do
        v = Vec3(N(rng), N(rng), N(rng));
    while (length_squared(v) < 1e-6f);
    return normalize(v);
}

} // namespace

TEST_CASE("Moller-Trumbore in float matches the double-precision reference", "[accel][quick]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(-1.f, 1.f);
    int compared = 0, hits = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 p0(U(rng), U(rng), U(rng)), p1(U(rng), U(rng), U(rng)),
            p2(U(rng), U(rng), U(rng));
        const Vec3 o = Vec3(U(rng), U(rng), U(rng)) * 3.f;
        // Aim at a random point of the plane region around the triangle, so about half hit.
        const float a = U(rng) * 1.2f, b = U(rng) * 1.2f;
        const Vec3 target = p0 + (p1 - p0) * std::abs(a) + (p2 - p0) * std::abs(b) * 0.6f;
        const Vec3 d = target - o;
        if (length_squared(d) < 1e-6f) continue;
        TriangleHitD ref;
        const bool hd = intersect_triangle_mt_double(Vec3d(o), Vec3d(d), Vec3d(p0), Vec3d(p1),
                                                     Vec3d(p2), 0.0, 1e30, ref);
        TriangleHit hf;
        const bool hf_ok = intersect_triangle_mt(o, d, p0, p1, p2, 0.f, 1e30f, hf);
        const double bmin = std::min({1.0 - ref.u - ref.v, ref.u, ref.v});
        if (hd && bmin < kEdgeMargin) continue;
        // A near-zero determinant makes any float answer meaningless; skip those too.
        const Vec3d n = cross(Vec3d(p1) - Vec3d(p0), Vec3d(p2) - Vec3d(p0));
        if (std::abs(dot(n, Vec3d(d))) < kMinConditioning * length(n) * length(Vec3d(d))) continue;
        ++compared;
        REQUIRE(hf_ok == hd);
        if (hd) {
            ++hits;
            REQUIRE(std::abs(hf.t - ref.t) <= kMtVsDoubleRelTol * std::abs(ref.t));
            REQUIRE(std::abs(hf.u - ref.u) <= kMtVsDoubleRelTol);
            REQUIRE(std::abs(hf.v - ref.v) <= kMtVsDoubleRelTol);
        }
    }
    INFO("compared " << compared << " hits " << hits);
    CHECK(compared > 15000);
    CHECK(hits > 3000);
}

TEST_CASE("watertight test agrees with Moller-Trumbore away from edges", "[accel][quick]") {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> U(-1.f, 1.f);
    int both = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 p0(U(rng), U(rng), U(rng)), p1(U(rng), U(rng), U(rng)),
            p2(U(rng), U(rng), U(rng));
        const Vec3 o = Vec3(U(rng), U(rng), U(rng)) * 3.f;
        // Aim at a point of the triangle's neighbourhood (barycentrics in [-0.2, 1.2]).
        const float a = U(rng) * 0.7f + 0.5f, b = U(rng) * 0.7f + 0.5f;
        const Vec3 aim = p0 + (p1 - p0) * a * 0.5f + (p2 - p0) * b * 0.5f;
        if (length_squared(aim - o) < 1e-6f) continue;
        const Vec3 d = normalize(aim - o);
        TriangleHitD ref;
        const bool hd = intersect_triangle_mt_double(Vec3d(o), Vec3d(d), Vec3d(p0), Vec3d(p1),
                                                     Vec3d(p2), 0.0, 1e30, ref);
        if (hd && std::min({1.0 - ref.u - ref.v, ref.u, ref.v}) < kEdgeMargin) continue;
        const Vec3d n = cross(Vec3d(p1) - Vec3d(p0), Vec3d(p2) - Vec3d(p0));
        if (std::abs(dot(n, Vec3d(d))) < kMinConditioning * length(n)) continue;
        TriangleHit hw;
        const bool hw_ok =
            intersect_triangle_watertight(o, make_watertight_ray(d), p0, p1, p2, 0.f, 1e30f, hw);
        REQUIRE(hw_ok == hd);
        if (hd) {
            ++both;
            REQUIRE(std::abs(hw.t - ref.t) <= kMtVsDoubleRelTol * std::max(1.0, std::abs(ref.t)));
            REQUIRE(std::abs(hw.u - ref.u) <= kMtVsDoubleRelTol);
            REQUIRE(std::abs(hw.v - ref.v) <= kMtVsDoubleRelTol);
        }
    }
    CHECK(both > 500);
}

TEST_CASE("triangle tests reject NaN and degenerate input", "[accel][quick]") {
    const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    TriangleHit h;
    CHECK_FALSE(
        intersect_triangle_mt(Vec3(nan, 0.2f, 1.f), Vec3(0, 0, -1), p0, p1, p2, 0.f, 10.f, h));
    CHECK_FALSE(
        intersect_triangle_mt(Vec3(0.2f, 0.2f, 1.f), Vec3(0, 0, 0), p0, p1, p2, 0.f, 10.f, h));
    CHECK_FALSE(
        intersect_triangle_mt(Vec3(0.2f, 0.2f, 1.f), Vec3(0, 0, -1), p0, p0, p2, 0.f, 10.f, h));
    CHECK_FALSE(intersect_triangle_watertight(
        Vec3(0.2f, 0.2f, 1.f), make_watertight_ray(Vec3(0, 0, -1)), p0, p0, p2, 0.f, 10.f, h));
    // Sanity: the same ray hits the proper triangle at t = 1 with u = v = 0.2 in both tests.
    REQUIRE(intersect_triangle_mt(Vec3(0.2f, 0.2f, 1.f), Vec3(0, 0, -1), p0, p1, p2, 0.f, 10.f, h));
    CHECK(h.t == Approx(1.f));
    CHECK(h.u == Approx(0.2f));
    CHECK(h.v == Approx(0.2f));
    REQUIRE(intersect_triangle_watertight(
        Vec3(0.2f, 0.2f, 1.f), make_watertight_ray(Vec3(0, 0, -1)), p0, p1, p2, 0.f, 10.f, h));
    CHECK(h.t == Approx(1.f));
    CHECK(h.u == Approx(0.2f));
    CHECK(h.v == Approx(0.2f));
    // Back side (double-sided) and the interval.
    REQUIRE(intersect_triangle_mt(Vec3(0.2f, 0.2f, -1.f), Vec3(0, 0, 1), p0, p1, p2, 0.f, 10.f, h));
    CHECK_FALSE(
        intersect_triangle_mt(Vec3(0.2f, 0.2f, 1.f), Vec3(0, 0, -1), p0, p1, p2, 0.f, 0.5f, h));
    CHECK_FALSE(intersect_triangle_watertight(
        Vec3(0.2f, 0.2f, 1.f), make_watertight_ray(Vec3(0, 0, -1)), p0, p1, p2, 1.5f, 10.f, h));
}

namespace {

struct LeakCount {
    int rays = 0, leaks = 0;
};

/// Rays from outside a closed convex mesh aimed exactly at its vertices and at points on its
/// edges (computed in float, so a few ulps off the exact edge either way). The direction makes
/// an angle of at least ~12 degrees with every triangle around the aimed point and points
/// into all of them, so the ray truly enters the solid there: it must hit the mesh at the aimed
/// distance. A miss, or a first hit farther away (the far side), is a leak.
LeakCount count_edge_leaks(const Scene& scene, TriangleTest test, std::uint32_t seed) {
    /// The first hit must be at the aimed distance; a far-side hit is a whole diameter away.
    constexpr float kEntryRelTol = 1e-3f;
    /// Minimum cosine between the ray and each outward normal around the target.
    constexpr float kMinCos = 0.2f;
    const BruteAccel brute(scene, test);
    const Mesh& m = scene.meshes.at(0);
    std::vector<std::vector<Vec3>> vertex_normals(m.positions.size());
    for (std::size_t j = 0; j < m.triangle_count(); ++j) {
        const std::uint32_t* t = &m.indices[3 * j];
        const Vec3 n = normalize(
            cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
        for (int k = 0; k < 3; ++k)
            vertex_normals[t[k]].push_back(n);
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    LeakCount lc;
    for (std::size_t j = 0; j < m.triangle_count(); ++j) {
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t ia = m.indices[3 * j + e], ib = m.indices[3 * j + (e + 1) % 3];
            const Vec3& pa = m.positions[ia];
            const Vec3& pb = m.positions[ib];
            std::vector<Vec3> around = vertex_normals[ia];
            around.insert(around.end(), vertex_normals[ib].begin(), vertex_normals[ib].end());
            Vec3 mean(0.f);
            for (const Vec3& n : around)
                mean += n;
            mean = normalize(mean);
            for (int k = 0; k < 3; ++k) {
                const Vec3 target = k == 0 ? pa : pa + (pb - pa) * U(rng);
                Vec3 w;
                bool found = false;
                for (int attempt = 0; attempt < 50 && !found; ++attempt) {
                    w = normalize(mean + random_unit(rng) * 0.6f);
                    found = true;
                    for (const Vec3& n : around)
                        found = found && dot(w, n) >= kMinCos;
                }
                if (!found) continue;
                const Vec3 o = target + w * (0.5f + 2.f * U(rng));
                Ray r;
                r.o = o;
                r.d = normalize(target - o);
                const float expected = length(target - o);
                const auto h = brute.intersect(r);
                ++lc.rays;
                if (!h || h->t > expected * (1.f + kEntryRelTol)) ++lc.leaks;
            }
        }
    }
    return lc;
}

} // namespace

TEST_CASE("watertight test does not leak through shared edges and vertices", "[accel][quick]") {
    for (const char* spec : {"sphere:2000", "cube:1200"}) {
        const Scene scene = make_procedural_scene(spec);
        const LeakCount wt = count_edge_leaks(scene, TriangleTest::Watertight, 3);
        const LeakCount mt = count_edge_leaks(scene, TriangleTest::MollerTrumbore, 3);
        INFO(spec << ": " << wt.rays << " edge/vertex rays; watertight leaks " << wt.leaks
                  << ", Moller-Trumbore leaks " << mt.leaks);
        WARN(spec << ": Moller-Trumbore leaked " << mt.leaks << " of " << mt.rays);
        REQUIRE(wt.rays > 10000);
        CHECK(wt.leaks == 0);
    }
}

TEST_CASE("robust sphere intersection far from the origin", "[accel][quick]") {
    // Unit sphere at distance 1e5: b'^2 and c are ~1e10, so the textbook discriminant
    // b'^2 - a c loses everything (its rounding error ~1e3 exceeds r^2 = 1).
    const Vec3 c(1e5f, 0.f, 0.f);
    const float r = 1.f;
    float t = 0.f;
    // Float spacing at 1e5 is 2^-7; t is accurate to a few ulps of that magnitude.
    constexpr float kFarTol = 0.05f;
    REQUIRE(intersect_sphere(Vec3(0.f), Vec3(1.f, 0.f, 0.f), c, r, 0.f, 1e30f, t));
    CHECK(std::abs(t - (1e5f - 1.f)) <= kFarTol);
    for (float off : {0.f, 0.5f, 0.9f, 0.99f}) {
        // Aim parallel to x at height `off`: a hit at t = 1e5 - sqrt(1 - off^2).
        REQUIRE(intersect_sphere(Vec3(0.f, off, 0.f), Vec3(1.f, 0.f, 0.f), c, r, 0.f, 1e30f, t));
        CHECK(std::abs(t - (1e5f - std::sqrt(1.f - off * off))) <= kFarTol);
    }
    CHECK_FALSE(intersect_sphere(Vec3(0.f, 1.01f, 0.f), Vec3(1.f, 0.f, 0.f), c, r, 0.f, 1e30f, t));
    // Non-unit direction and an oblique ray from the other side of the origin.
    REQUIRE(intersect_sphere(Vec3(0.f, 0.f, -50.f), Vec3(2e5f, 0.f, 100.f) / 1e5f, c, r, 0.f, 1e30f,
                             t));
    const Vec3 p = Vec3(0.f, 0.f, -50.f) + Vec3(2e5f, 0.f, 100.f) / 1e5f * t;
    CHECK(std::abs(length(p - c) - r) < 0.02f);
    // From inside: the far side, t = r.
    REQUIRE(intersect_sphere(c, Vec3(0.f, 1.f, 0.f), c, r, 0.f, 1e30f, t));
    CHECK(t == Approx(1.f));
    // Interval limits.
    CHECK_FALSE(intersect_sphere(Vec3(0.f), Vec3(1.f, 0.f, 0.f), c, r, 0.f, 1e4f, t));
    REQUIRE(intersect_sphere(Vec3(0.f), Vec3(1.f, 0.f, 0.f), c, r, 99999.5f, 1e30f, t));
    CHECK(std::abs(t - (1e5f + 1.f)) <= kFarTol);
}
