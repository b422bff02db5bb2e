#pragma once
// Per-pixel sample generators. A Sampler is a small value type (one per thread); start() puts it
// at (pixel, sample index) and every number it then returns is a pure function of
// (seed, pixel, sample index, dimension). Images are therefore identical for any thread count or
// tile order, and sample n + 1 never repeats numbers of samples 0..n.
//
// Sobol: a padded, scrambled (0,2)-sequence. Every 2-D request uses the first two Sobol
// dimensions (van der Corput and the generator matrix of Sobol dimension 2), each component
// Owen-scrambled with its own seed hash(seed, px, py, dimension), and the sample index permuted
// per (pixel, dimension) by a nested-uniform (Owen) shuffle of its bits. 1-D requests use the van
// der Corput component alone with their own scramble and shuffle. The scramble is the hash-based
// nested uniform scramble of Laine and Karras ("Stratified Sampling for Stochastic Transparency",
// EGSR 2011), in the improved form of Burley ("Practical Hash-based Owen Scrambling", JCGT 2020);
// padding and index shuffling as in Pharr et al., PBRT 4th ed., PaddedSobolSampler. Any aligned
// block of 2^k consecutive sample indices of one pixel forms a (0,k,2)-net per dimension pair.
// Sample indices are used modulo 2^32.
#include "candela/math/vec.h"
#include "candela/sampling/rng.h"

#include <cstdint>

namespace candela {

enum class SamplerKind { Independent, Sobol };

namespace sobol {

/// Reverses the 32 bits of x.
constexpr std::uint32_t reverse_bits(std::uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/// First Sobol dimension (base-2 van der Corput radical inverse) as a 0.32 fixed-point fraction.
constexpr std::uint32_t sobol_dim0(std::uint32_t index) {
    return reverse_bits(index);
}

/// Second Sobol dimension (primitive polynomial x + 1, all direction numbers m_i = 1) as a 0.32
/// fixed-point fraction: the generator matrix column for bit i is v_i = v_{i-1} ^ (v_{i-1} >> 1).
constexpr std::uint32_t sobol_dim1(std::uint32_t index) {
    std::uint32_t r = 0u;
    for (std::uint32_t v = 1u << 31; index != 0u; index >>= 1, v ^= v >> 1)
        if (index & 1u) r ^= v;
    return r;
}

/// Laine-Karras style permutation on bit-reversed values (Burley 2020 constants): each output bit
/// is the input bit flipped by a hash of the seed and of the LOWER input bits only.
constexpr std::uint32_t laine_karras_permutation(std::uint32_t x, std::uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/// Nested uniform (Owen) scramble of a 0.32 fixed-point fraction: the flip of each bit depends
/// only on the seed and the more significant bits, so stratification is preserved.
constexpr std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
    return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

/// Bijective shuffle of sample indices such that the first 2^k indices map onto one aligned
/// block of 2^k indices (nested scramble of the index's bits, low bits depending on high ones).
constexpr std::uint32_t shuffle_index(std::uint32_t index, std::uint32_t seed) {
    return owen_scramble(index, seed);
}

/// 0.32 fixed point to float in [0, 1): keeps the top 24 bits so that rounding never gives 1.
constexpr float to_unit_float(std::uint32_t x) {
    return static_cast<float>(x >> 8) * 5.9604644775390625e-8f; // 2^-24
}

} // namespace sobol

class Sampler {
  public:
    Sampler(SamplerKind kind, std::uint64_t seed) : kind_(kind), seed_(seed) {}

    SamplerKind kind() const { return kind_; }
    std::uint64_t seed() const { return seed_; }

    /// Positions the sampler at sample `sample_index` of pixel (px, py) and resets the dimension to
    /// 0. The resulting stream depends only on (seed, px, py, sample_index).
    void start(std::uint32_t px, std::uint32_t py, std::uint64_t sample_index) {
        pixel_hash_ = hash_combine(seed_, px, py);
        index_ = sample_index;
        dimension_ = 0;
        if (kind_ == SamplerKind::Independent) {
            std::uint64_t h = hash_combine(pixel_hash_, sample_index);
            rng_.seed(h, hash_combine(h, kStreamSalt));
        }
    }

    /// Next uniform number in [0, 1) (consumes one dimension).
    float get_1d() {
        if (kind_ == SamplerKind::Independent) {
            ++dimension_;
            return rng_.next_float();
        }
        std::uint32_t dim = dimension_++;
        std::uint64_t h = hash_combine(pixel_hash_, dim);
        auto idx = sobol::shuffle_index(static_cast<std::uint32_t>(index_),
                                        static_cast<std::uint32_t>(hash_combine(h, kShuffleSalt)));
        return sobol::to_unit_float(
            sobol::owen_scramble(sobol::sobol_dim0(idx), static_cast<std::uint32_t>(h)));
    }

    /// Next uniform point in [0, 1)^2 (consumes two dimensions).
    Vec2 get_2d() {
        if (kind_ == SamplerKind::Independent) {
            dimension_ += 2;
            float a = rng_.next_float();
            float b = rng_.next_float();
            return {a, b};
        }
        std::uint32_t dim = dimension_;
        dimension_ += 2;
        std::uint64_t h0 = hash_combine(pixel_hash_, dim);
        std::uint64_t h1 = hash_combine(pixel_hash_, dim + 1u);
        auto idx = sobol::shuffle_index(static_cast<std::uint32_t>(index_),
                                        static_cast<std::uint32_t>(hash_combine(h0, kShuffleSalt)));
        return {sobol::to_unit_float(
                    sobol::owen_scramble(sobol::sobol_dim0(idx), static_cast<std::uint32_t>(h0))),
                sobol::to_unit_float(
                    sobol::owen_scramble(sobol::sobol_dim1(idx), static_cast<std::uint32_t>(h1)))};
    }

    /// Number of dimensions consumed since start().
    std::uint32_t dimension() const { return dimension_; }

  private:
    // Arbitrary distinct constants separating the hash streams used for different purposes.
    static constexpr std::uint64_t kStreamSalt = 0x53545245414dULL;  // PCG stream selector
    static constexpr std::uint64_t kShuffleSalt = 0x53485546464cULL; // Sobol index shuffle

    SamplerKind kind_;
    std::uint64_t seed_;
    std::uint64_t pixel_hash_ = 0;
    std::uint64_t index_ = 0;
    std::uint32_t dimension_ = 0;
    Pcg32 rng_;
};

} // namespace candela
