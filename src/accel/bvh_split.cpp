// The binary split of a primitive range in the builtin BVH's build: binned SAH (binning the
// centroids, evaluating the SAH at every bin boundary, choosing the split, partitioning), an
// exact SAH sweep for small ranges, and the index-median fallback.
#include "bvh_build.h"
#include "bvh_layout.h"

#include "candela/accel/bvh.h"

#include <emmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

namespace candela::bvh_detail {

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
/// centroids of one axis instead of binning (see sweep_split).
constexpr std::uint32_t kSweepMaxPrims = 16;
/// Ranges of at least 2 kBinSamples primitives bin only every k-th one (k = size /
/// kBinSamples, rounded down): the SAH of a split of a large range is estimated well by a few
/// hundred centroids, and binning every primitive at each level would dominate the build.
/// Measured against 2048 (bench_bvh --build-only): the tree's SAH cost changes by under 1 %
/// either way on CBbunny and spheres of 1e5 and 1e6 triangles. Smaller ranges bin fully, and
/// their children's boxes then come from the bins (boxes_from_bins).
constexpr std::uint32_t kBinSamples = 512;
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

/// Exact SAH split of a small range along the axis of largest centroid extent `ext`
/// (which must be positive): sorts the range by centroid and sweeps all n - 1 positions.
/// For a handful of primitives this is cheaper than clearing and sweeping bins on 3 axes.
/// Branch-free where the data decides: the sort ranks every key against every other, and
/// the two sides' boxes come from the sweeps' prefix and suffix boxes.
void sweep_split(BuildPrim* prims, const Range& r, const float* ext, Range& left, Range& right) {
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

/// Hoare partition of r: primitives whose doubled centroid along axis ax is below t go
/// first. Sets left and right to the two parts with their centroid boxes and, when
/// kBoxes, their boxes, accumulated on the way.
template <bool kBoxes>
void partition(BuildPrim* prims, const Range& r, int ax, float t, Range& left, Range& right) {
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
            const __m128 lo = _mm_and_ps(prims[j - 1].lo, m), hi = _mm_and_ps(prims[j - 1].hi, m);
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

/// Splits r at the index median (both halves keep their order): the fallback when the
/// centroids coincide, the tree is deep, or the binning found no split.
void median_split(const BuildPrim* prims, const Range& r, Range& left, Range& right) {
    left.begin = r.begin;
    left.end = right.begin = r.begin + r.size() / 2;
    right.end = r.end;
    range_bounds(prims, left);
    range_bounds(prims, right);
}

/// How the doubled centroids of a range map to bins: on each axis,
/// floor((c - clo) * nb / extent), clamped to [0, nb - 1]; axes of zero extent map to bin 0
/// and are never split.
struct BinGrid {
    int nb = kBins;           ///< bins per axis
    alignas(16) float sc[4];  ///< nb / extent per axis (0 for an axis of zero extent), 0 in w
    __m128 cmin, scale, top;  ///< the range's lowest centroid, sc, nb - 1
    std::uint32_t stride = 1; ///< every stride-th primitive is binned
    int sets = 1;             ///< bin sets, alternate primitives going to alternate sets

    __m128i bin_of(__m128 c) const {
        return _mm_cvttps_epi32(
            _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, cmin), scale), _mm_setzero_ps()), top));
    }
};

/// The bin grid of range r, whose centroid extent per axis is ext.
BinGrid make_bin_grid(const Range& r, const float* ext) {
    BinGrid g;
    g.nb = r.size() <= kFewBinsMaxPrims ? kFewBins : kBins;
    for (int a = 0; a < 3; ++a)
        g.sc[a] = ext[a] > 0.f ? static_cast<float>(g.nb) / ext[a] : 0.f;
    g.sc[3] = 0.f;
    g.scale = _mm_load_ps(g.sc);
    g.cmin = r.clo;
    g.top = _mm_set1_ps(static_cast<float>(g.nb - 1));
    g.stride = std::max(1u, r.size() / kBinSamples);
    // Small ranges (kFewBins) bin into one set: there clearing and merging a second set
    // would cost more than the chained updates it avoids.
    g.sets = g.nb == kBins ? 2 : 1;
    return g;
}

/// Per bin set, axis and bin: the box of the primitives binned there. A bin's primitive count
/// rides in the w lane of its upper bound (as a float, exact below 2^24, far above the at most
/// 2 kBinSamples primitives binned per range), so one vector update per axis replaces a
/// separate counter. After merge_bin_sets, set 0 holds the merged boxes and n the counts.
struct Bins {
    __m128 lo[2][3][kBins], hi[2][3][kBins];
    std::uint32_t n[3][kBins];
};

/// An empty bin's upper bound: -inf in x, y and z, a count of 0 in w.
inline __m128 empty_bin_hi() {
    const float inf = std::numeric_limits<float>::infinity();
    return _mm_set_ps(0.f, -inf, -inf, -inf);
}

/// Bins every g.stride-th primitive of r. Two sets of bins take alternate primitives:
/// consecutive primitives often fall in the same bin, and one set would chain their
/// read-modify-write updates through memory.
void bin_centroids(const BuildPrim* prims, const Range& r, const BinGrid& g, Bins& b) {
    const __m128 m = xyz_mask();
    const __m128 empty_lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
    const __m128 empty_hi = empty_bin_hi();
    for (int s = 0; s < g.sets; ++s)
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < g.nb; ++k) {
                b.lo[s][a][k] = empty_lo;
                b.hi[s][a][k] = empty_hi;
            }
    const __m128 one_w = _mm_set_ps(1.f, 0.f, 0.f, 0.f);
    auto bin_one = [&](int s, std::uint32_t i) {
        const __m128 lo = _mm_and_ps(prims[i].lo, m), hi = _mm_and_ps(prims[i].hi, m);
        const __m128i bin = g.bin_of(_mm_add_ps(lo, hi));
        const int b0 = _mm_cvtsi128_si32(bin);
        const int b1 = _mm_cvtsi128_si32(_mm_shuffle_epi32(bin, _MM_SHUFFLE(1, 1, 1, 1)));
        const int b2 = _mm_cvtsi128_si32(_mm_shuffle_epi32(bin, _MM_SHUFFLE(2, 2, 2, 2)));
        b.lo[s][0][b0] = _mm_min_ps(b.lo[s][0][b0], lo);
        b.hi[s][0][b0] = _mm_add_ps(_mm_max_ps(b.hi[s][0][b0], hi), one_w);
        b.lo[s][1][b1] = _mm_min_ps(b.lo[s][1][b1], lo);
        b.hi[s][1][b1] = _mm_add_ps(_mm_max_ps(b.hi[s][1][b1], hi), one_w);
        b.lo[s][2][b2] = _mm_min_ps(b.lo[s][2][b2], lo);
        b.hi[s][2][b2] = _mm_add_ps(_mm_max_ps(b.hi[s][2][b2], hi), one_w);
    };
    const std::uint32_t stride = g.stride;
    std::uint32_t i0 = r.begin;
    if (g.sets == 2) {
        for (; i0 + stride < r.end; i0 += 2 * stride) {
            bin_one(0, i0);
            bin_one(1, i0 + stride);
        }
        if (i0 < r.end) bin_one(0, i0);
    } else {
        for (; i0 < r.end; ++i0)
            bin_one(0, i0);
    }
}

/// Merges the second bin set into the first and takes the counts out of the w lanes.
void merge_bin_sets(const BinGrid& g, Bins& b) {
    const __m128 m = xyz_mask();
    const __m128 empty_hi = empty_bin_hi();
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < g.nb; ++k) {
            const __m128 h0 = b.hi[0][a][k], h1 = g.sets == 2 ? b.hi[1][a][k] : empty_hi;
            const float count = _mm_cvtss_f32(_mm_shuffle_ps(h0, h0, _MM_SHUFFLE(3, 3, 3, 3))) +
                                _mm_cvtss_f32(_mm_shuffle_ps(h1, h1, _MM_SHUFFLE(3, 3, 3, 3)));
            b.n[a][k] = static_cast<std::uint32_t>(count);
            if (g.sets == 2) b.lo[0][a][k] = _mm_min_ps(b.lo[0][a][k], b.lo[1][a][k]);
            b.hi[0][a][k] = _mm_and_ps(_mm_max_ps(h0, h1), m);
        }
}

/// The merged bins transposed: lane a of each vector belongs to axis a, so that one vector
/// holds one coordinate of the three axes' bin k (lane 3 is unused).
struct BinColumns {
    __m128 lox[kBins], loy[kBins], loz[kBins], hix[kBins], hiy[kBins], hiz[kBins];
    __m128i cnt[kBins];
};

void transpose_bins(const BinGrid& g, const Bins& b, BinColumns& col) {
    // Column k of the three axes' bins, as one vector per coordinate.
    auto transpose = [](const __m128(&bins)[3][kBins], int k, __m128& x, __m128& y, __m128& z) {
        __m128 b0 = bins[0][k], b1 = bins[1][k], b2 = bins[2][k], b3 = _mm_setzero_ps();
        _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
        x = b0;
        y = b1;
        z = b2;
    };
    for (int k = 0; k < g.nb; ++k) {
        transpose(b.lo[0], k, col.lox[k], col.loy[k], col.loz[k]);
        transpose(b.hi[0], k, col.hix[k], col.hiy[k], col.hiz[k]);
        col.cnt[k] = _mm_setr_epi32(static_cast<int>(b.n[0][k]), static_cast<int>(b.n[1][k]),
                                    static_cast<int>(b.n[2][k]), 0);
    }
}

/// The union of a run of bins on each axis, and its primitive counts (lane a: axis a).
struct SoaBox {
    __m128 x0, y0, z0, x1, y1, z1;
    __m128i n;
};

inline void grow(SoaBox& b, const BinColumns& col, int k) {
    b.x0 = _mm_min_ps(b.x0, col.lox[k]);
    b.y0 = _mm_min_ps(b.y0, col.loy[k]);
    b.z0 = _mm_min_ps(b.z0, col.loz[k]);
    b.x1 = _mm_max_ps(b.x1, col.hix[k]);
    b.y1 = _mm_max_ps(b.y1, col.hiy[k]);
    b.z1 = _mm_max_ps(b.z1, col.hiz[k]);
    b.n = _mm_add_epi32(b.n, col.cnt[k]);
}

/// half_area per lane, with its operations in its order.
inline __m128 half_areas(const SoaBox& b) {
    const __m128 ex = _mm_sub_ps(b.x1, b.x0), ey = _mm_sub_ps(b.y1, b.y0),
                 ez = _mm_sub_ps(b.z1, b.z0);
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
}

/// blocks(n) per lane.
inline __m128 blocks_v(__m128i n) {
    return _mm_cvtepi32_ps(_mm_srli_epi32(_mm_add_epi32(n, _mm_set1_epi32(3)), 2));
}

/// Per axis, the cheapest split at a bin boundary: its SAH cost, and the last bin on its left
/// (-1 when the axis has no split with both sides non-empty, or zero centroid extent).
struct AxisSplits {
    alignas(16) float cost[4];
    alignas(16) std::int32_t bin[4];
};

/// SAH of every bin boundary on the three axes at once (ext: the centroid extent per axis).
/// Per lane the arithmetic is half_area's and the cost's, in the same order, so the choice is
/// the one a scalar sweep over the axes would make.
AxisSplits evaluate_sah(const BinGrid& g, const BinColumns& col, const float* ext) {
    const int nb = g.nb;
    const float inf = std::numeric_limits<float>::infinity();
    const __m128 pinf = _mm_set1_ps(inf), ninf = _mm_set1_ps(-inf);
    const __m128i zero_i = _mm_setzero_si128();
    const SoaBox empty_box{pinf, pinf, pinf, ninf, ninf, ninf, zero_i};
    // Sweep from the right: the area (0 when empty) and count of bins k.. nb - 1.
    __m128 right_area[kBins];
    __m128i right_n[kBins];
    SoaBox right_box = empty_box;
    for (int k = nb - 1; k > 0; --k) {
        grow(right_box, col, k);
        right_area[k] = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(right_box.n, zero_i)),
                                      half_areas(right_box));
        right_n[k] = right_box.n;
    }
    // Lanes that may split: axes of positive centroid extent (lane 3 is unused).
    const __m128 axis_ok = _mm_cmpgt_ps(_mm_setr_ps(ext[0], ext[1], ext[2], 0.f), _mm_setzero_ps());
    // Sweep from the left, keeping per lane the first cheapest boundary.
    __m128 best_v = pinf;
    __m128i best_k = _mm_set1_epi32(-1);
    SoaBox left_box = empty_box;
    for (int k = 0; k < nb - 1; ++k) {
        grow(left_box, col, k);
        const __m128 cost = _mm_add_ps(_mm_mul_ps(half_areas(left_box), blocks_v(left_box.n)),
                                       _mm_mul_ps(right_area[k + 1], blocks_v(right_n[k + 1])));
        const __m128i empty = _mm_or_si128(_mm_cmpeq_epi32(left_box.n, zero_i),
                                           _mm_cmpeq_epi32(right_n[k + 1], zero_i));
        const __m128 better =
            _mm_and_ps(_mm_andnot_ps(_mm_castsi128_ps(empty), _mm_cmplt_ps(cost, best_v)), axis_ok);
        best_v = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_v));
        const __m128i bk = _mm_castps_si128(better);
        best_k = _mm_or_si128(_mm_and_si128(bk, _mm_set1_epi32(k)), _mm_andnot_si128(bk, best_k));
    }
    AxisSplits s;
    _mm_store_ps(s.cost, best_v);
    _mm_store_si128(reinterpret_cast<__m128i*>(s.bin), best_k);
    return s;
}

/// A binned split: the axis and the last bin on the left side.
struct BinSplit {
    int axis = -1; ///< -1: no split with both sides non-empty
    int bin = -1;
};

/// The cheapest of the three axes' splits; the lowest axis on ties.
BinSplit choose_split(const AxisSplits& s) {
    BinSplit best;
    float best_cost = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a)
        if (s.bin[a] >= 0 && s.cost[a] < best_cost) {
            best_cost = s.cost[a];
            best.axis = a;
            best.bin = s.bin[a];
        }
    return best;
}

/// Sets the boxes of left and right from the bins of the split axis, exact when every
/// primitive was binned (g.stride == 1).
void boxes_from_bins(const BinGrid& g, const Bins& b, const BinSplit& split, Range& left,
                     Range& right) {
    const float inf = std::numeric_limits<float>::infinity();
    left.lo = right.lo = _mm_set1_ps(inf);
    left.hi = right.hi = _mm_set1_ps(-inf);
    for (int k = 0; k < g.nb; ++k) {
        Range& side = k <= split.bin ? left : right;
        side.lo = _mm_min_ps(side.lo, b.lo[0][split.axis][k]);
        side.hi = _mm_max_ps(side.hi, b.hi[0][split.axis][k]);
    }
}

/// Binned SAH split of r (more than kSweepMaxPrims primitives, centroid extent ext per axis):
/// bins the centroids, evaluates the SAH at every bin boundary, chooses the cheapest, and
/// partitions; at the index median when no boundary has primitives on both sides.
void binned_split(BuildPrim* prims, const Range& r, const float* ext, Range& left, Range& right) {
    const BinGrid g = make_bin_grid(r, ext);
    Bins bins;
    bin_centroids(prims, r, g, bins);
    merge_bin_sets(g, bins);
    BinColumns col;
    transpose_bins(g, bins, col);
    const BinSplit split = choose_split(evaluate_sah(g, col, ext));
    // When every primitive was binned, an axis of positive extent has its extreme
    // centroids in bins 0 and nb - 1, so a split with both sides non-empty exists; a
    // sample of a large range may miss the extremes and see them all in one bin.
    if (split.axis < 0) {
        median_split(prims, r, left, right);
        return;
    }
    const int ax = split.axis;
    // bin_of(c)[ax] <= split.bin iff x = (c - clo) * scale < s + 1 (the same two roundings
    // as bin_of; floor(clamp(x, 0, nb - 1)) <= s iff x < s + 1, since s + 1 <= nb - 1).
    // x is a non-decreasing function of c, so this holds exactly for c below a threshold
    // t: the partition compares c against t alone, keeping its loop in registers.
    const float t = split_threshold(lane(g.cmin, ax), g.sc[ax], static_cast<float>(split.bin + 1),
                                    lane(r.chi, ax));
    if (g.stride == 1) {
        // Every primitive was binned, so the bins on each side of the split hold the two
        // boxes exactly, and the partition only accumulates the centroid boxes.
        partition<false>(prims, r, ax, t, left, right);
        boxes_from_bins(g, bins, split, left, right);
    } else {
        // The bins saw only a sample: the partition accumulates the boxes too.
        partition<true>(prims, r, ax, t, left, right);
    }
}

} // namespace

/// Bounds of prims[begin, end) and of their doubled centroids.
void range_bounds(const BuildPrim* prims, Range& r) {
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

void split_range(BuildPrim* prims, const Range& r, Range& left, Range& right) {
    alignas(16) float ext[4];
    _mm_store_ps(ext, _mm_sub_ps(r.chi, r.clo));
    const bool flat = !(ext[0] > 0.f) && !(ext[1] > 0.f) && !(ext[2] > 0.f);
    left.depth = right.depth = r.depth + 1;
    if (flat || r.depth >= kSahMaxDepth)
        median_split(prims, r, left, right);
    else if (r.size() <= kSweepMaxPrims)
        sweep_split(prims, r, ext, left, right);
    else
        binned_split(prims, r, ext, left, right);
}

} // namespace candela::bvh_detail
