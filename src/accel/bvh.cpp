#include "candela/accel/bvh.h"

#include "bvh_kernels.h"
#include "bvh_layout.h"

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
#include <chrono>
#include <cstddef>
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
/// Ranges of at least 2 kBinSamples primitives bin only every k-th one (k = size /
/// kBinSamples, rounded down): the SAH of a split of a large range is estimated well by a few
/// hundred centroids, and binning every primitive at each level would dominate the build.
/// Measured against 2048 (bench_bvh --build-only): the tree's SAH cost changes by under 1 %
/// either way on CBbunny and spheres of 1e5 and 1e6 triangles. Smaller ranges bin fully, and
/// their children's boxes then come from the bins (Builder::split).
constexpr std::uint32_t kBinSamples = 512;
/// Subtrees with fewer primitives than this are built serially (a TBB task costs about as
/// much as binning a few thousand primitives).
constexpr std::uint32_t kParallelMinPrims = 8192;
/// Ranges of at most this many primitives (two leaves' worth) are split first when a node
/// collapses its binary subtree into kBvhWidth children.
constexpr std::uint32_t kSmallChildPrims = 2 * kBvhMaxLeafPrims;

using bvh_detail::kLeafFloats;
using bvh_detail::kMaxPrims;
using bvh_detail::kSahMaxDepth;
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

/// Lane `a` (0..3) of v.
inline float lane(__m128 v, int a) {
    alignas(16) float f[4];
    _mm_store_ps(f, v);
    return f[a];
}

/// Maps floats to unsigned integers of the same order (-0 just below +0).
inline std::uint32_t float_order(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float order_float(std::uint32_t k) {
    const std::uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

/// The smallest float t with (t - cmin) * scale >= limit, each operation rounded once as in
/// the binning, for scale > 0, cmin < cmax and (cmax - cmin) * scale >= limit > 0. Since the
/// rounded expression does not decrease with t, it is < limit exactly when c < t. Found by
/// a galloping search from the real-valued estimate, then bisection in float order.
inline float split_threshold(float cmin, float scale, float limit, float cmax) {
    const __m128 cm = _mm_set_ss(cmin), sc = _mm_set_ss(scale), li = _mm_set_ss(limit);
    auto below = [&](std::uint32_t k) { // (f - cmin) * scale < limit for f = order_float(k)
        const __m128 x = _mm_mul_ss(_mm_sub_ss(_mm_set_ss(order_float(k)), cm), sc);
        return _mm_comilt_ss(x, li) != 0;
    };
    const std::uint32_t kmin = float_order(cmin), kmax = float_order(cmax);
    std::uint32_t k = float_order(cmin + limit / scale);
    k = std::min(std::max(k, kmin), kmax);
    // Invariant once bracketed: below(lo) and !below(hi), lo < hi.
    std::uint32_t lo, hi;
    if (below(k)) {
        lo = k;
        std::uint32_t step = 1;
        for (;;) {
            // below(kmax) is false by the precondition; the guard only rules out an endless
            // loop should rounding ever break it.
            if (lo == kmax) return std::numeric_limits<float>::infinity();
            hi = kmax - lo > step ? lo + step : kmax;
            if (!below(hi)) break;
            lo = hi;
            step *= 2;
        }
    } else {
        hi = k;
        if (hi == kmin) return order_float(hi);
        std::uint32_t step = 1;
        for (;;) {
            lo = hi - kmin > step ? hi - step : kmin;
            if (below(lo) || lo == kmin) break;
            hi = lo;
            step *= 2;
        }
        if (!below(lo)) return order_float(lo);
    }
    while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (below(mid))
            lo = mid;
        else
            hi = mid;
    }
    return order_float(hi);
}

/// Half the surface area of box [lo, hi] (only the ratio of areas matters to the SAH), computed
/// in registers: e.x e.y + e.y e.z + e.z e.x, the products and sums in that order.
inline float half_area(__m128 lo, __m128 hi) {
    const __m128 e = _mm_sub_ps(hi, lo);
    const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));
    const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(1, 1, 1, 1)));
    return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(p, p)));
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
    /// Branch-free where the data decides: the sort ranks every key against every other, and
    /// the two sides' boxes come from the sweeps' prefix and suffix boxes.
    void sweep_split(const Range& r, const float* ext, Range& left, Range& right) {
        const __m128 m = xyz_mask();
        int ax = 0;
        if (ext[1] > ext[ax]) ax = 1;
        if (ext[2] > ext[ax]) ax = 2;
        const std::uint32_t n = r.size();
        BuildPrim* p = prims + r.begin;
        // Sort keys: the centroid coordinate as an order-preserving unsigned integer, with its
        // top bit flipped so that SSE2's signed compare orders it. A primitive's rank is the
        // number of smaller keys plus the number of equal keys before it (ties keep range
        // order), counted four keys at a time. Unused slots hold the largest key, which no
        // finite centroid reaches.
        static_assert(kSweepMaxPrims % 4 == 0, "keys are compared four at a time");
        alignas(16) std::int32_t key[kSweepMaxPrims];
        __m128 lo[kSweepMaxPrims], hi[kSweepMaxPrims];
        for (std::uint32_t i = 0; i < n; ++i) {
            lo[i] = _mm_and_ps(p[i].lo, m);
            hi[i] = _mm_and_ps(p[i].hi, m);
            alignas(16) float c[4];
            _mm_store_ps(c, _mm_add_ps(lo[i], hi[i]));
            // + 0.f turns -0 into +0: they compare equal as floats, so must as keys.
            key[i] = static_cast<std::int32_t>(float_order(c[ax] + 0.f) ^ 0x80000000u);
        }
        const std::uint32_t groups = (n + 3) / 4;
        for (std::uint32_t i = n; i < 4 * groups; ++i)
            key[i] = std::numeric_limits<std::int32_t>::max();
        BuildPrim sorted[kSweepMaxPrims];
        __m128 slo[kSweepMaxPrims], shi[kSweepMaxPrims];
        for (std::uint32_t i = 0; i < n; ++i) {
            const __m128i ki = _mm_set1_epi32(key[i]);
            const __m128i ii = _mm_set1_epi32(static_cast<int>(i));
            __m128i pos = _mm_setr_epi32(0, 1, 2, 3);
            __m128i count = _mm_setzero_si128();
            for (std::uint32_t q = 0; q < groups; ++q) {
                const __m128i kq = _mm_load_si128(reinterpret_cast<const __m128i*>(key + 4 * q));
                const __m128i before =
                    _mm_or_si128(_mm_cmplt_epi32(kq, ki),
                                 _mm_and_si128(_mm_cmpeq_epi32(kq, ki), _mm_cmplt_epi32(pos, ii)));
                count = _mm_sub_epi32(count, before); // a true lane is -1
                pos = _mm_add_epi32(pos, _mm_set1_epi32(4));
            }
            count = _mm_add_epi32(count, _mm_shuffle_epi32(count, _MM_SHUFFLE(1, 0, 3, 2)));
            count = _mm_add_epi32(count, _mm_shuffle_epi32(count, _MM_SHUFFLE(2, 3, 0, 1)));
            const auto rank = static_cast<std::uint32_t>(_mm_cvtsi128_si32(count));
            sorted[rank] = p[i];
            slo[rank] = lo[i];
            shi[rank] = hi[i];
        }
        const float inf = std::numeric_limits<float>::infinity();
        // suffix[i]: box and centroid box of sorted[i, n).
        __m128 suf_lo[kSweepMaxPrims], suf_hi[kSweepMaxPrims];
        __m128 suf_clo[kSweepMaxPrims], suf_chi[kSweepMaxPrims];
        float right_cost[kSweepMaxPrims];
        __m128 blo = _mm_set1_ps(inf), bhi = _mm_set1_ps(-inf), clo = blo, chi = bhi;
        for (std::uint32_t i = n - 1; i > 0; --i) {
            const __m128 c = _mm_add_ps(slo[i], shi[i]);
            blo = _mm_min_ps(blo, slo[i]);
            bhi = _mm_max_ps(bhi, shi[i]);
            clo = _mm_min_ps(clo, c);
            chi = _mm_max_ps(chi, c);
            suf_lo[i] = blo;
            suf_hi[i] = bhi;
            suf_clo[i] = clo;
            suf_chi[i] = chi;
            right_cost[i] = half_area(blo, bhi) * blocks(n - i);
        }
        blo = _mm_set1_ps(inf);
        bhi = _mm_set1_ps(-inf);
        clo = blo;
        chi = bhi;
        std::uint32_t best = n / 2;
        float best_cost = inf;
        __m128 best_lo = blo, best_hi = bhi, best_clo = clo, best_chi = chi;
        for (std::uint32_t i = 1; i < n; ++i) {
            const __m128 c = _mm_add_ps(slo[i - 1], shi[i - 1]);
            blo = _mm_min_ps(blo, slo[i - 1]);
            bhi = _mm_max_ps(bhi, shi[i - 1]);
            clo = _mm_min_ps(clo, c);
            chi = _mm_max_ps(chi, c);
            const float cost = half_area(blo, bhi) * blocks(i) + right_cost[i];
            if (cost < best_cost) {
                best_cost = cost;
                best = i;
                best_lo = blo;
                best_hi = bhi;
                best_clo = clo;
                best_chi = chi;
            }
        }
        for (std::uint32_t i = 0; i < n; ++i)
            p[i] = sorted[i];
        left.begin = r.begin;
        left.end = right.begin = r.begin + best;
        right.end = r.end;
        left.lo = best_lo;
        left.hi = best_hi;
        left.clo = best_clo;
        left.chi = best_chi;
        right.lo = suf_lo[best];
        right.hi = suf_hi[best];
        right.clo = suf_clo[best];
        right.chi = suf_chi[best];
    }

    /// Splits r at the index median (both halves keep their order).
    void median_split(const Range& r, Range& left, Range& right) const {
        left.begin = r.begin;
        left.end = right.begin = r.begin + r.size() / 2;
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
            median_split(r, left, right);
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
        // A bin's primitive count rides in the w lane of its upper bound (as a float, exact
        // below 2^24, far above the at most 2 kBinSamples primitives binned per range), so
        // one vector update per axis replaces a separate counter.
        __m128 bin_lo[2][3][kBins], bin_hi[2][3][kBins];
        const __m128 empty_lo = _mm_set1_ps(inf);
        const __m128 empty_hi = _mm_set_ps(0.f, -inf, -inf, -inf);
        // Small ranges (kFewBins) bin into one set: there clearing and merging a second set
        // would cost more than the chained updates it avoids.
        const int sets = nb == kBins ? 2 : 1;
        for (int s = 0; s < sets; ++s)
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < nb; ++k) {
                    bin_lo[s][a][k] = empty_lo;
                    bin_hi[s][a][k] = empty_hi;
                }
        const __m128 one_w = _mm_set_ps(1.f, 0.f, 0.f, 0.f);
        const std::uint32_t stride = std::max(1u, r.size() / kBinSamples);
        auto bin_one = [&](int s, std::uint32_t i) {
            const __m128 lo = _mm_and_ps(prims[i].lo, m), hi = _mm_and_ps(prims[i].hi, m);
            const __m128i b = bin_of(_mm_add_ps(lo, hi));
            const int b0 = _mm_cvtsi128_si32(b);
            const int b1 = _mm_cvtsi128_si32(_mm_shuffle_epi32(b, _MM_SHUFFLE(1, 1, 1, 1)));
            const int b2 = _mm_cvtsi128_si32(_mm_shuffle_epi32(b, _MM_SHUFFLE(2, 2, 2, 2)));
            bin_lo[s][0][b0] = _mm_min_ps(bin_lo[s][0][b0], lo);
            bin_hi[s][0][b0] = _mm_add_ps(_mm_max_ps(bin_hi[s][0][b0], hi), one_w);
            bin_lo[s][1][b1] = _mm_min_ps(bin_lo[s][1][b1], lo);
            bin_hi[s][1][b1] = _mm_add_ps(_mm_max_ps(bin_hi[s][1][b1], hi), one_w);
            bin_lo[s][2][b2] = _mm_min_ps(bin_lo[s][2][b2], lo);
            bin_hi[s][2][b2] = _mm_add_ps(_mm_max_ps(bin_hi[s][2][b2], hi), one_w);
        };
        std::uint32_t i0 = r.begin;
        if (sets == 2) {
            for (; i0 + stride < r.end; i0 += 2 * stride) {
                bin_one(0, i0);
                bin_one(1, i0 + stride);
            }
            if (i0 < r.end) bin_one(0, i0);
        } else {
            for (; i0 < r.end; ++i0)
                bin_one(0, i0);
        }

        std::uint32_t bin_n[3][kBins];
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < nb; ++k) {
                const __m128 h0 = bin_hi[0][a][k], h1 = sets == 2 ? bin_hi[1][a][k] : empty_hi;
                const float count = _mm_cvtss_f32(_mm_shuffle_ps(h0, h0, _MM_SHUFFLE(3, 3, 3, 3))) +
                                    _mm_cvtss_f32(_mm_shuffle_ps(h1, h1, _MM_SHUFFLE(3, 3, 3, 3)));
                bin_n[a][k] = static_cast<std::uint32_t>(count);
                if (sets == 2) bin_lo[0][a][k] = _mm_min_ps(bin_lo[0][a][k], bin_lo[1][a][k]);
                bin_hi[0][a][k] = _mm_and_ps(_mm_max_ps(h0, h1), m);
            }
        // SAH of every bin boundary on the three axes at once: lane a of each vector belongs
        // to axis a. The bins' boxes are transposed so that one vector holds one coordinate of
        // the three axes' boxes; per lane the arithmetic is half_area's and the cost's, in the
        // same order, so the choice is the one a scalar sweep over the axes would make.
        __m128 lox[kBins], loy[kBins], loz[kBins], hix[kBins], hiy[kBins], hiz[kBins];
        __m128i cnt[kBins];
        // Column k of the three axes' bins, as one vector per coordinate.
        auto transpose = [](const __m128(&bins)[3][kBins], int k, __m128& x, __m128& y, __m128& z) {
            __m128 b0 = bins[0][k], b1 = bins[1][k], b2 = bins[2][k], b3 = _mm_setzero_ps();
            _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
            x = b0;
            y = b1;
            z = b2;
        };
        for (int k = 0; k < nb; ++k) {
            transpose(bin_lo[0], k, lox[k], loy[k], loz[k]);
            transpose(bin_hi[0], k, hix[k], hiy[k], hiz[k]);
            cnt[k] = _mm_setr_epi32(static_cast<int>(bin_n[0][k]), static_cast<int>(bin_n[1][k]),
                                    static_cast<int>(bin_n[2][k]), 0);
        }
        // The union of a run of bins on each axis, and its primitive counts.
        struct SoaBox {
            __m128 x0, y0, z0, x1, y1, z1;
            __m128i n;
        };
        auto grow = [&](SoaBox& b, int k) {
            b.x0 = _mm_min_ps(b.x0, lox[k]);
            b.y0 = _mm_min_ps(b.y0, loy[k]);
            b.z0 = _mm_min_ps(b.z0, loz[k]);
            b.x1 = _mm_max_ps(b.x1, hix[k]);
            b.y1 = _mm_max_ps(b.y1, hiy[k]);
            b.z1 = _mm_max_ps(b.z1, hiz[k]);
            b.n = _mm_add_epi32(b.n, cnt[k]);
        };
        auto areas = [](const SoaBox& b) {
            const __m128 ex = _mm_sub_ps(b.x1, b.x0), ey = _mm_sub_ps(b.y1, b.y0),
                         ez = _mm_sub_ps(b.z1, b.z0);
            return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)),
                              _mm_mul_ps(ez, ex));
        };
        auto blocks_v = [](__m128i n) { // blocks(n) per lane
            return _mm_cvtepi32_ps(_mm_srli_epi32(_mm_add_epi32(n, _mm_set1_epi32(3)), 2));
        };
        const __m128 pinf = _mm_set1_ps(inf), ninf = _mm_set1_ps(-inf);
        const __m128i zero_i = _mm_setzero_si128();
        const SoaBox empty_box{pinf, pinf, pinf, ninf, ninf, ninf, zero_i};
        __m128 right_area[kBins];
        __m128i right_n[kBins];
        SoaBox right_box = empty_box;
        for (int k = nb - 1; k > 0; --k) {
            grow(right_box, k);
            right_area[k] = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(right_box.n, zero_i)),
                                          areas(right_box));
            right_n[k] = right_box.n;
        }
        // Lanes that may split: axes of positive centroid extent (lane 3 is unused).
        const __m128 axis_ok =
            _mm_cmpgt_ps(_mm_setr_ps(ext[0], ext[1], ext[2], 0.f), _mm_setzero_ps());
        __m128 best_v = pinf;
        __m128i best_k = _mm_set1_epi32(-1);
        SoaBox left_box = empty_box;
        for (int k = 0; k < nb - 1; ++k) {
            grow(left_box, k);
            const __m128 cost = _mm_add_ps(_mm_mul_ps(areas(left_box), blocks_v(left_box.n)),
                                           _mm_mul_ps(right_area[k + 1], blocks_v(right_n[k + 1])));
            const __m128i empty = _mm_or_si128(_mm_cmpeq_epi32(left_box.n, zero_i),
                                               _mm_cmpeq_epi32(right_n[k + 1], zero_i));
            const __m128 better = _mm_and_ps(
                _mm_andnot_ps(_mm_castsi128_ps(empty), _mm_cmplt_ps(cost, best_v)), axis_ok);
            best_v = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_v));
            const __m128i bk = _mm_castps_si128(better);
            best_k =
                _mm_or_si128(_mm_and_si128(bk, _mm_set1_epi32(k)), _mm_andnot_si128(bk, best_k));
        }
        alignas(16) float lane_cost[4];
        alignas(16) std::int32_t lane_k[4];
        _mm_store_ps(lane_cost, best_v);
        _mm_store_si128(reinterpret_cast<__m128i*>(lane_k), best_k);
        int best_axis = -1, best_split = -1;
        float best_cost = inf;
        for (int a = 0; a < 3; ++a)
            if (lane_k[a] >= 0 && lane_cost[a] < best_cost) {
                best_cost = lane_cost[a];
                best_axis = a;
                best_split = lane_k[a];
            }
        // When every primitive was binned, an axis of positive extent has its extreme
        // centroids in bins 0 and nb - 1, so a split with both sides non-empty exists; a
        // sample of a large range may miss the extremes and see them all in one bin.
        if (best_axis < 0) {
            median_split(r, left, right);
            return;
        }
        const int ax = best_axis;
        // bin_of(c)[ax] <= best_split iff x = (c - clo) * scale < s + 1 (the same two roundings
        // as bin_of; floor(clamp(x, 0, nb - 1)) <= s iff x < s + 1, since s + 1 <= nb - 1).
        // x is a non-decreasing function of c, so this holds exactly for c below a threshold
        // t: the partition compares c against t alone, keeping its loop in registers.
        const float t = split_threshold(lane(cmin, ax), sc[ax], static_cast<float>(best_split + 1),
                                        lane(r.chi, ax));
        if (stride == 1) {
            // Every primitive was binned, so the bins on each side of the split hold the two
            // boxes exactly, and the partition only accumulates the centroid boxes.
            partition<false>(r, ax, t, left, right);
            left.lo = right.lo = _mm_set1_ps(inf);
            left.hi = right.hi = _mm_set1_ps(-inf);
            for (int k = 0; k < nb; ++k) {
                Range& side = k <= best_split ? left : right;
                side.lo = _mm_min_ps(side.lo, bin_lo[0][ax][k]);
                side.hi = _mm_max_ps(side.hi, bin_hi[0][ax][k]);
            }
        } else {
            // The bins saw only a sample: the partition accumulates the boxes too.
            partition<true>(r, ax, t, left, right);
        }
    }

    /// Hoare partition of r: primitives whose doubled centroid along axis ax is below t go
    /// first. Sets left and right to the two parts with their centroid boxes and, when
    /// kBoxes, their boxes, accumulated on the way.
    template <bool kBoxes>
    void partition(const Range& r, int ax, float t, Range& left, Range& right) {
        const __m128 m = xyz_mask();
        const float inf = std::numeric_limits<float>::infinity();
        const __m128 t_v = _mm_set1_ps(t);
        auto goes_left = [&](__m128 c) {
            return ((_mm_movemask_ps(_mm_cmplt_ps(c, t_v)) >> ax) & 1) != 0;
        };
        __m128 lclo = _mm_set1_ps(inf), lchi = _mm_set1_ps(-inf);
        __m128 rclo = lclo, rchi = lchi;
        __m128 llo = lclo, lhi = lchi, rlo = lclo, rhi = lchi;
        std::uint32_t i = r.begin, j = r.end;
        for (;;) {
            while (i < j) {
                const __m128 lo = _mm_and_ps(prims[i].lo, m), hi = _mm_and_ps(prims[i].hi, m);
                const __m128 c = _mm_add_ps(lo, hi);
                if (!goes_left(c)) break;
                if (kBoxes) {
                    llo = _mm_min_ps(llo, lo);
                    lhi = _mm_max_ps(lhi, hi);
                }
                lclo = _mm_min_ps(lclo, c);
                lchi = _mm_max_ps(lchi, c);
                ++i;
            }
            while (i < j) {
                const __m128 lo = _mm_and_ps(prims[j - 1].lo, m),
                             hi = _mm_and_ps(prims[j - 1].hi, m);
                const __m128 c = _mm_add_ps(lo, hi);
                if (goes_left(c)) break;
                if (kBoxes) {
                    rlo = _mm_min_ps(rlo, lo);
                    rhi = _mm_max_ps(rhi, hi);
                }
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
    /// splittable children (small ones first, then by surface area) until there are
    /// kBvhWidth, then recurses into inner children.
    /// Leaves and inner levels of a subtree, returned up the recursion, so parallel subtrees
    /// share no counters.
    struct SubtreeStats {
        std::size_t leaves = 0;
        int depth = 0; ///< levels of inner nodes down to the deepest one
    };

    SubtreeStats build(std::uint32_t index, const Range& r, int depth) {
        // The traversal stack is sized for kBvhMaxDepth inner nodes on a path (bvh_layout.h
        // shows that no tree is deeper); a deeper one would overflow it.
        if (depth > bvh_detail::kBvhMaxDepth)
            throw Error(ErrorKind::Internal, "builtin BVH: the tree exceeds its maximum depth");
        Range child[kBvhWidth];
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
            split(child[pick], left, right);
            child[pick] = left;
            area[pick] = half_area(left.lo, left.hi);
            child[n] = right;
            area[n++] = half_area(right.lo, right.hi);
        }
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
    const auto start = std::chrono::steady_clock::now();
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
        build_seconds_ =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
        builder.range_bounds(root);
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
    build_seconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace candela
