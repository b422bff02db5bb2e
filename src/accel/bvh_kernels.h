#pragma once
// Traversal kernels of the builtin BVH, one set per instruction set: bvh_sse2.cpp and
// bvh_avx2.cpp each compile the loop of bvh_trace_body.h with their own box test. Internal to
// src/accel.
#include "bvh_layout.h"

#include "candela/accel/bvh.h"

namespace candela::bvh_detail {

/// Kernels indexed [watertight][sphere mode: none, true spheres only, with ellipsoids][any hit].
struct KernelSet {
    BvhAccel::TraceFn fn[2][3][2];
};

KernelSet sse2_kernels();
/// Only callable on a CPU with AVX2 (bvh_cpu_has_avx2()).
KernelSet avx2_kernels();

} // namespace candela::bvh_detail
