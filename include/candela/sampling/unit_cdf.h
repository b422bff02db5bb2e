#pragma once
// A discrete distribution as an integer CDF, inverted by a raw 32-bit uniform so that every index
// is chosen with exactly the probability pmf() reports.
//
// Probabilities are whole units of 2^-23: every such value is a float exactly, so pmf() needs no
// rounding. Index i owns the units
// [cdf(i), cdf(i + 1)) of [0, 2^23); a 32-bit uniform u chooses the index whose range holds the
// unit u >> 9, so each index is chosen by exactly units(i) * 2^9 of the 2^32 values of u: the
// realised probability is pmf(i) with no error. The choice is monotone in u, so a stratified u
// gives stratified choices, and the values of u inside the chosen range are reused as a continuous
// coordinate (sample()'s `remapped`) for a position inside the chosen cell (a texel, a triangle).
// Cost: O(log n) per choice, 4 bytes per index.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela {

/// log2 of the number of units in probability 1.
inline constexpr int kProbabilityUnitBits = 23;
/// Units in probability 1: a probability of k units is k * 2^-23.
inline constexpr std::uint32_t kProbabilityUnits = std::uint32_t(1) << kProbabilityUnitBits;

class UnitCdf {
  public:
    /// Units in probability 1 (and the most indices with a positive probability).
    static constexpr std::uint32_t kUnits = kProbabilityUnits;

    UnitCdf() = default;
    /// `units[i]` is index i's probability in units of 2^-23; they must sum to 2^23 exactly
    /// (throws Error(Internal) otherwise, or when `units` is empty).
    explicit UnitCdf(const std::vector<std::uint32_t>& units);

    std::size_t size() const { return cdf_.empty() ? 0 : cdf_.size() - 1; }
    /// The index whose range holds the 32-bit uniform `u` (its unit u >> 9).
    std::uint32_t find(std::uint32_t u) const {
        // The last index whose range starts at or before u's unit: ranges of zero units are
        // empty and upper_bound steps over them.
        const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u >> kLowBits);
        return std::uint32_t(it - (cdf_.begin() + 1));
    }
    /// The index whose range holds the 32-bit uniform `u`, and in `remapped` the position of u
    /// inside that range as a float in [0, 1): the centre of u's share of the range (one of
    /// units * 2^9 equal parts), rounded down to a multiple of 2^-24.
    std::uint32_t sample(std::uint32_t u, float* remapped) const;
    /// Probability of index i: units(i) * 2^-23, a float exactly (0 outside the range).
    float pmf(std::size_t i) const { return i < size() ? float(units(i)) * 0x1p-23f : 0.f; }
    std::uint32_t units(std::size_t i) const { return cdf_[i + 1] - cdf_[i]; }
    /// The first unit of index i's range (cdf(size()) = 2^23).
    std::uint32_t cdf(std::size_t i) const { return cdf_[i]; }

  private:
    static constexpr int kLowBits = 32 - kProbabilityUnitBits; ///< 32-bit values per unit: 2^9
    std::vector<std::uint32_t> cdf_; ///< size n + 1, cdf_[0] = 0, cdf_[n] = 2^23
};

/// Rounds non-negative `weights` to units of 2^-23 summing to 2^23 exactly, for any number of
/// weights up to 2^23: every share is rounded down, but a positive weight gets at least one unit
/// (nothing that weighs is ever left out); the units still missing go one each to the largest
/// remainders, so every share is within one unit of its exact value, unless the one-unit
/// minimums overshoot, when the excess is taken back one unit at a time from the largest
/// shares. Zero weights get zero units, unless every weight is zero, when the result is uniform
/// (the first 2^23 mod n indices one unit more). Throws Error(Internal) for an empty table, a
/// negative or non-finite weight, or more positive weights than units.
std::vector<std::uint32_t> round_to_units(const std::vector<double>& weights);

/// The sum of `weights` and how many are positive.
struct WeightSum {
    double sum = 0.0;
    std::size_t positive = 0;
};
/// WeightSum of `weights`; throws Error(Internal), worded as from `who`, for an empty table or a
/// negative or non-finite weight (naming its index).
WeightSum checked_weight_sum(const std::vector<double>& weights, const char* who);

/// Rounds non-negative `weights` to units of 2^-23 summing to kProbabilityUnits, with a floor:
/// every positive weight gets at least `floor_share` / (number of positive weights) of the total
/// (mixed in as (1 - floor_share) w / sum + floor_share / m) and never less than one unit; every
/// index but the largest is rounded to the nearest unit and the largest takes what is left.
/// Zero weights get zero units, unless every weight is zero, when the result is uniform. Throws
/// Error(Internal) for an empty table, a negative or non-finite weight, or more weights than
/// units. (The light sampler's rounding; round_to_units() is the environment's and the meshes'.)
std::vector<std::uint32_t> weights_to_units(const std::vector<double>& weights, double floor_share);

} // namespace candela
