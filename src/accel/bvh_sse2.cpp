// SSE2 traversal kernels of the builtin BVH: the eight child boxes of a node are tested as two
// SSE passes of four. SSE2 is the x86-64 baseline, so these kernels run on every CPU; the
// AVX2 ones (bvh_avx2.cpp) replace them where the CPU has AVX2.
#include "bvh_kernels.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/math/ray.h"
#include "candela/scene/scene.h"

#include <emmintrin.h>
#include <xmmintrin.h>

#include <cstdint>
#include <cstring>

namespace candela::bvh_detail {

namespace {

#include "bvh_trace_body.h"

/// Slab test of the eight children of a node as two SSE passes of four.
class BoxSse2 {
  public:
    BoxSse2(const Ray& ray, const Vec3& inv)
        : ox_(_mm_set1_ps(ray.o.x)), oy_(_mm_set1_ps(ray.o.y)), oz_(_mm_set1_ps(ray.o.z)),
          ix_(_mm_set1_ps(inv.x)), iy_(_mm_set1_ps(inv.y)), iz_(_mm_set1_ps(inv.z)),
          fix_(_mm_set1_ps(inv.x * kSlabFarScale)), fiy_(_mm_set1_ps(inv.y * kSlabFarScale)),
          fiz_(_mm_set1_ps(inv.z * kSlabFarScale)), tmin_(_mm_set1_ps(ray.tmin)),
          tmax_(_mm_set1_ps(ray.tmax)), nx_(near_plane_offset(0, inv.x)),
          ny_(near_plane_offset(1, inv.y)), nz_(near_plane_offset(2, inv.z)) {}
    void set_tmax(float t) { tmax_ = _mm_set1_ps(t); }
    unsigned test(const Bvh8Node& node, float* tn) const {
        const float* b = node.bounds[0][0];
        return half(b, tn) | (half(b + 4, tn + 4) << 4);
    }

  private:
    /// Four children starting at plane offset b: entry distances to tn, hit mask returned.
    unsigned half(const float* b, float* tn) const {
        const __m128 tnx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + nx_), ox_), ix_);
        const __m128 tny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + ny_), oy_), iy_);
        const __m128 tnz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + nz_), oz_), iz_);
        const __m128 tfx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + (nx_ ^ kBvhWidth)), ox_), fix_);
        const __m128 tfy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + (ny_ ^ kBvhWidth)), oy_), fiy_);
        const __m128 tfz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + (nz_ ^ kBvhWidth)), oz_), fiz_);
        // max_ps / min_ps return their second operand when either is NaN, so a NaN slab
        // distance (0 * inf) leaves the interval unchanged.
        const __m128 tnear = _mm_max_ps(tnz, _mm_max_ps(tny, _mm_max_ps(tnx, tmin_)));
        const __m128 tfar = _mm_min_ps(tfz, _mm_min_ps(tfy, _mm_min_ps(tfx, tmax_)));
        _mm_store_ps(tn, tnear);
        return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(tnear, tfar)));
    }

    __m128 ox_, oy_, oz_, ix_, iy_, iz_, fix_, fiy_, fiz_, tmin_, tmax_;
    int nx_, ny_, nz_;
};

} // namespace

KernelSet sse2_kernels() {
    return make_kernel_set<BoxSse2>();
}

} // namespace candela::bvh_detail
