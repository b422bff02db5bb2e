#pragma once
// Per-pixel sample generators. A Sampler is a value type (one per thread); start() puts it
// at (pixel, sample index) and every number it then returns is a pure function of
// (seed, pixel, sample index, dimension). Images are therefore identical for any thread count or
// tile order, and sample n + 1 never repeats numbers of samples 0..n. The samplers keep the
// hashes that depend only on the pixel (the pixel hash and Sobol's seeds of each dimension)
// while consecutive start() calls stay on one pixel; this saves time and changes no value.
//
// Independent: each request hashes (pixel hash, sample index, dimension) with the splitmix64
// finaliser (rng.h) into 64 bits, one value from the top 32 bits (24 of them kept), a 2-D point
// from both halves. Being addressed by dimension, like Sobol, it needs no state between
// requests, so a path's numbers do not depend on which requests came before.
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
#include "candela/util/enum_table.h"

#include <cstdint>

namespace candela {

enum class SamplerKind { Independent, Sobol };
/// --sampler (util/enum_table.h).
inline constexpr EnumTable<SamplerKind, 2> kSamplerKinds = {{
    {SamplerKind::Sobol, "sobol", "Owen-scrambled, the default"},
    {SamplerKind::Independent, "independent", "the CS184 sampler"},
}};

namespace sobol {

/// Reverses the 32 bits of x: the byte order by one byte swap, then the bits within each byte.
constexpr std::uint32_t reverse_bits(std::uint32_t x) {
    x = __builtin_bswap32(x);
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
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

/// shuffle_index(index, seed) from the bit-reversed index (Sampler keeps it reversed).
constexpr std::uint32_t shuffle_reversed_index(std::uint32_t reversed_index, std::uint32_t seed) {
    return reverse_bits(laine_karras_permutation(reversed_index, seed));
}

/// The two coordinates of padded Sobol point `idx` (a shuffled index), each Owen-scrambled with
/// its own seed, as 0.32 fixed-point fractions. First: owen_scramble(sobol_dim0(idx), s) =
/// reverse(LK(idx, s)), the radical inverse's bit reversal cancelling the scramble's first one.
/// Second: owen_scramble(sobol_dim1(idx), s) = reverse(LK(superset_xor(idx), s)), as sobol_dim1 =
/// reverse_bits o superset_xor.
constexpr std::uint32_t scrambled_first(std::uint32_t idx, std::uint32_t scramble) {
    return reverse_bits(laine_karras_permutation(idx, scramble));
}
constexpr std::uint32_t scrambled_second(std::uint32_t idx, std::uint32_t scramble) {
    return reverse_bits(laine_karras_permutation(superset_xor(idx), scramble));
}

} // namespace sobol

class Sampler {
  public:
    Sampler(SamplerKind kind, std::uint64_t seed) : kind_(kind), seed_(seed) {}

    SamplerKind kind() const { return kind_; }
    std::uint64_t seed() const { return seed_; }

    /// Positions the sampler at sample `sample_index` of pixel (px, py) and resets the dimension to
    /// 0. Every value then depends only on (seed, px, py, sample_index, dimension).
    void start(std::uint32_t px, std::uint32_t py, std::uint64_t sample_index) {
        dimension_ = 0;
        select_pixel(px, py);
        if (kind_ == SamplerKind::Independent) {
            point_hash_ = hash_combine(pixel_hash_, sample_index, kIndependentSalt);
            return;
        }
        reversed_index_ = sobol::reverse_bits(static_cast<std::uint32_t>(sample_index));
    }

    /// Next uniform number in [0, 1) (consumes one dimension): the top 24 bits of get_1d_bits().
    [[gnu::always_inline]] float get_1d() { return bits_to_unit_float(get_1d_bits()); }

    /// Next uniform 32-bit integer (consumes one dimension): all the bits get_1d() keeps 24 of,
    /// for choices whose realised probabilities must be exact (sampling/unit_cdf.h).
    [[gnu::always_inline]] std::uint32_t get_1d_bits() {
        const std::uint32_t dim = dimension_++;
        if (kind_ == SamplerKind::Independent)
            return static_cast<std::uint32_t>(independent_bits(dim) >> 32);
        const DimensionSeeds d = dimension_seeds(dim);
        const std::uint32_t idx = sobol::shuffle_reversed_index(reversed_index_, d.shuffle);
        return sobol::scrambled_first(idx, d.scramble);
    }

    /// Next uniform point in [0, 1)^2 (consumes two dimensions): the top 24 bits of each
    /// coordinate of get_2d_bits().
    [[gnu::always_inline]] Vec2 get_2d() { return bits_to_unit_point(get_2d_bits()); }

    /// Next uniform point in [0, 1)^2 as raw 32-bit coordinates (consumes two dimensions).
    [[gnu::always_inline]] Bits2 get_2d_bits() {
        const std::uint32_t dim = dimension_;
        dimension_ += 2;
        if (kind_ == SamplerKind::Independent) {
            // One 64-bit hash gives both coordinates.
            const std::uint64_t h = independent_bits(dim);
            return {static_cast<std::uint32_t>(h >> 32), static_cast<std::uint32_t>(h)};
        }
        const DimensionSeeds d0 = dimension_seeds(dim);
        const std::uint32_t scramble1 = dimension_seeds(dim + 1u).scramble;
        const std::uint32_t idx = sobol::shuffle_reversed_index(reversed_index_, d0.shuffle);
        return {sobol::scrambled_first(idx, d0.scramble), sobol::scrambled_second(idx, scramble1)};
    }

    /// The dimension the next request consumes (requests since start() unless moved).
    std::uint32_t dimension() const { return dimension_; }

    /// Makes the next request consume dimension `dim`. Integrators give every use of a random
    /// number along a path a fixed dimension (render/vertex_draws.h, DimensionLayout), so that the
    /// same bounce of every sample of a pixel draws from the same dimensions whatever the
    /// earlier bounces consumed: Sobol strata hold per use across a pixel's samples.
    void set_dimension(std::uint32_t dim) { dimension_ = dim; }

  private:
    friend class SampleBatch; // fills batches from the same seeds (sample_batch.h)

    /// Consecutive samples of one pixel share the pixel hash (and, for Sobol, the seeds of the
    /// dimensions already used).
    void select_pixel(std::uint32_t px, std::uint32_t py) {
        if (!pixel_cached_ || px != cached_px_ || py != cached_py_) {
            pixel_hash_ = hash_combine(seed_, px, py);
            cached_px_ = px;
            cached_py_ = py;
            pixel_cached_ = true;
            cached_mask_ = 0;
        }
    }

    // Arbitrary distinct constants separating the hash streams used for different purposes.
    static constexpr std::uint64_t kIndependentSalt = 0x494e444550ULL; // independent values
    static constexpr std::uint64_t kShuffleSalt = 0x53485546464cULL;   // Sobol index shuffle
    /// Dimensions whose Sobol seeds are kept per pixel: more than a depth-8 path consumes;
    /// deeper dimensions are hashed on every request.
    static constexpr std::uint32_t kCachedDims = 64;

    /// Sobol seeds of one dimension of the current pixel: the Owen scramble of the value and
    /// the shuffle of the sample index.
    struct DimensionSeeds {
        std::uint32_t scramble;
        std::uint32_t shuffle;
    };

    /// Independent sampler: 64 hashed bits for dimension `dim` of the current sample (its
    /// top 32 bits give a 1-D value, both halves a 2-D point).
    std::uint64_t independent_bits(std::uint32_t dim) const {
        return hash_combine(point_hash_, dim);
    }

    static DimensionSeeds hash_dimension(std::uint64_t pixel_hash, std::uint32_t dim) {
        const std::uint64_t h = hash_combine(pixel_hash, dim);
        return {static_cast<std::uint32_t>(h),
                static_cast<std::uint32_t>(hash_combine(h, kShuffleSalt))};
    }

    /// Seeds of dimension `dim` of the current pixel: each dimension is hashed once per pixel,
    /// on its first use, and kept while start() stays on that pixel.
    DimensionSeeds dimension_seeds(std::uint32_t dim) {
        if (dim >= kCachedDims) return hash_dimension(pixel_hash_, dim);
        const std::uint64_t bit = std::uint64_t(1) << dim;
        if (!(cached_mask_ & bit)) {
            seeds_[dim] = hash_dimension(pixel_hash_, dim);
            cached_mask_ |= bit;
        }
        return seeds_[dim];
    }

    SamplerKind kind_;
    std::uint64_t seed_;
    std::uint64_t pixel_hash_ = 0; // hash(seed, px, py) of the cached pixel
    std::uint64_t point_hash_ = 0; // independent: hash of the current sample
    std::uint32_t dimension_ = 0;
    std::uint32_t reversed_index_ = 0; // Sobol: reverse_bits of the sample index mod 2^32
    bool pixel_cached_ = false;        // pixel_hash_ and seeds_ belong to (cached_px_, cached_py_)
    std::uint32_t cached_px_ = 0, cached_py_ = 0;
    std::uint64_t cached_mask_ = 0; // bit d: seeds_[d] is valid for the cached pixel
    DimensionSeeds seeds_[kCachedDims] = {};
};

} // namespace candela
