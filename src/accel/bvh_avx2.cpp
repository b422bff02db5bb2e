// AVX2 traversal kernels of the builtin BVH: the eight child boxes of a node are tested in one
// 256-bit pass. Everything below the target pragma is compiled for AVX2 and only ever called
// after bvh_cpu_has_avx2() (see BvhAccel::select_kernels). No FMA: the box test must keep the
// rounding of (bound - o) * inv_d that the conservative far-plane scale accounts for, and the
// triangle test must stay bit-identical to the scalar Moller-Trumbore.
#include "bvh_kernels.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/math/ray.h"
#include "candela/scene/scene.h"

#include <immintrin.h>

#include <cstdint>
#include <cstring>

#pragma GCC push_options
#pragma GCC target("avx2")

namespace candela::bvh_detail {

namespace {

#include "bvh_trace_body.h"

/// Slab test of the eight children of a node in one AVX pass.
class BoxAvx2 {
  public:
    BoxAvx2(const Ray& ray, const Vec3& inv)
        : ox_(_mm256_set1_ps(ray.o.x)), oy_(_mm256_set1_ps(ray.o.y)), oz_(_mm256_set1_ps(ray.o.z)),
          ix_(_mm256_set1_ps(inv.x)), iy_(_mm256_set1_ps(inv.y)), iz_(_mm256_set1_ps(inv.z)),
          fix_(_mm256_set1_ps(inv.x * kSlabFarScale)), fiy_(_mm256_set1_ps(inv.y * kSlabFarScale)),
          fiz_(_mm256_set1_ps(inv.z * kSlabFarScale)), tmin_(_mm256_set1_ps(ray.tmin)),
          tmax_(_mm256_set1_ps(ray.tmax)), nx_(near_plane_offset(0, inv.x)),
          ny_(near_plane_offset(1, inv.y)), nz_(near_plane_offset(2, inv.z)) {}
    void set_tmax(float t) { tmax_ = _mm256_set1_ps(t); }
    unsigned test(const Bvh8Node& node, float* tn) const {
        const float* b = node.bounds[0][0];
        const __m256 tnx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + nx_), ox_), ix_);
        const __m256 tny = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + ny_), oy_), iy_);
        const __m256 tnz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + nz_), oz_), iz_);
        const __m256 tfx =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + (nx_ ^ kBvhWidth)), ox_), fix_);
        const __m256 tfy =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + (ny_ ^ kBvhWidth)), oy_), fiy_);
        const __m256 tfz =
            _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + (nz_ ^ kBvhWidth)), oz_), fiz_);
        // max_ps / min_ps return their second operand when either is NaN, so a NaN slab
        // distance (0 * inf) leaves the interval unchanged.
        const __m256 tnear = _mm256_max_ps(tnz, _mm256_max_ps(tny, _mm256_max_ps(tnx, tmin_)));
        const __m256 tfar = _mm256_min_ps(tfz, _mm256_min_ps(tfy, _mm256_min_ps(tfx, tmax_)));
        _mm256_store_ps(tn, tnear);
        return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(tnear, tfar, _CMP_LE_OQ)));
    }

  private:
    __m256 ox_, oy_, oz_, ix_, iy_, iz_, fix_, fiy_, fiz_, tmin_, tmax_;
    int nx_, ny_, nz_;
};

} // namespace

KernelSet avx2_kernels() {
    return make_kernel_set<BoxAvx2>();
}

} // namespace candela::bvh_detail

#pragma GCC pop_options
