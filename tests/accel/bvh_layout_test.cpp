#include "candela/accel/brute.h"
#include "candela/accel/bvh.h"
#include "candela/diagnostics/check.h"
#include "candela/scene/procedural.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <limits>
#include <vector>

using namespace candela;

namespace {

/// What a walk of the tree counts.
struct WalkCounts {
    std::size_t fill = 0;   ///< used child slots of inner nodes
    std::size_t leaves = 0; ///< leaves reached
    int depth = 0;          ///< deepest level reached, the root's level being 1
};

/// Walks the subtree of child reference `ref` at level `level`, marking every primitive
/// reference seen in `seen` and growing `box` by the vertices of its triangles (single-mesh
/// scenes only).
void walk(const BvhAccel& bvh, const Mesh& mesh, std::uint32_t ref, std::uint32_t parent, int level,
          std::vector<int>& seen, Bounds3& box, WalkCounts& counts) {
    counts.depth = std::max(counts.depth, level);
    if (ref & kBvhLeafBit) {
        ++counts.leaves;
        const std::uint32_t c = (ref & 7u) + 1;
        REQUIRE(c <= static_cast<std::uint32_t>(kBvhMaxLeafPrims));
        for (std::uint32_t k = 0; k < c; ++k) {
            const std::uint32_t p = bvh.leaf_prim_ref(ref, k);
            REQUIRE(p < seen.size());
            ++seen[p];
            for (int v = 0; v < 3; ++v)
                box.grow(mesh.positions[mesh.indices[3 * p + v]]);
        }
        return;
    }
    // Depth-first layout: an inner node comes after its parent.
    REQUIRE(ref < bvh.nodes().size());
    if (parent != std::numeric_limits<std::uint32_t>::max()) REQUIRE(ref > parent);
    const Bvh8Node& node = bvh.nodes()[ref];
    const float inf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < kBvhWidth; ++k) {
        const bool empty = node.bounds[0][0][k] == inf;
        if (empty) {
            // Unused slots: lo = +inf, hi = -inf on every axis, so that no ray enters them.
            for (int a = 0; a < 3; ++a) {
                CHECK(node.bounds[a][0][k] == inf);
                CHECK(node.bounds[a][1][k] == -inf);
            }
            continue;
        }
        ++counts.fill;
        Bounds3 sub;
        walk(bvh, mesh, node.child[k], ref, level + 1, seen, sub, counts);
        // The stored box is the exact box of the child's primitives.
        for (int a = 0; a < 3; ++a) {
            CHECK(node.bounds[a][0][k] == sub.lo[a]);
            CHECK(node.bounds[a][1][k] == sub.hi[a]);
        }
        box.grow(sub.lo);
        box.grow(sub.hi);
    }
}

} // namespace

TEST_CASE("BVH8 layout: every triangle in one leaf, exact child boxes, depth-first nodes",
          "[accel][quick]") {
    for (const char* spec : {"sphere:20000", "soup:3000:7", "sphere:50", "sphere:2"}) {
        const Scene scene = make_procedural_scene(spec);
        REQUIRE(scene.meshes.size() == 1);
        const Mesh& mesh = scene.meshes[0];
        for (int threads : {1, 0}) {
            const BvhAccel bvh(scene, TriangleTest::MollerTrumbore, threads);
            std::vector<int> seen(mesh.triangle_count(), 0);
            Bounds3 box;
            WalkCounts counts;
            walk(bvh, mesh, bvh.root(), std::numeric_limits<std::uint32_t>::max(), 1, seen, box,
                 counts);
            const std::size_t fill = counts.fill;
            // The statistics the build reports are the tree's.
            CHECK(bvh.leaf_count() == counts.leaves);
            CHECK(bvh.depth() == counts.depth);
            for (std::size_t i = 0; i < seen.size(); ++i)
                REQUIRE(seen[i] == 1);
            CHECK(box.lo == bvh.bounds().lo);
            CHECK(box.hi == bvh.bounds().hi);
            if (!bvh.nodes().empty()) {
                // Every inner node but a root over few primitives has at least two children.
                CHECK(fill + 1 >= 2 * bvh.nodes().size());
            }
            INFO(spec << ": " << bvh.nodes().size() << " nodes, " << bvh.leaf_count() << " leaves, "
                      << fill << " children");
            CHECK(bvh.memory_bytes() <= 64 * mesh.triangle_count() + 256);
        }
    }
}

TEST_CASE("BVH8: the tree does not depend on the number of build threads", "[accel][quick]") {
    // Large enough for the parallel build to split its top levels into tasks.
    for (const char* spec : {"sphere:60000", "soup:40000:3"}) {
        const Scene scene = make_procedural_scene(spec);
        const BvhAccel serial(scene, TriangleTest::MollerTrumbore, 1);
        const BvhAccel parallel(scene, TriangleTest::MollerTrumbore, 0);
        INFO(spec);
        REQUIRE(serial.nodes().size() == parallel.nodes().size());
        CHECK(serial.root() == parallel.root());
        CHECK(std::memcmp(serial.nodes().data(), parallel.nodes().data(),
                          serial.nodes().size() * sizeof(Bvh8Node)) == 0);
        CHECK(serial.leaf_count() == parallel.leaf_count());
        CHECK(serial.depth() == parallel.depth());
        // Same leaves, primitive by primitive.
        std::size_t compared = 0;
        for (const Bvh8Node& n : serial.nodes())
            for (int k = 0; k < kBvhWidth; ++k)
                if (n.child[k] & kBvhLeafBit) {
                    for (std::uint32_t p = 0; p <= (n.child[k] & 7u); ++p) {
                        CHECK(serial.leaf_prim_ref(n.child[k], p) ==
                              parallel.leaf_prim_ref(n.child[k], p));
                        ++compared;
                    }
                }
        CHECK(compared == scene.triangle_count());
    }
}

TEST_CASE("SSE2 and AVX2 traversals of the BVH8 give identical answers", "[accel][quick]") {
    if (!bvh_cpu_has_avx2()) {
        const Scene scene = make_procedural_scene("sphere:500");
        CHECK_THROWS_AS(BvhAccel(scene, TriangleTest::MollerTrumbore, 1, BvhIsa::Avx2), Error);
        CHECK(BvhAccel(scene, TriangleTest::MollerTrumbore, 1).isa() == BvhIsa::Sse2);
        return;
    }
    const Scene scenes[] = {make_procedural_scene("sphere:20000"),
                            make_procedural_scene("soup:2000:3"),
                            make_procedural_scene("spheres:200")};
    for (const Scene& scene : scenes) {
        for (TriangleTest test : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
            const BvhAccel sse(scene, test, 1, BvhIsa::Sse2);
            const BvhAccel avx(scene, test, 1, BvhIsa::Avx2);
            const BruteAccel brute(scene, test);
            REQUIRE(sse.isa() == BvhIsa::Sse2);
            REQUIRE(avx.isa() == BvhIsa::Avx2);
            CHECK(BvhAccel(scene, test, 1).isa() == BvhIsa::Avx2);
            std::vector<Ray> rays = make_bounce_rays(scene, 3000, 11);
            for (const auto& extra :
                 {make_shadow_rays(scene, 3000, 11), make_edge_rays(scene, 2000, 11)})
                rays.insert(rays.end(), extra.begin(), extra.end());
            std::size_t hits = 0;
            for (const Ray& r : rays) {
                const auto a = sse.intersect(r), b = avx.intersect(r), c = brute.intersect(r);
                REQUIRE(a.has_value() == b.has_value());
                REQUIRE(a.has_value() == c.has_value());
                REQUIRE(sse.occluded(r) == a.has_value());
                REQUIRE(avx.occluded(r) == a.has_value());
                if (!a) continue;
                ++hits;
                // Same tree, same kernels but for the box test's width: bit-identical hits.
                REQUIRE(a->prim_id == b->prim_id);
                REQUIRE(a->geom_id == b->geom_id);
                REQUIRE(a->t == b->t);
                REQUIRE(a->u == b->u);
                REQUIRE(a->v == b->v);
                // Against brute force: the same t (the primitive may differ on ties).
                if (a->geom_id == c->geom_id && a->prim_id == c->prim_id)
                    REQUIRE(a->t == c->t);
                else
                    REQUIRE(std::abs(a->t - c->t) <= kTieRelTolerance * std::abs(c->t));
            }
            INFO(scene.source << ": " << hits << " hits of " << rays.size());
            CHECK(hits > rays.size() / 10);
        }
    }
}
