#pragma once
// The builtin BVH's build, internal to src/accel: the per-primitive build records, primitive
// ranges, and the binary split of a range (bvh_split.cpp) from which bvh_build.cpp collapses
// the 8-wide nodes.
#include <emmintrin.h>
#include <xmmintrin.h>

#include <cstdint>

namespace candela::bvh_detail {

/// Build-time record of one primitive: its box, with the scene-wide reference in lo.w and the
/// mesh index in hi.w (as bit patterns; masked off before any arithmetic).
struct BuildPrim {
    __m128 lo, hi;
};

/// A primitive range with its box and the box of its doubled centroids (lo + hi).
struct Range {
    std::uint32_t begin = 0, end = 0;
    int depth = 0; ///< binary split levels above this range
    __m128 lo, hi, clo, chi;
    std::uint32_t size() const { return end - begin; }
};

/// All bits set in x, y and z, clear in w: masks the tags off a BuildPrim's boxes.
inline __m128 xyz_mask() {
    return _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
}

/// Lane `lane` (0..3) of v as a bit pattern.
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

/// Sets r's box and centroid box to those of prims[r.begin, r.end).
void range_bounds(const BuildPrim* prims, Range& r);

/// Splits r (more than kBvhMaxLeafPrims primitives) in two non-empty ranges, partitioning
/// prims in place: by binned SAH on the doubled centroids (an exact SAH sweep for small
/// ranges), or at the index median when the centroids coincide or the range is kSahMaxDepth
/// split levels deep. Sets both sides' boxes, centroid boxes and depth.
void split_range(BuildPrim* prims, const Range& r, Range& left, Range& right);

} // namespace candela::bvh_detail
