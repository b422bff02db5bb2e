#pragma once
// Traversal kernels of the builtin BVH, one set per instruction set. Internal to src/accel.
#include "candela/accel/bvh.h"

namespace candela::bvh_detail {

/// Kernels indexed [watertight][sphere mode: none, true spheres only, with ellipsoids][any hit].
struct KernelSet {
    BvhAccel::TraceFn fn[2][3][2];
};

/// Floats per primitive in the leaf data: 9 coordinates and the reference.
constexpr std::size_t kLeafFloats = 10;

KernelSet sse2_kernels();
/// Only callable on a CPU with AVX2 (bvh_cpu_has_avx2()).
KernelSet avx2_kernels();

} // namespace candela::bvh_detail
