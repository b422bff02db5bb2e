// The integer CDF in units of 2^-23 and the roundings of weights to those units.
#include "candela/sampling/unit_cdf.h"

#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace candela {

UnitCdf::UnitCdf(const std::vector<std::uint32_t>& units) {
    CANDELA_CHECK(!units.empty(), "UnitCdf: empty table");
    cdf_.resize(units.size() + 1);
    cdf_[0] = 0;
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < units.size(); ++i) {
        total += units[i];
        if (total > kProbabilityUnits) break;
        cdf_[i + 1] = std::uint32_t(total);
    }
    CANDELA_CHECK(total == kProbabilityUnits,
                  "UnitCdf: units sum to " +
                      std::string(total > kProbabilityUnits ? "more than " : "") +
                      std::to_string(total) + ", not 2^23");
}

std::uint32_t UnitCdf::sample(std::uint32_t u, float* remapped) const {
    const std::uint32_t i = find(u);
    // u's offset among the units(i) * 2^9 values of the range; the centre of its part of
    // [0, 1), (offset + 1/2) / (units * 2^9), in 24-bit fixed point: (2 offset + 1) 2^14 /
    // units, below 2^24 because offset < units * 2^9.
    const std::uint32_t offset = u - (cdf_[i] << kLowBits);
    const std::uint64_t fixed = ((std::uint64_t(offset) * 2u + 1u) << (24 - kLowBits - 1)) /
                                std::uint64_t(cdf_[i + 1] - cdf_[i]);
    *remapped = float(fixed) * 0x1p-24f;
    return i;
}

std::vector<std::uint32_t> round_to_units(const std::vector<double>& weights) {
    const std::size_t n = weights.size();
    const WeightSum checked = checked_weight_sum(weights, "round_to_units");
    const double sum = checked.sum;
    const std::size_t positive = checked.positive;
    const std::size_t counted = positive > 0 ? positive : n;
    CANDELA_CHECK(counted <= kProbabilityUnits,
                  "round_to_units: " + std::to_string(counted) + " weights exceed 2^23 units");
    std::vector<std::uint32_t> units(n, 0u);
    if (positive == 0 || !std::isfinite(sum)) {
        if (positive > 0) // the sum overflows: weigh every positive weight alike
            for (std::size_t i = 0; i < n; ++i)
                units[i] = weights[i] > 0.0 ? 1u : 0u;
        else
            units.assign(n, 1u);
        // Spread 2^23 over the chosen indices as evenly as integers allow.
        const auto m = std::uint32_t(counted);
        std::uint32_t k = 0;
        for (std::size_t i = 0; i < n; ++i) {
            if (!units[i]) continue;
            units[i] = kProbabilityUnits / m + (k < kProbabilityUnits % m ? 1u : 0u);
            ++k;
        }
        return units;
    }
    // Exact shares in units, their floors (at least one unit each) and what is left over.
    const double scale = double(kProbabilityUnits) / sum;
    std::vector<double> share(n);
    std::int64_t given = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!(weights[i] > 0.0)) continue;
        share[i] = weights[i] * scale;
        units[i] = std::max<std::uint32_t>(1u, std::uint32_t(std::floor(share[i])));
        given += units[i];
    }
    std::int64_t left = std::int64_t(kProbabilityUnits) - given;
    std::vector<std::uint32_t> order;
    order.reserve(positive);
    for (std::size_t i = 0; i < n; ++i)
        if (weights[i] > 0.0) order.push_back(std::uint32_t(i));
    if (left > 0) {
        // Largest remainders first (ties by index, so the result is deterministic); the
        // remainders add up to `left` up to rounding, and any rounding excess cycles on.
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const double ra = share[a] - units[a], rb = share[b] - units[b];
            return ra != rb ? ra > rb : a < b;
        });
        for (std::size_t k = 0; left > 0; k = (k + 1) % order.size(), --left)
            ++units[order[k]];
    } else if (left < 0) {
        // The one-unit minimums overshot: take the excess back from the largest shares, one
        // unit each per round (there is enough: at most 2^23 indices hold one unit each).
        // Only indices above one unit can give; an index leaves the list when it gets down to
        // one, so the work is the excess plus the number of indices.
        std::vector<std::uint32_t> donors;
        for (std::uint32_t i : order)
            if (units[i] > 1u) donors.push_back(i);
        std::sort(donors.begin(), donors.end(), [&](std::uint32_t a, std::uint32_t b) {
            return share[a] != share[b] ? share[a] > share[b] : a < b;
        });
        while (left < 0) {
            CANDELA_CHECK(!donors.empty(), "round_to_units: no unit to take back");
            for (std::size_t k = 0; k < donors.size() && left < 0; ++k) {
                --units[donors[k]];
                ++left;
            }
            donors.erase(std::remove_if(donors.begin(), donors.end(),
                                        [&](std::uint32_t i) { return units[i] <= 1u; }),
                         donors.end());
        }
    }
    return units;
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
    CANDELA_CHECK(n <= kProbabilityUnits,
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
        units[i] = std::max<std::uint32_t>(1u, std::uint32_t(std::llround(s * kProbabilityUnits)));
        taken += units[i];
    }
    CANDELA_CHECK(taken < kProbabilityUnits, "weights_to_units: the table's floors exceed 1");
    units[largest] = std::uint32_t(kProbabilityUnits - taken);
    return units;
}

} // namespace candela
