#pragma once
// Per-pixel sample generators. A Sampler is a value type (one per thread); start() puts it
// at (pixel, sample index) and every number it then returns is a pure function of
// (seed, pixel, sample index, dimension). Images are therefore identical for any thread count or
// tile order, and sample n + 1 never repeats numbers of samples 0..n. The Sobol sampler keeps
// the hashes that depend only on the pixel (the pixel hash and the seeds of each dimension)
// while consecutive start() calls stay on one pixel; this saves time and changes no value.
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

/// XOR superset transform of the 32 bit positions of x: bit j of the result is the XOR of the
/// bits i of x whose position i contains j as a bit subset (i & j == j). Five shift-mask steps,
/// one per bit of a position.
constexpr std::uint32_t superset_xor(std::uint32_t x) {
    x ^= (x >> 1) & 0x55555555u;
    x ^= (x >> 2) & 0x33333333u;
    x ^= (x >> 4) & 0x0f0f0f0fu;
    x ^= (x >> 8) & 0x00ff00ffu;
    x ^= (x >> 16) & 0x0000ffffu;
    return x;
}

/// Second Sobol dimension (primitive polynomial x + 1, all direction numbers m_i = 1) as a 0.32
/// fixed-point fraction: the generator matrix column for bit i is v_i = v_{i-1} ^ (v_{i-1} >> 1),
/// v_0 = 2^31, so bit 31 - j of v_i is C(i, j) mod 2 (Pascal's triangle). By Lucas' theorem
/// C(i, j) is odd exactly when j is a bit subset of i, so the matrix-vector product is the
/// superset transform of the index's bits, read from the top bit down.
constexpr std::uint32_t sobol_dim1(std::uint32_t index) {
    return reverse_bits(superset_xor(index));
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
        dimension_ = 0;
        if (kind_ == SamplerKind::Independent) {
            std::uint64_t h = hash_combine(hash_combine(seed_, px, py), sample_index);
            rng_.seed(h, hash_combine(h, kStreamSalt));
            return;
        }
        // Consecutive samples of one pixel share the pixel hash and the per-dimension seeds.
        if (!pixel_cached_ || px != cached_px_ || py != cached_py_) {
            pixel_hash_ = hash_combine(seed_, px, py);
            cached_px_ = px;
            cached_py_ = py;
            pixel_cached_ = true;
            cached_dims_ = 0;
        }
        reversed_index_ = sobol::reverse_bits(static_cast<std::uint32_t>(sample_index));
    }

    /// Next uniform number in [0, 1) (consumes one dimension).
    float get_1d() {
        if (kind_ == SamplerKind::Independent) {
            ++dimension_;
            return rng_.next_float();
        }
        const DimensionSeeds d = dimension_seeds(dimension_++);
        // owen_scramble(sobol_dim0(idx), scramble) = reverse(LK(idx, scramble)): the radical
        // inverse's bit reversal cancels the scramble's first one.
        const std::uint32_t idx = shuffled_index(d.shuffle);
        return sobol::to_unit_float(
            sobol::reverse_bits(sobol::laine_karras_permutation(idx, d.scramble)));
    }

    /// Next uniform point in [0, 1)^2 (consumes two dimensions).
    Vec2 get_2d() {
        if (kind_ == SamplerKind::Independent) {
            dimension_ += 2;
            float a = rng_.next_float();
            float b = rng_.next_float();
            return {a, b};
        }
        const std::uint32_t dim = dimension_;
        dimension_ += 2;
        const DimensionSeeds d0 = dimension_seeds(dim);
        const std::uint32_t scramble1 = dimension_seeds(dim + 1u).scramble;
        const std::uint32_t idx = shuffled_index(d0.shuffle);
        // Second component: owen_scramble(sobol_dim1(idx), s) = reverse(LK(superset_xor(idx), s)),
        // as sobol_dim1 = reverse_bits o superset_xor; the first as in get_1d.
        const std::uint32_t x0 =
            sobol::reverse_bits(sobol::laine_karras_permutation(idx, d0.scramble));
        const std::uint32_t x1 = sobol::reverse_bits(
            sobol::laine_karras_permutation(sobol::superset_xor(idx), scramble1));
        return {sobol::to_unit_float(x0), sobol::to_unit_float(x1)};
    }

    /// The dimension the next request consumes (requests since start() unless moved).
    std::uint32_t dimension() const { return dimension_; }

    /// Makes the next request consume dimension `dim`. Integrators give every use of a random
    /// number along a path a fixed dimension (render/integrator.h, DimensionLayout), so that the
    /// same bounce of every sample of a pixel draws from the same Sobol dimensions whatever the
    /// earlier bounces consumed; stratification across a pixel's samples then holds per use.
    /// The independent sampler's numbers do not depend on the dimension (any layout gives
    /// independent uniforms); it only records it.
    void set_dimension(std::uint32_t dim) { dimension_ = dim; }

  private:
    // Arbitrary distinct constants separating the hash streams used for different purposes.
    static constexpr std::uint64_t kStreamSalt = 0x53545245414dULL;  // PCG stream selector
    static constexpr std::uint64_t kShuffleSalt = 0x53485546464cULL; // Sobol index shuffle
    /// Dimensions whose seeds are kept per pixel: more than a depth-8 path consumes; deeper
    /// dimensions are hashed on every request.
    static constexpr std::uint32_t kCachedDims = 64;

    /// Sobol seeds of one dimension of the current pixel: the Owen scramble of the value and
    /// the shuffle of the sample index.
    struct DimensionSeeds {
        std::uint32_t scramble;
        std::uint32_t shuffle;
    };

    static DimensionSeeds hash_dimension(std::uint64_t pixel_hash, std::uint32_t dim) {
        const std::uint64_t h = hash_combine(pixel_hash, dim);
        return {static_cast<std::uint32_t>(h),
                static_cast<std::uint32_t>(hash_combine(h, kShuffleSalt))};
    }

    /// sobol::shuffle_index(sample index, shuffle) from the sample index reversed in start().
    std::uint32_t shuffled_index(std::uint32_t shuffle) const {
        return sobol::reverse_bits(sobol::laine_karras_permutation(reversed_index_, shuffle));
    }

    /// Seeds of dimension `dim` of the current pixel, from the per-pixel cache when possible.
    DimensionSeeds dimension_seeds(std::uint32_t dim) {
        if (dim < cached_dims_) return seeds_[dim];
        if (dim >= kCachedDims) return hash_dimension(pixel_hash_, dim);
        for (; cached_dims_ <= dim; ++cached_dims_)
            seeds_[cached_dims_] = hash_dimension(pixel_hash_, cached_dims_);
        return seeds_[dim];
    }

    SamplerKind kind_;
    std::uint64_t seed_;
    std::uint64_t pixel_hash_ = 0; // Sobol: hash(seed, px, py) of the cached pixel
    std::uint32_t dimension_ = 0;
    std::uint32_t reversed_index_ = 0; // Sobol: reverse_bits of the sample index mod 2^32
    bool pixel_cached_ = false;        // pixel_hash_ and seeds_ belong to (cached_px_, cached_py_)
    std::uint32_t cached_px_ = 0, cached_py_ = 0;
    std::uint32_t cached_dims_ = 0; // seeds_[0, cached_dims_) are valid for the cached pixel
    DimensionSeeds seeds_[kCachedDims] = {};
    Pcg32 rng_;
};

} // namespace candela
