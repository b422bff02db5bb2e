// The alias table in exact integer units and the rounding of weights to those units.
#include "candela/sampling/alias_table.h"

#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

AliasTable::AliasTable(const std::vector<std::uint32_t>& units) : units_(units) {
    const std::size_t n = units.size();
    CANDELA_CHECK(n > 0, "AliasTable: empty table");
    std::uint64_t total = 0;
    for (std::uint32_t u : units)
        total += u;
    CANDELA_CHECK(total == kUnits,
                  "AliasTable: units sum to " + std::to_string(total) + ", not 2^23");
    // Demands in 32-bit values (units * 2^9) against each bucket's capacity, both exact
    // integers; Vose's worklists pair a bucket whose index wants less than its capacity with one
    // that wants more. The sums of demands and capacities of the unfinished indices stay equal,
    // so whatever is left at the end wants exactly its capacity.
    constexpr int kShift = 32 - kUnitBits;
    std::vector<std::uint64_t> demand(n), begin(n + 1);
    for (std::size_t i = 0; i <= n; ++i)
        begin[i] = bucket_begin(i);
    std::vector<std::uint32_t> small, large;
    for (std::size_t i = 0; i < n; ++i) {
        demand[i] = std::uint64_t(units[i]) << kShift;
        (demand[i] < begin[i + 1] - begin[i] ? small : large).push_back(std::uint32_t(i));
    }
    entries_.assign(n, Entry{0u, 0u});
    while (!small.empty() && !large.empty()) {
        const std::uint32_t s = small.back(), l = large.back();
        small.pop_back();
        const std::uint64_t capacity = begin[s + 1] - begin[s];
        entries_[s] = Entry{std::uint32_t(begin[s] + demand[s]), l};
        demand[l] -= capacity - demand[s];
        if (demand[l] < begin[l + 1] - begin[l]) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // Whole buckets: every value chooses the index itself (the alias is never reached).
    for (const std::vector<std::uint32_t>* rest : {&small, &large})
        for (std::uint32_t i : *rest)
            entries_[i] = Entry{std::uint32_t(begin[i]), i};
}

WeightSum checked_weight_sum(const std::vector<double>& weights, const char* who) {
    CANDELA_CHECK(!weights.empty(), std::string(who) + ": empty table");
    WeightSum s;
    for (std::size_t i = 0; i < weights.size(); ++i) {
        CANDELA_CHECK(std::isfinite(weights[i]) && weights[i] >= 0.0,
                      std::string(who) + ": weight " + std::to_string(weights[i]) + " at index " +
                          std::to_string(i));
        s.sum += weights[i];
        s.positive += weights[i] > 0.0;
    }
    return s;
}

std::vector<std::uint32_t> weights_to_units(const std::vector<double>& weights,
                                            double floor_share) {
    const std::size_t n = weights.size();
    CANDELA_CHECK(n <= AliasTable::kUnits,
                  "weights_to_units: " + std::to_string(n) + " weights exceed 2^23 units");
    const WeightSum checked = checked_weight_sum(weights, "weights_to_units");
    const double sum = checked.sum;
    const std::size_t positive = checked.positive;
    std::vector<std::uint32_t> units(n, 0u);
    auto share = [&](std::size_t i) {
        if (!(sum > 0.0)) return 1.0 / double(n);
        if (!(weights[i] > 0.0)) return 0.0;
        return (1.0 - floor_share) * weights[i] / sum + floor_share / double(positive);
    };
    // Every index but the largest is rounded to the nearest unit (at least one when its share is
    // positive); the largest takes what is left, which rounding cannot push below half its
    // share while there are fewer than 2^22 indices.
    std::size_t largest = 0;
    for (std::size_t i = 1; i < n; ++i)
        if (share(i) > share(largest)) largest = i;
    std::uint64_t taken = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (i == largest) continue;
        const double s = share(i);
        if (!(s > 0.0)) continue;
        units[i] = std::max<std::uint32_t>(1u, std::uint32_t(std::llround(s * AliasTable::kUnits)));
        taken += units[i];
    }
    CANDELA_CHECK(taken < AliasTable::kUnits, "weights_to_units: the table's floors exceed 1");
    units[largest] = std::uint32_t(AliasTable::kUnits - taken);
    return units;
}

} // namespace candela
