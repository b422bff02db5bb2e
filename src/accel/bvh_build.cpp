// The builtin BVH's build: BvhAccel's constructor numbers the primitives, computes their
// boxes, and builds the 8-wide tree top down, each node collapsing the binary splits of its
// range (bvh_split.cpp) into up to kBvhWidth children, in parallel TBB tasks for large
// subtrees; the nodes are then laid out depth first.
#include "bvh_build.h"
#include "bvh_layout.h"

#include "candela/accel/bvh.h"
#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <emmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/concurrent_vector.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>

namespace candela {

namespace {

/// Subtrees with fewer primitives than this are built serially (a TBB task costs about as
/// much as binning a few thousand primitives).
constexpr std::uint32_t kParallelMinPrims = 8192;
/// Ranges of at most this many primitives (two leaves' worth) are split first when a node
/// collapses its binary subtree into kBvhWidth children.
constexpr std::uint32_t kSmallChildPrims = 2 * kBvhMaxLeafPrims;

using bvh_detail::BuildPrim;
using bvh_detail::half_area;
using bvh_detail::kLeafFloats;
using bvh_detail::kMaxPrims;
using bvh_detail::lane_bits;
using bvh_detail::Range;
using bvh_detail::range_bounds;
using bvh_detail::split_range;
using bvh_detail::xyz_mask;

/// Sphere boxes are padded by this relative amount of |c| + r: the float root-finder may place
/// a grazing hit a few ulps outside the exact box.
constexpr float kSphereBoxPad = float_gamma(8);

struct Builder {
    BuildPrim* prims;
    float* leaf_data;
    const Scene& scene;
    const std::vector<std::uint32_t>& mesh_first_ref;
    std::uint32_t sphere_first_ref;
    bool parallel;
    bool edges; ///< store p0, e1, e2 (Moller-Trumbore) instead of p0, p1, p2
    tbb::concurrent_vector<Bvh8Node> nodes;

    /// Writes the leaf data of [begin, begin + c) and returns its child reference.
    std::uint32_t make_leaf(std::uint32_t begin, std::uint32_t c) {
        float* base = leaf_data + kLeafFloats * begin;
        for (std::uint32_t k = 0; k < c; ++k) {
            const std::uint32_t ref = lane_bits(prims[begin + k].lo, 3);
            Vec3 p[3];
            if (ref >= sphere_first_ref) {
                const Sphere& s = scene.spheres[ref - sphere_first_ref];
                p[0] = s.center;
                p[1] = Vec3(s.radius, 0.f, 0.f);
                p[2] = Vec3(0.f);
            } else {
                const std::uint32_t g = lane_bits(prims[begin + k].hi, 3);
                const Mesh& m = scene.meshes[g];
                const std::uint32_t j = ref - mesh_first_ref[g];
                for (int v = 0; v < 3; ++v)
                    p[v] = m.positions[m.indices[3 * j + v]];
            }
            if (edges && ref < sphere_first_ref) {
                p[1] = p[1] - p[0];
                p[2] = p[2] - p[0];
            }
            for (int v = 0; v < 3; ++v)
                for (int a = 0; a < 3; ++a)
                    base[(3 * v + a) * c + k] = p[v][a];
            std::memcpy(base + 9 * c + k, &ref, sizeof ref);
        }
        return kBvhLeafBit | (begin << 3) | (c - 1);
    }

    /// Leaves and inner levels of a subtree, returned up the recursion, so parallel subtrees
    /// share no counters.
    struct SubtreeStats {
        std::size_t leaves = 0;
        int depth = 0; ///< levels of inner nodes down to the deepest one
    };

    /// Splits r (more than kBvhMaxLeafPrims primitives) into the children of one node: splits
    /// the splittable children (small ones first, then by surface area) until there are
    /// kBvhWidth or none is left to split. Returns how many children `child` holds.
    int collapse(const Range& r, Range (&child)[kBvhWidth]) {
        float area[kBvhWidth]; ///< half_area of each child's box, computed once
        child[0] = r;
        area[0] = half_area(r.lo, r.hi);
        int n = 1;
        while (n < kBvhWidth) {
            // Children of at most kSmallChildPrims primitives go first: left unsplit they
            // would become inner nodes of two or three leaves, most of their slots empty.
            // Among the rest, the largest surface area goes first (the usual collapse).
            int pick = -1;
            bool pick_small = false;
            float pick_area = -1.f;
            for (int k = 0; k < n; ++k) {
                const std::uint32_t s = child[k].size();
                if (s <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) continue;
                const bool small = s <= kSmallChildPrims;
                const float a = area[k];
                if ((small && !pick_small) || (small == pick_small && a > pick_area)) {
                    pick_area = a;
                    pick_small = small;
                    pick = k;
                }
            }
            if (pick < 0) break;
            Range left, right;
            split_range(prims, child[pick], left, right);
            child[pick] = left;
            area[pick] = half_area(left.lo, left.hi);
            child[n] = right;
            area[n++] = half_area(right.lo, right.hi);
        }
        return n;
    }

    /// Fills node `index`, at inner level `depth` (the root's is 1), for range r (more than
    /// kBvhMaxLeafPrims primitives): collapses r into its children, writes their leaves and
    /// the node, then builds the inner children's subtrees.
    SubtreeStats build(std::uint32_t index, const Range& r, int depth) {
        // The traversal stack is sized for kBvhMaxDepth inner nodes on a path (bvh_layout.h
        // shows that no tree is deeper); a deeper one would overflow it.
        if (depth > bvh_detail::kBvhMaxDepth)
            throw Error(ErrorKind::Internal, "builtin BVH: the tree exceeds its maximum depth");
        Range child[kBvhWidth];
        const int n = collapse(r, child);
        Bvh8Node node;
        const float inf = std::numeric_limits<float>::infinity();
        // The inner children's nodes are allocated together: one atomic step of the vector.
        std::uint32_t next = 0, inner_count = 0;
        for (int k = 0; k < n; ++k)
            inner_count += child[k].size() > static_cast<std::uint32_t>(kBvhMaxLeafPrims);
        if (inner_count)
            next = static_cast<std::uint32_t>(nodes.grow_by(inner_count) - nodes.begin());
        SubtreeStats stats{0, depth};
        std::uint32_t inner[kBvhWidth];
        for (int k = 0; k < kBvhWidth; ++k) {
            inner[k] = 0;
            if (k >= n) {
                for (int a = 0; a < 3; ++a) {
                    node.bounds[a][0][k] = inf;
                    node.bounds[a][1][k] = -inf;
                }
                node.child[k] = 0;
                continue;
            }
            alignas(16) float lo[4], hi[4];
            _mm_store_ps(lo, child[k].lo);
            _mm_store_ps(hi, child[k].hi);
            for (int a = 0; a < 3; ++a) {
                node.bounds[a][0][k] = lo[a];
                node.bounds[a][1][k] = hi[a];
            }
            if (child[k].size() <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) {
                node.child[k] = make_leaf(child[k].begin, child[k].size());
                ++stats.leaves;
            } else {
                node.child[k] = inner[k] = next++;
            }
        }
        for (std::uint32_t& p : node.pad)
            p = 0;
        nodes[index] = node;
        SubtreeStats sub[kBvhWidth];
        auto recurse = [&](int k) {
            if (inner[k]) sub[k] = build(inner[k], child[k], depth + 1);
        };
        if (parallel && r.size() >= kParallelMinPrims)
            tbb::parallel_for(0, n, recurse);
        else
            for (int k = 0; k < n; ++k)
                recurse(k);
        for (int k = 0; k < n; ++k) {
            stats.leaves += sub[k].leaves;
            stats.depth = std::max(stats.depth, sub[k].depth);
        }
        return stats;
    }
};

/// Copies the subtree of `src` into `out` in depth-first order and returns its new index.
std::uint32_t linearize(const tbb::concurrent_vector<Bvh8Node>& in, std::uint32_t src,
                        BvhVector<Bvh8Node>& out) {
    const auto dst = static_cast<std::uint32_t>(out.size());
    out.push_back(in[src]);
    for (int k = 0; k < kBvhWidth; ++k) {
        const std::uint32_t c = in[src].child[k];
        if (!(c & kBvhLeafBit) && c != 0) {
            const std::uint32_t nc = linearize(in, c, out);
            out[dst].child[k] = nc;
        }
    }
    return dst;
}

} // namespace

BvhAccel::BvhAccel(const Scene& scene, TriangleTest test, int build_threads, BvhIsa isa)
    : scene_(scene), test_(test) {
    const Stopwatch timer;
    select_kernels(isa);
    // Scene-wide primitive numbering: triangles of mesh 0, mesh 1, ..., then spheres.
    mesh_first_ref_.resize(scene.meshes.size() + 1);
    std::uint64_t total = 0;
    for (std::size_t g = 0; g < scene.meshes.size(); ++g) {
        mesh_first_ref_[g] = static_cast<std::uint32_t>(total);
        total += scene.meshes[g].triangle_count();
    }
    mesh_first_ref_.back() = static_cast<std::uint32_t>(total);
    sphere_first_ref_ = static_cast<std::uint32_t>(total);
    total += scene.spheres.size();
    if (total >= kMaxPrims)
        throw Error(ErrorKind::Scene,
                    "builtin BVH: too many primitives (" + std::to_string(total) + ")");
    const auto n = static_cast<std::uint32_t>(total);
    prim_count_ = n;
    // Every leaf float is written by make_leaf; only the spare tail is cleared here.
    leaf_data_.resize(kLeafFloats * static_cast<std::size_t>(n) + 4);
    std::fill(leaf_data_.end() - 4, leaf_data_.end(), 0.f);
    if (n == 0) {
        build_seconds_ = timer.seconds();
        return;
    }

    BvhVector<BuildPrim> info(n);
    // Boxes of the primitives with refs in [lo, hi), vertex by vertex in registers, mesh by mesh.
    auto fill = [&](std::uint32_t lo, std::uint32_t hi) {
        const __m128 m = xyz_mask();
        auto vertex = [](const Vec3& p) { return _mm_setr_ps(p.x, p.y, p.z, 0.f); };
        auto tagged = [&](__m128 v, std::uint32_t tag) {
            return _mm_or_ps(_mm_and_ps(v, m),
                             _mm_castsi128_ps(_mm_set_epi32(static_cast<int>(tag), 0, 0, 0)));
        };
        std::uint32_t r = lo;
        if (r < sphere_first_ref_) {
            auto g = static_cast<std::uint32_t>(
                std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), r) -
                mesh_first_ref_.begin() - 1);
            for (; r < std::min(hi, sphere_first_ref_); ++g) {
                const Mesh& mesh = scene.meshes[g];
                const std::uint32_t end = std::min(hi, mesh_first_ref_[g + 1]);
                const std::uint32_t* idx = mesh.indices.data() + 3 * (r - mesh_first_ref_[g]);
                for (; r < end; ++r, idx += 3) {
                    const __m128 a = vertex(mesh.positions[idx[0]]);
                    const __m128 b = vertex(mesh.positions[idx[1]]);
                    const __m128 c = vertex(mesh.positions[idx[2]]);
                    info[r].lo = tagged(_mm_min_ps(_mm_min_ps(a, b), c), r);
                    info[r].hi = tagged(_mm_max_ps(_mm_max_ps(a, b), c), g);
                }
            }
        }
        for (; r < hi; ++r) {
            const Bounds3 box =
                padded_sphere_box(scene.spheres[r - sphere_first_ref_], kSphereBoxPad);
            info[r].lo = tagged(vertex(box.lo), r);
            info[r].hi = tagged(vertex(box.hi), 0);
        }
    };
    const bool parallel = build_threads != 1;
    Builder builder{info.data(),
                    leaf_data_.data(),
                    scene,
                    mesh_first_ref_,
                    sphere_first_ref_,
                    parallel,
                    test == TriangleTest::MollerTrumbore,
                    {}};
    auto run = [&] {
        if (parallel)
            tbb::parallel_for(
                tbb::blocked_range<std::uint32_t>(0, n, 4096),
                [&](const tbb::blocked_range<std::uint32_t>& r) { fill(r.begin(), r.end()); });
        else
            fill(0, n);
        Range root;
        root.begin = 0;
        root.end = n;
        range_bounds(info.data(), root);
        alignas(16) float lo[4], hi[4];
        _mm_store_ps(lo, root.lo);
        _mm_store_ps(hi, root.hi);
        bounds_ = Bounds3{Vec3(lo[0], lo[1], lo[2]), Vec3(hi[0], hi[1], hi[2])};
        if (n <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) {
            root_ = builder.make_leaf(0, n);
            leaf_count_ = 1;
            depth_ = 1;
        } else {
            builder.nodes.grow_by(1);
            const Builder::SubtreeStats stats = builder.build(0, root, 1);
            leaf_count_ = stats.leaves;
            depth_ = stats.depth + 1; // the leaf level
        }
    };
    if (parallel) {
        tbb::task_arena arena(build_threads > 0 ? build_threads : tbb::task_arena::automatic);
        arena.execute(run);
    } else {
        run();
    }
    if (!builder.nodes.empty()) {
        nodes_.reserve(builder.nodes.size());
        root_ = linearize(builder.nodes, 0, nodes_);
    }
    build_seconds_ = timer.seconds();
}

} // namespace candela
