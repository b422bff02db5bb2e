#include "candela/accel/bvh.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <emmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/concurrent_vector.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <limits>

namespace candela {

namespace {

// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007):
// 16 centroid bins per axis, which Wald reports within a few percent of the full sweep SAH.
constexpr int kBins = 16;
/// Small ranges (at most kFewBinsMaxPrims primitives) use kFewBins bins: there the fixed cost of
/// clearing and sweeping 16 bins per axis outweighs binning itself, and a handful of
/// primitives has few distinct split positions anyway.
constexpr int kFewBins = 8;
constexpr std::uint32_t kFewBinsMaxPrims = 48;
/// Ranges of at most this many primitives are split by an exact SAH sweep over the sorted
/// centroids of one axis instead of binning (see Builder::sweep_split).
constexpr std::uint32_t kSweepMaxPrims = 16;
/// Ranges larger than this bin only every k-th primitive (k = size / kBinSamples, rounded
/// down): the SAH of a split of a huge range is estimated well by a few thousand centroids,
/// and binning the full range at each of the top levels would dominate the build.
constexpr std::uint32_t kBinSamples = 8192;
/// Past this many binary split levels the build switches to index-median splits, which halve
/// the range, so the depth stays below kSahMaxDepth + 32 for any primitive count < 2^32.
constexpr int kSahMaxDepth = 64;
constexpr int kMaxDepth = kSahMaxDepth + 32;
/// Each inner node pushes at most three children, once per level.
constexpr int kStackSize = 3 * kMaxDepth + 4;
/// Subtrees with fewer primitives than this are built serially (a TBB task costs about as
/// much as binning a few thousand primitives).
constexpr std::uint32_t kParallelMinPrims = 8192;
/// Leaf references pack the first primitive in 28 bits.
constexpr std::uint32_t kMaxPrims = 1u << 28;

/// Floats per primitive in the leaf data: 9 vertex coordinates and the reference.
constexpr std::size_t kLeafFloats = 10;
/// pbrt-v4's conservative slab test: scaling the far distance by 1 + 2 gamma(n) covers the
/// n roundings of (bound - o) * inv_d, so no box is missed by a ray that hits its content.
/// The traversal folds the scale into the inverse direction used for far planes, which adds a
/// fourth rounding, hence gamma(4).
constexpr float kSlabFarScale = 1.f + 2.f * float_gamma(4);
/// Sphere boxes are padded by this relative amount of |c| + r: the float root-finder may place
/// a grazing hit a few ulps outside the exact box.
constexpr float kSphereBoxPad = float_gamma(8);

/// Build-time record of one primitive: its box, with the scene-wide reference in lo.w and the
/// mesh index in hi.w (as bit patterns; masked off before any arithmetic).
struct BuildPrim {
    __m128 lo, hi;
};

inline __m128 xyz_mask() {
    return _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
}
inline std::uint32_t lane_bits(__m128 v, int lane) {
    alignas(16) std::uint32_t a[4];
    _mm_store_ps(reinterpret_cast<float*>(a), v);
    return a[lane];
}

/// Half the surface area of box [lo, hi] (only the ratio of areas matters to the SAH).
inline float half_area(__m128 lo, __m128 hi) {
    alignas(16) float e[4];
    _mm_store_ps(e, _mm_sub_ps(hi, lo));
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}

/// SAH cost of n primitives: leaves are tested four at a time.
inline float blocks(std::uint32_t n) {
    return static_cast<float>((n + 3) >> 2);
}

/// A primitive range with its box and the box of its doubled centroids (lo + hi).
struct Range {
    std::uint32_t begin = 0, end = 0;
    int depth = 0; ///< binary split levels above this range
    __m128 lo, hi, clo, chi;
    std::uint32_t size() const { return end - begin; }
};

struct Builder {
    BuildPrim* prims;
    float* leaf_data;
    const Scene& scene;
    const std::vector<std::uint32_t>& mesh_first_ref;
    std::uint32_t sphere_first_ref;
    bool parallel;
    tbb::concurrent_vector<Bvh4Node> nodes;
    std::atomic<std::size_t> leaves{0};
    std::atomic<int> max_depth{0};

    /// Writes the leaf data of [begin, begin + c) and returns its child reference.
    std::uint32_t make_leaf(std::uint32_t begin, std::uint32_t c) {
        leaves.fetch_add(1, std::memory_order_relaxed);
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
            for (int v = 0; v < 3; ++v)
                for (int a = 0; a < 3; ++a)
                    base[(3 * v + a) * c + k] = p[v][a];
            std::memcpy(base + 9 * c + k, &ref, sizeof ref);
        }
        return kBvhLeafBit | (begin << 3) | (c - 1);
    }

    /// Bounds of prims[begin, end) and of their doubled centroids.
    void range_bounds(Range& r) const {
        const __m128 m = xyz_mask();
        __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
        __m128 hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());
        __m128 clo = lo, chi = hi;
        for (std::uint32_t i = r.begin; i < r.end; ++i) {
            const __m128 a = _mm_and_ps(prims[i].lo, m), b = _mm_and_ps(prims[i].hi, m);
            const __m128 c = _mm_add_ps(a, b);
            lo = _mm_min_ps(lo, a);
            hi = _mm_max_ps(hi, b);
            clo = _mm_min_ps(clo, c);
            chi = _mm_max_ps(chi, c);
        }
        r.lo = _mm_and_ps(lo, m);
        r.hi = _mm_and_ps(hi, m);
        r.clo = _mm_and_ps(clo, m);
        r.chi = _mm_and_ps(chi, m);
    }

    /// Exact SAH split of a small range along the axis of largest centroid extent `ext`
    /// (which must be positive): sorts the range by centroid and sweeps all n - 1 positions.
    /// For a handful of primitives this is cheaper than clearing and sweeping bins on 3 axes.
    void sweep_split(const Range& r, const float* ext, Range& left, Range& right) {
        const __m128 m = xyz_mask();
        int ax = 0;
        if (ext[1] > ext[ax]) ax = 1;
        if (ext[2] > ext[ax]) ax = 2;
        const std::uint32_t n = r.size();
        BuildPrim* p = prims + r.begin;
        float key[kSweepMaxPrims];
        for (std::uint32_t i = 0; i < n; ++i) {
            alignas(16) float c[4];
            _mm_store_ps(c, _mm_add_ps(_mm_and_ps(p[i].lo, m), _mm_and_ps(p[i].hi, m)));
            const float k = c[ax];
            const BuildPrim e = p[i];
            std::uint32_t j = i;
            for (; j > 0 && key[j - 1] > k; --j) {
                key[j] = key[j - 1];
                p[j] = p[j - 1];
            }
            key[j] = k;
            p[j] = e;
        }
        const float inf = std::numeric_limits<float>::infinity();
        float right_cost[kSweepMaxPrims];
        __m128 lo = _mm_set1_ps(inf), hi = _mm_set1_ps(-inf);
        for (std::uint32_t i = n - 1; i > 0; --i) {
            lo = _mm_min_ps(lo, _mm_and_ps(p[i].lo, m));
            hi = _mm_max_ps(hi, _mm_and_ps(p[i].hi, m));
            right_cost[i] = half_area(lo, hi) * blocks(n - i);
        }
        lo = _mm_set1_ps(inf);
        hi = _mm_set1_ps(-inf);
        std::uint32_t best = n / 2;
        float best_cost = inf;
        for (std::uint32_t i = 1; i < n; ++i) {
            lo = _mm_min_ps(lo, _mm_and_ps(p[i - 1].lo, m));
            hi = _mm_max_ps(hi, _mm_and_ps(p[i - 1].hi, m));
            const float cost = half_area(lo, hi) * blocks(i) + right_cost[i];
            if (cost < best_cost) {
                best_cost = cost;
                best = i;
            }
        }
        left.begin = r.begin;
        left.end = right.begin = r.begin + best;
        right.end = r.end;
        range_bounds(left);
        range_bounds(right);
    }

    /// Splits r (more than kBvhMaxLeafPrims primitives) in two non-empty ranges, partitioning
    /// prims in place: by binned SAH on the doubled centroids, or at the index median when the
    /// centroids coincide or the tree is too deep.
    void split(const Range& r, Range& left, Range& right) {
        const __m128 m = xyz_mask();
        alignas(16) float ext[4];
        _mm_store_ps(ext, _mm_sub_ps(r.chi, r.clo));
        const bool flat = !(ext[0] > 0.f) && !(ext[1] > 0.f) && !(ext[2] > 0.f);
        left.depth = right.depth = r.depth + 1;
        if (flat || r.depth >= kSahMaxDepth) {
            left.begin = r.begin;
            left.end = right.begin = r.begin + r.size() / 2;
            right.end = r.end;
            range_bounds(left);
            range_bounds(right);
            return;
        }
        if (r.size() <= kSweepMaxPrims) {
            sweep_split(r, ext, left, right);
            return;
        }
        // Bin index per axis: floor((c - clo) * kBins / extent), clamped; axes of zero extent
        // map to bin 0 and are skipped by the sweep.
        const int nb = r.size() <= kFewBinsMaxPrims ? kFewBins : kBins;
        alignas(16) float sc[4];
        for (int a = 0; a < 3; ++a)
            sc[a] = ext[a] > 0.f ? static_cast<float>(nb) / ext[a] : 0.f;
        sc[3] = 0.f;
        const __m128 scale = _mm_load_ps(sc);
        const __m128 cmin = r.clo;
        const __m128 top = _mm_set1_ps(static_cast<float>(nb - 1));
        const __m128 zero = _mm_setzero_ps();
        auto bin_of = [&](__m128 c) {
            return _mm_cvttps_epi32(
                _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, cmin), scale), zero), top));
        };
        const float inf = std::numeric_limits<float>::infinity();
        // Two sets of bins, for alternate primitives: consecutive primitives often fall in the
        // same bin, and one set would chain their read-modify-write updates through memory.
        __m128 bin_lo[2][3][kBins], bin_hi[2][3][kBins];
        std::uint32_t bin_n[2][3][kBins];
        for (int s = 0; s < 2; ++s)
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < nb; ++k) {
                    bin_n[s][a][k] = 0;
                    bin_lo[s][a][k] = _mm_set1_ps(inf);
                    bin_hi[s][a][k] = _mm_set1_ps(-inf);
                }
        const std::uint32_t stride = std::max(1u, r.size() / kBinSamples);
        auto bin_one = [&](int s, std::uint32_t i) {
            const __m128 lo = _mm_and_ps(prims[i].lo, m), hi = _mm_and_ps(prims[i].hi, m);
            alignas(16) std::int32_t b[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(b), bin_of(_mm_add_ps(lo, hi)));
            for (int a = 0; a < 3; ++a) {
                bin_lo[s][a][b[a]] = _mm_min_ps(bin_lo[s][a][b[a]], lo);
                bin_hi[s][a][b[a]] = _mm_max_ps(bin_hi[s][a][b[a]], hi);
                ++bin_n[s][a][b[a]];
            }
        };
        std::uint32_t i0 = r.begin;
        for (; i0 + stride < r.end; i0 += 2 * stride) {
            bin_one(0, i0);
            bin_one(1, i0 + stride);
        }
        if (i0 < r.end) bin_one(0, i0);
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < nb; ++k) {
                bin_lo[0][a][k] = _mm_min_ps(bin_lo[0][a][k], bin_lo[1][a][k]);
                bin_hi[0][a][k] = _mm_max_ps(bin_hi[0][a][k], bin_hi[1][a][k]);
                bin_n[0][a][k] += bin_n[1][a][k];
            }
        int best_axis = -1, best_split = -1;
        float best_cost = inf;
        for (int a = 0; a < 3; ++a) {
            if (!(ext[a] > 0.f)) continue;
            float right_area[kBins];
            std::uint32_t right_n[kBins];
            __m128 lo = _mm_set1_ps(inf), hi = _mm_set1_ps(-inf);
            std::uint32_t n = 0;
            for (int k = nb - 1; k > 0; --k) {
                lo = _mm_min_ps(lo, bin_lo[0][a][k]);
                hi = _mm_max_ps(hi, bin_hi[0][a][k]);
                n += bin_n[0][a][k];
                right_area[k] = n ? half_area(lo, hi) : 0.f;
                right_n[k] = n;
            }
            lo = _mm_set1_ps(inf);
            hi = _mm_set1_ps(-inf);
            n = 0;
            for (int k = 0; k < nb - 1; ++k) {
                lo = _mm_min_ps(lo, bin_lo[0][a][k]);
                hi = _mm_max_ps(hi, bin_hi[0][a][k]);
                n += bin_n[0][a][k];
                if (n == 0 || right_n[k + 1] == 0) continue;
                const float cost =
                    half_area(lo, hi) * blocks(n) + right_area[k + 1] * blocks(right_n[k + 1]);
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = a;
                    best_split = k;
                }
            }
        }
        // An axis of positive extent has its extreme centroids in bins 0 and nb - 1, so a
        // split with both sides non-empty always exists.
        const int ax = best_axis;
        // bin_of(c)[ax] <= best_split, as one scalar compare: with x = (c - clo) * scale (the
        // same two roundings as bin_of), floor(clamp(x, 0, nb - 1)) <= s iff x < s + 1, since
        // s + 1 <= nb - 1.
        alignas(16) float cmin_a[4];
        _mm_store_ps(cmin_a, cmin);
        const float cmin_ax = cmin_a[ax], scale_ax = sc[ax];
        const float limit = static_cast<float>(best_split + 1);
        auto goes_left = [&](__m128 c) {
            alignas(16) float cc[4];
            _mm_store_ps(cc, c);
            return (cc[ax] - cmin_ax) * scale_ax < limit;
        };
        // Hoare partition, accumulating the boxes and centroid boxes of both sides on the way
        // (the bins may have seen only a sample).
        __m128 lclo = _mm_set1_ps(inf), lchi = _mm_set1_ps(-inf);
        __m128 rclo = lclo, rchi = lchi;
        __m128 llo = lclo, lhi = lchi, rlo = lclo, rhi = lchi;
        std::uint32_t i = r.begin, j = r.end;
        for (;;) {
            while (i < j) {
                const __m128 lo = _mm_and_ps(prims[i].lo, m), hi = _mm_and_ps(prims[i].hi, m);
                const __m128 c = _mm_add_ps(lo, hi);
                if (!goes_left(c)) break;
                llo = _mm_min_ps(llo, lo);
                lhi = _mm_max_ps(lhi, hi);
                lclo = _mm_min_ps(lclo, c);
                lchi = _mm_max_ps(lchi, c);
                ++i;
            }
            while (i < j) {
                const __m128 lo = _mm_and_ps(prims[j - 1].lo, m),
                             hi = _mm_and_ps(prims[j - 1].hi, m);
                const __m128 c = _mm_add_ps(lo, hi);
                if (goes_left(c)) break;
                rlo = _mm_min_ps(rlo, lo);
                rhi = _mm_max_ps(rhi, hi);
                rclo = _mm_min_ps(rclo, c);
                rchi = _mm_max_ps(rchi, c);
                --j;
            }
            if (i >= j) break;
            std::swap(prims[i], prims[j - 1]);
        }
        left.begin = r.begin;
        left.end = right.begin = i;
        right.end = r.end;
        left.lo = llo;
        left.hi = lhi;
        left.clo = lclo;
        left.chi = lchi;
        right.lo = rlo;
        right.hi = rhi;
        right.clo = rclo;
        right.chi = rchi;
    }

    /// Fills node `index` for range r (more than kBvhMaxLeafPrims primitives): splits the
    /// largest splittable child until there are four, then recurses into inner children.
    void build(std::uint32_t index, const Range& r, int depth) {
        int seen = max_depth.load(std::memory_order_relaxed);
        while (depth > seen && !max_depth.compare_exchange_weak(seen, depth)) {
        }
        Range child[4];
        child[0] = r;
        int n = 1;
        while (n < 4) {
            int pick = -1;
            float pick_area = -1.f;
            for (int k = 0; k < n; ++k) {
                if (child[k].size() <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) continue;
                const float a = half_area(child[k].lo, child[k].hi);
                if (a > pick_area) {
                    pick_area = a;
                    pick = k;
                }
            }
            if (pick < 0) break;
            Range left, right;
            split(child[pick], left, right);
            child[pick] = left;
            child[n++] = right;
        }
        Bvh4Node node;
        const float inf = std::numeric_limits<float>::infinity();
        std::uint32_t inner[4];
        for (int k = 0; k < 4; ++k) {
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
            } else {
                const auto it = nodes.grow_by(1);
                node.child[k] = inner[k] = static_cast<std::uint32_t>(it - nodes.begin());
            }
        }
        for (std::uint32_t& p : node.pad)
            p = 0;
        nodes[index] = node;
        auto recurse = [&](int k) {
            if (inner[k]) build(inner[k], child[k], depth + 1);
        };
        if (parallel && r.size() >= kParallelMinPrims)
            tbb::parallel_for(0, n, recurse);
        else
            for (int k = 0; k < n; ++k)
                recurse(k);
    }
};

/// Copies the subtree of `src` into `out` in depth-first order and returns its new index.
std::uint32_t linearize(const tbb::concurrent_vector<Bvh4Node>& in, std::uint32_t src,
                        std::vector<Bvh4Node>& out) {
    const auto dst = static_cast<std::uint32_t>(out.size());
    out.push_back(in[src]);
    for (int k = 0; k < 4; ++k) {
        const std::uint32_t c = in[src].child[k];
        if (!(c & kBvhLeafBit) && c != 0) {
            const std::uint32_t nc = linearize(in, c, out);
            out[dst].child[k] = nc;
        }
    }
    return dst;
}

} // namespace

BvhAccel::BvhAccel(const Scene& scene, TriangleTest test, int build_threads)
    : scene_(scene), test_(test) {
    const auto start = std::chrono::steady_clock::now();
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
    leaf_data_.assign(kLeafFloats * n + 4, 0.f);
    if (n == 0) {
        build_seconds_ =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return;
    }

    std::vector<BuildPrim> info(n);
    auto fill = [&](std::uint32_t lo, std::uint32_t hi) {
        for (std::uint32_t r = lo; r < hi; ++r) {
            Bounds3 b;
            std::uint32_t g = 0;
            if (r >= sphere_first_ref_) {
                const Sphere& s = scene.spheres[r - sphere_first_ref_];
                const Vec3 pad((max_component(vabs(s.center)) + s.radius) * kSphereBoxPad);
                b.grow(s.center - Vec3(s.radius) - pad);
                b.grow(s.center + Vec3(s.radius) + pad);
            } else {
                g = static_cast<std::uint32_t>(
                    std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), r) -
                    mesh_first_ref_.begin() - 1);
                const Mesh& m = scene.meshes[g];
                const std::uint32_t j = r - mesh_first_ref_[g];
                for (int k = 0; k < 3; ++k)
                    b.grow(m.positions[m.indices[3 * j + k]]);
            }
            float ref_bits, g_bits;
            std::memcpy(&ref_bits, &r, sizeof r);
            std::memcpy(&g_bits, &g, sizeof g);
            info[r].lo = _mm_set_ps(ref_bits, b.lo.z, b.lo.y, b.lo.x);
            info[r].hi = _mm_set_ps(g_bits, b.hi.z, b.hi.y, b.hi.x);
        }
    };
    const bool parallel = build_threads != 1;
    Builder builder{
        info.data(), leaf_data_.data(), scene, mesh_first_ref_, sphere_first_ref_, parallel, {}, {},
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
        builder.range_bounds(root);
        alignas(16) float lo[4], hi[4];
        _mm_store_ps(lo, root.lo);
        _mm_store_ps(hi, root.hi);
        bounds_ = Bounds3{Vec3(lo[0], lo[1], lo[2]), Vec3(hi[0], hi[1], hi[2])};
        if (n <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) {
            root_ = builder.make_leaf(0, n);
            builder.max_depth = 1;
        } else {
            builder.nodes.grow_by(1);
            builder.build(0, root, 1);
            builder.max_depth.fetch_add(1); // the leaf level
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
    leaf_count_ = builder.leaves.load();
    depth_ = builder.max_depth.load();
    build_seconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Hit BvhAccel::decode(std::uint32_t ref, float t, float u, float v) const {
    if (ref >= sphere_first_ref_)
        return Hit{t, 0.f, 0.f, scene_.sphere_geom_id(), ref - sphere_first_ref_};
    const std::size_t g = std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), ref) -
                          mesh_first_ref_.begin() - 1;
    return Hit{t, u, v, static_cast<std::uint32_t>(g), ref - mesh_first_ref_[g]};
}

template <TriangleTest kTest, bool kSpheres, bool kAnyHit>
bool BvhAccel::trace(const Ray& ray, Hit& hit) const {
    if (prim_count_ == 0) return false;
    const Vec3 inv(1.f / ray.d.x, 1.f / ray.d.y, 1.f / ray.d.z);
    const __m128 ox = _mm_set1_ps(ray.o.x), oy = _mm_set1_ps(ray.o.y), oz = _mm_set1_ps(ray.o.z);
    const __m128 dx = _mm_set1_ps(ray.d.x), dy = _mm_set1_ps(ray.d.y), dz = _mm_set1_ps(ray.d.z);
    const __m128 ix = _mm_set1_ps(inv.x), iy = _mm_set1_ps(inv.y), iz = _mm_set1_ps(inv.z);
    const __m128 fix = _mm_set1_ps(inv.x * kSlabFarScale), fiy = _mm_set1_ps(inv.y * kSlabFarScale),
                 fiz = _mm_set1_ps(inv.z * kSlabFarScale);
    // Offsets (in floats) of the near and far planes of axis a in a node: a * 8 + (0 or 4).
    const int nx = inv.x < 0.f ? 4 : 0, ny = (inv.y < 0.f ? 4 : 0) + 8,
              nz = (inv.z < 0.f ? 4 : 0) + 16;
    const int fx = nx ^ 4, fy = ny ^ 4, fz = nz ^ 4;
    WatertightRay wr;
    if (kTest == TriangleTest::Watertight) wr = make_watertight_ray(ray.d);
    const float tmin = ray.tmin;
    float tmax = ray.tmax;
    const __m128 vtmin = _mm_set1_ps(tmin);
    __m128 vtmax = _mm_set1_ps(tmax);
    const __m128 one = _mm_set1_ps(1.f), zero = _mm_setzero_ps();

    const float* best_base = nullptr;
    std::uint32_t best_c = 0, best_lane = 0;
    float best_u = 0.f, best_v = 0.f;

    // Stack of (child reference, box entry distance); entries beyond the closest hit found
    // meanwhile are dropped when popped.
    struct Entry {
        std::uint32_t ref;
        float t;
    };
    Entry stack[kStackSize];
    // Children the ray enters are fetched early: their loads overlap the work on siblings.
    auto prefetch_child = [this](std::uint32_t c) {
        const char* p = (c & kBvhLeafBit)
                            ? reinterpret_cast<const char*>(leaf_data_.data() +
                                                            kLeafFloats * ((c & ~kBvhLeafBit) >> 3))
                            : reinterpret_cast<const char*>(&nodes_[c]);
        _mm_prefetch(p, _MM_HINT_T0);
        _mm_prefetch(p + 64, _MM_HINT_T0);
    };
    int sp = 0;
    std::uint32_t ref = root_;
    for (;;) {
        if (!(ref & kBvhLeafBit)) {
            const float* b = nodes_[ref].bounds[0][0];
            const __m128 tnx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + nx), ox), ix);
            const __m128 tny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + ny), oy), iy);
            const __m128 tnz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + nz), oz), iz);
            const __m128 tfx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + fx), ox), fix);
            const __m128 tfy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + fy), oy), fiy);
            const __m128 tfz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + fz), oz), fiz);
            // max_ps / min_ps return their second operand when either is NaN, so a NaN slab
            // distance (0 * inf) leaves the interval unchanged.
            const __m128 tnear = _mm_max_ps(tnz, _mm_max_ps(tny, _mm_max_ps(tnx, vtmin)));
            const __m128 tfar = _mm_min_ps(tfz, _mm_min_ps(tfy, _mm_min_ps(tfx, vtmax)));
            unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(tnear, tfar)));
            if (mask != 0) {
                const std::uint32_t* child = nodes_[ref].child;
                alignas(16) float tn[4];
                _mm_store_ps(tn, tnear);
                const unsigned k0 = static_cast<unsigned>(__builtin_ctz(mask));
                mask &= mask - 1;
                if (mask == 0) {
                    ref = child[k0];
                    continue;
                }
                const unsigned k1 = static_cast<unsigned>(__builtin_ctz(mask));
                mask &= mask - 1;
                prefetch_child(child[k0]);
                prefetch_child(child[k1]);
                if (mask == 0) {
                    if (tn[k0] <= tn[k1]) {
                        stack[sp++] = Entry{child[k1], tn[k1]};
                        ref = child[k0];
                    } else {
                        stack[sp++] = Entry{child[k0], tn[k0]};
                        ref = child[k1];
                    }
                    continue;
                }
                // Three or four children: push them all, sort the pushed entries so that the
                // nearest is on top, and continue with it.
                const int first = sp;
                stack[sp++] = Entry{child[k0], tn[k0]};
                stack[sp++] = Entry{child[k1], tn[k1]};
                while (mask) {
                    const unsigned k = static_cast<unsigned>(__builtin_ctz(mask));
                    mask &= mask - 1;
                    prefetch_child(child[k]);
                    stack[sp++] = Entry{child[k], tn[k]};
                }
                for (int i = first + 1; i < sp && !kAnyHit; ++i) {
                    const Entry e = stack[i];
                    int j = i;
                    while (j > first && stack[j - 1].t < e.t) {
                        stack[j] = stack[j - 1];
                        --j;
                    }
                    stack[j] = e;
                }
                ref = stack[--sp].ref;
                continue;
            }
        } else {
            const std::uint32_t c = (ref & 7u) + 1;
            const float* base = leaf_data_.data() + kLeafFloats * ((ref & ~kBvhLeafBit) >> 3);
            unsigned sphere_mask = 0;
            if (kSpheres) {
                const __m128i refs =
                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(base + 9 * c));
                const __m128i first =
                    _mm_set1_epi32(static_cast<std::int32_t>(sphere_first_ref_) - 1);
                sphere_mask = static_cast<unsigned>(
                                  _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(refs, first)))) &
                              ((1u << c) - 1);
            }
            if (kTest == TriangleTest::MollerTrumbore) {
                // Four Moller-Trumbore tests with exactly the operations (and their order) of
                // intersect_triangle_mt, so t, u and v are bit-identical to the scalar test.
                const __m128 p0x = _mm_loadu_ps(base), p0y = _mm_loadu_ps(base + c),
                             p0z = _mm_loadu_ps(base + 2 * c);
                const __m128 e1x = _mm_sub_ps(_mm_loadu_ps(base + 3 * c), p0x);
                const __m128 e1y = _mm_sub_ps(_mm_loadu_ps(base + 4 * c), p0y);
                const __m128 e1z = _mm_sub_ps(_mm_loadu_ps(base + 5 * c), p0z);
                const __m128 e2x = _mm_sub_ps(_mm_loadu_ps(base + 6 * c), p0x);
                const __m128 e2y = _mm_sub_ps(_mm_loadu_ps(base + 7 * c), p0y);
                const __m128 e2z = _mm_sub_ps(_mm_loadu_ps(base + 8 * c), p0z);
                // pvec = cross(d, e2)
                const __m128 px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(dz, e2y));
                const __m128 py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(dx, e2z));
                const __m128 pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(dy, e2x));
                const __m128 det = _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)),
                                              _mm_mul_ps(e1z, pz));
                const __m128 inv_det = _mm_div_ps(one, det);
                const __m128 tx = _mm_sub_ps(ox, p0x), ty = _mm_sub_ps(oy, p0y),
                             tz = _mm_sub_ps(oz, p0z);
                const __m128 u =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(tx, px), _mm_mul_ps(ty, py)),
                                          _mm_mul_ps(tz, pz)),
                               inv_det);
                // qvec = cross(tvec, e1)
                const __m128 qx = _mm_sub_ps(_mm_mul_ps(ty, e1z), _mm_mul_ps(tz, e1y));
                const __m128 qy = _mm_sub_ps(_mm_mul_ps(tz, e1x), _mm_mul_ps(tx, e1z));
                const __m128 qz = _mm_sub_ps(_mm_mul_ps(tx, e1y), _mm_mul_ps(ty, e1x));
                const __m128 v =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)),
                                          _mm_mul_ps(dz, qz)),
                               inv_det);
                const __m128 t =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)),
                                          _mm_mul_ps(e2z, qz)),
                               inv_det);
                __m128 ok = _mm_cmpneq_ps(det, zero);
                ok = _mm_and_ps(ok, _mm_cmpge_ps(u, zero));
                ok = _mm_and_ps(ok, _mm_cmple_ps(u, one));
                ok = _mm_and_ps(ok, _mm_cmpge_ps(v, zero));
                ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_add_ps(u, v), one));
                ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, vtmin));
                ok = _mm_and_ps(ok, _mm_cmple_ps(t, vtmax));
                unsigned hits =
                    static_cast<unsigned>(_mm_movemask_ps(ok)) & ((1u << c) - 1) & ~sphere_mask;
                if (hits) {
                    if (kAnyHit) return true;
                    alignas(16) float ts[4], us[4], vs[4];
                    _mm_store_ps(ts, t);
                    _mm_store_ps(us, u);
                    _mm_store_ps(vs, v);
                    // In lane order with t <= tmax, as the scalar loop would accept them.
                    while (hits) {
                        const unsigned k = static_cast<unsigned>(__builtin_ctz(hits));
                        hits &= hits - 1;
                        if (ts[k] <= tmax) {
                            tmax = ts[k];
                            best_base = base;
                            best_c = c;
                            best_lane = k;
                            best_u = us[k];
                            best_v = vs[k];
                        }
                    }
                    vtmax = _mm_set1_ps(tmax);
                }
            } else {
                for (std::uint32_t k = 0; k < c; ++k) {
                    if (kSpheres && (sphere_mask >> k) & 1u) continue;
                    const Vec3 p0(base[k], base[c + k], base[2 * c + k]);
                    const Vec3 p1(base[3 * c + k], base[4 * c + k], base[5 * c + k]);
                    const Vec3 p2(base[6 * c + k], base[7 * c + k], base[8 * c + k]);
                    TriangleHit th;
                    if (!intersect_triangle_watertight(ray.o, wr, p0, p1, p2, tmin, tmax, th))
                        continue;
                    if (kAnyHit) return true;
                    tmax = th.t;
                    best_base = base;
                    best_c = c;
                    best_lane = k;
                    best_u = th.u;
                    best_v = th.v;
                }
                vtmax = _mm_set1_ps(tmax);
            }
            if (kSpheres && sphere_mask) {
                for (std::uint32_t k = 0; k < c; ++k) {
                    if (!((sphere_mask >> k) & 1u)) continue;
                    const Vec3 center(base[k], base[c + k], base[2 * c + k]);
                    float t;
                    if (!intersect_sphere(ray.o, ray.d, center, base[3 * c + k], tmin, tmax, t))
                        continue;
                    if (kAnyHit) return true;
                    tmax = t;
                    best_base = base;
                    best_c = c;
                    best_lane = k;
                    best_u = best_v = 0.f;
                }
                vtmax = _mm_set1_ps(tmax);
            }
        }
        // Pop the next node that still begins before the closest hit so far.
        while (sp > 0 && stack[sp - 1].t > tmax)
            --sp;
        if (sp == 0) break;
        ref = stack[--sp].ref;
    }
    if (!best_base) return false;
    std::uint32_t best_ref;
    std::memcpy(&best_ref, best_base + 9 * best_c + best_lane, sizeof best_ref);
    hit = decode(best_ref, tmax, best_u, best_v);
    return true;
}

std::optional<Hit> BvhAccel::intersect(const Ray& ray) const {
    if (!is_valid_ray(ray)) return std::nullopt;
    Hit hit;
    const bool spheres = !scene_.spheres.empty();
    bool found;
    if (test_ == TriangleTest::Watertight)
        found = spheres ? trace<TriangleTest::Watertight, true, false>(ray, hit)
                        : trace<TriangleTest::Watertight, false, false>(ray, hit);
    else
        found = spheres ? trace<TriangleTest::MollerTrumbore, true, false>(ray, hit)
                        : trace<TriangleTest::MollerTrumbore, false, false>(ray, hit);
    if (!found) return std::nullopt;
    return hit;
}

bool BvhAccel::occluded(const Ray& ray) const {
    if (!is_valid_ray(ray)) return false;
    Hit hit;
    const bool spheres = !scene_.spheres.empty();
    if (test_ == TriangleTest::Watertight)
        return spheres ? trace<TriangleTest::Watertight, true, true>(ray, hit)
                       : trace<TriangleTest::Watertight, false, true>(ray, hit);
    return spheres ? trace<TriangleTest::MollerTrumbore, true, true>(ray, hit)
                   : trace<TriangleTest::MollerTrumbore, false, true>(ray, hit);
}

Bounds3 BvhAccel::bounds() const {
    return bounds_;
}

std::size_t BvhAccel::memory_bytes() const {
    return nodes_.capacity() * sizeof(Bvh4Node) + leaf_data_.capacity() * sizeof(float) +
           mesh_first_ref_.capacity() * sizeof(std::uint32_t);
}

} // namespace candela
