#pragma once
// Pseudo-random numbers and integer hashing.
//
// PCG32 follows M. E. O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
// Algorithms for Random Number Generation" (2014): a 64-bit LCG state with the XSH-RR output
// permutation. The 64-bit mixer is the finaliser of splitmix64 (Steele, Lea, Flood, "Fast
// Splittable Pseudorandom Number Generators", OOPSLA 2014).
#include "candela/math/vec.h"

#include <cstdint>

namespace candela {

/// splitmix64's Weyl increment: 2^64 divided by the golden ratio, rounded to odd. Consecutive
/// states differ by it; hash_combine adds it to decorrelate equal inputs.
constexpr std::uint64_t kGoldenGamma = 0x9E3779B97F4A7C15ULL;

/// The top 24 bits of `bits` as a float in [0, 1): exact (24 bits fit a float's significand),
/// multiples of 2^-24, so rounding never gives 1.
constexpr float bits_to_unit_float(std::uint32_t bits) {
    return static_cast<float>(bits >> 8) * 0x1p-24f;
}

/// A point of [0, 1)^2 as two raw 32-bit fixed-point fractions (Sampler::get_2d_bits): the
/// whole precision of a sampler's 2-D point, for choices that must realise an integer
/// probability exactly (sampling/unit_cdf.h) before their coordinates become floats.
struct Bits2 {
    std::uint32_t x = 0, y = 0;
};

/// Both coordinates of `u` as floats, as Sampler::get_2d returns them.
constexpr Vec2 bits_to_unit_point(Bits2 u) {
    return {bits_to_unit_float(u.x), bits_to_unit_float(u.y)};
}

/// The inverse of bits_to_unit_float for values on its grid (multiples of 2^-24 in [0, 1)),
/// which it maps back exactly; other values in [0, 1) are rounded down to 32 bits, values from 1
/// on give the largest, negative ones (and NaN) zero.
constexpr std::uint32_t unit_float_to_bits(float u) {
    if (u >= 1.f) return 0xffffffffu;
    return u > 0.f ? static_cast<std::uint32_t>(static_cast<double>(u) * 0x1p32) : 0u;
}

/// unit_float_to_bits of both coordinates: the inverse of bits_to_unit_point on its grid.
constexpr Bits2 unit_point_to_bits(Vec2 u) {
    return {unit_float_to_bits(u.x), unit_float_to_bits(u.y)};
}

/// The top 53 bits of `bits` as a double in [0, 1), multiples of 2^-53.
constexpr double bits_to_unit_double(std::uint64_t bits) {
    return static_cast<double>(bits >> 11) * 0x1p-53;
}

/// splitmix64 finaliser: a bijective avalanche mix of 64 bits. Returns a well-scrambled 64-bit
/// value.
constexpr std::uint64_t mix64(std::uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

/// Combines an accumulated hash `h` with one more value `v`. Order-sensitive.
constexpr std::uint64_t hash_combine(std::uint64_t h, std::uint64_t v) {
    // Golden-ratio increment decorrelates equal consecutive inputs before the mix.
    return mix64(h ^ (v + kGoldenGamma + (h << 6) + (h >> 2)));
}

/// Hashes any number of integers (seed, pixel x, pixel y, sample index, dimension...) into one
/// 64-bit value. Order-sensitive; distinct argument tuples give independent-looking outputs.
template <typename... Ts>
constexpr std::uint64_t hash_combine(std::uint64_t h, std::uint64_t v, Ts... rest) {
    return hash_combine(hash_combine(h, v), static_cast<std::uint64_t>(rest)...);
}

/// PCG32 (XSH-RR, 64-bit state, selectable stream).
class Pcg32 {
  public:
    constexpr Pcg32() = default;
    constexpr Pcg32(std::uint64_t initstate, std::uint64_t initseq) { seed(initstate, initseq); }

    /// Seeds the generator: `initstate` picks the starting point, `initseq` the stream
    /// (2^63 distinct streams).
    constexpr void seed(std::uint64_t initstate, std::uint64_t initseq) {
        state_ = 0u;
        inc_ = (initseq << 1u) | 1u;
        next_u32();
        state_ += initstate;
        next_u32();
    }

    /// Uniform 32-bit integer.
    constexpr std::uint32_t next_u32() {
        std::uint64_t old = state_;
        state_ = old * kMultiplier + inc_;
        auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        auto rot = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }

    /// Uniform float in [0, 1): the top 24 bits scaled by 2^-24, so 1 is never returned.
    constexpr float next_float() { return bits_to_unit_float(next_u32()); }

  private:
    static constexpr std::uint64_t kMultiplier = 6364136223846793005ULL;
    std::uint64_t state_ = 0x853c49e6748fea9bULL;
    std::uint64_t inc_ = 0xda3e39cb94b95bdbULL;
};

/// splitmix64 (Steele, Lea, Flood 2014): a 64-bit counter advanced by kGoldenGamma and passed
/// through mix64. Any state is a valid seed, so generators can be derived from counters (a ray
/// index, a case number) and run in parallel, identically every run. Diagnostics and test-case
/// generation use it; the renderer's samples come from Sampler.
class SplitMix64 {
  public:
    constexpr explicit SplitMix64(std::uint64_t state) : state_(state) {}

    /// Uniform 64-bit integer.
    constexpr std::uint64_t next_u64() { return mix64(state_ += kGoldenGamma); }

    /// Uniform float in [0, 1) from the top 24 bits.
    constexpr float next_float() {
        return bits_to_unit_float(static_cast<std::uint32_t>(next_u64() >> 32));
    }

    /// Uniform double in [0, 1) from the top 53 bits.
    constexpr double next_double() { return bits_to_unit_double(next_u64()); }

    /// Two uniform floats in [0, 1), x drawn first.
    constexpr Vec2 next_vec2() {
        const float x = next_float();
        const float y = next_float();
        return {x, y};
    }

    /// Integer in [0, n) (n > 0) by reduction modulo n: biased by at most n / 2^64, which the
    /// diagnostics that use it do not notice.
    constexpr std::uint64_t next_below(std::uint64_t n) { return next_u64() % n; }

  private:
    std::uint64_t state_;
};

} // namespace candela
