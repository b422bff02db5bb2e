#pragma once
// CANDELA_BATCH_KERNEL marks a loop over a batch of paths that GCC vectorises: it is compiled
// twice, for the x86-64 baseline and for AVX2 (eight floats per instruction), and the loader picks
// the AVX2 version on a CPU that has it. Neither version enables FMA, so both compute the same
// bits. Configuring with -DCANDELA_BASELINE_KERNELS=ON compiles the baseline version alone, which
// is how the baseline is checked on a machine with AVX2 (its renders must equal the default
// build's bit for bit).
#include <cstddef>

namespace candela {

/// The distance, in floats, between the component arrays of a batch of n paths (x, y, z, ... of
/// a structure of arrays): n rounded up to whole cache lines plus one line. A power-of-two
/// distance (the batch size) would put every component stream into the same cache sets.
constexpr std::size_t batch_stride(std::size_t n) {
    constexpr std::size_t kLineFloats = 16; // a 64-byte cache line
    return (n + kLineFloats - 1) / kLineFloats * kLineFloats + kLineFloats;
}

} // namespace candela

#if defined(CANDELA_BASELINE_KERNELS)
#define CANDELA_BATCH_KERNEL
#else
#define CANDELA_BATCH_KERNEL __attribute__((target_clones("avx2", "default")))
#endif
