#pragma once
// A discrete distribution whose realised probabilities are exactly the ones it reports.
//
// Probabilities are whole multiples of 2^-23 ("units"): every such value is a float exactly,
// so pmf() needs no rounding. A choice is made from one raw 32-bit uniform u by Walker's alias
// method in integer arithmetic (A. J. Walker, "An Efficient Method for Generating Discrete
// Random Variables with General Distributions", ACM TOMS 3(3), 1977; the worklist construction
// of M. D. Vose, IEEE TSE 17(9), 1991): bucket i = floor(u n / 2^32) holds the 32-bit values
// [ceil(i 2^32 / n), ceil((i + 1) 2^32 / n)); below the bucket's integer threshold the choice is
// i, above it the bucket's alias. Each index is therefore chosen by an exact number of the 2^32
// values of u, and that number is units(i) * 2^9 by construction: with a uniform 32-bit u the
// realised probability equals pmf() with no error at all.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela {

class AliasTable {
  public:
    /// log2 of the number of units in probability 1.
    static constexpr int kUnitBits = 23;
    static constexpr std::uint32_t kUnits = std::uint32_t(1) << kUnitBits;

    AliasTable() = default;
    /// `units[i]` is index i's probability in units of 2^-23; they must sum to kUnits exactly
    /// (throws Error(Internal) otherwise, or when `units` is empty).
    explicit AliasTable(const std::vector<std::uint32_t>& units);

    std::size_t size() const { return units_.size(); }
    /// The index chosen by the 32-bit uniform `u`. O(1), no branch on the table's contents.
    std::uint32_t sample(std::uint32_t u) const {
        const auto i = std::uint32_t((std::uint64_t(u) * units_.size()) >> 32);
        const Entry& e = entries_[i];
        return u < e.threshold ? i : e.alias;
    }
    /// Probability of index i: units(i) * 2^-23, a float exactly (0 outside the range).
    float pmf(std::size_t i) const { return i < units_.size() ? float(units_[i]) * 0x1p-23f : 0.f; }
    std::uint32_t units(std::size_t i) const { return units_[i]; }
    /// The first 32-bit value of bucket i (bucket n starts at 2^32).
    std::uint64_t bucket_begin(std::size_t i) const {
        return ((std::uint64_t(i) << 32) + units_.size() - 1) / units_.size();
    }
    /// Bucket i chooses i for u < threshold(i) and alias(i) from there to its end.
    std::uint32_t threshold(std::size_t i) const { return entries_[i].threshold; }
    std::uint32_t alias(std::size_t i) const { return entries_[i].alias; }

  private:
    struct Entry {
        std::uint32_t threshold; ///< absolute: values of u below it (in the bucket) choose i
        std::uint32_t alias;
    };
    std::vector<Entry> entries_;
    std::vector<std::uint32_t> units_;
};

/// The sum of `weights` and how many are positive.
struct WeightSum {
    double sum = 0.0;
    std::size_t positive = 0;
};
/// WeightSum of `weights`; throws Error(Internal), worded as from `who`, for an empty table or a
/// negative or non-finite weight (naming its index).
WeightSum checked_weight_sum(const std::vector<double>& weights, const char* who);

/// Rounds non-negative `weights` to units of 2^-23 summing to AliasTable::kUnits, with a floor:
/// every positive weight gets at least `floor_share` / (number of positive weights) of the total
/// (mixed in as (1 - floor_share) w / sum + floor_share / m) and never less than one unit. Zero
/// weights get zero units, unless every weight is zero, when the result is uniform. Throws
/// Error(Internal) for an empty table, a negative or non-finite weight, or more weights than
/// units.
std::vector<std::uint32_t> weights_to_units(const std::vector<double>& weights, double floor_share);

} // namespace candela
