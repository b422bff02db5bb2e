#pragma once
// Exact counts of the 32-bit uniforms that choose each index of a discrete choice made by
// inverting a CDF: the realised probability of index k is count[k] / 2^32, with no sampling
// error, to compare with the probability the estimator divides by.
#include <catch2/catch.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela::test {

/// The number of 32-bit values u for which choose(u) == k, for every k < n. `choose` must be
/// monotone non-decreasing in u (an inverted CDF is): the first u choosing at least k is found
/// by bisection (33 calls per index) and index k holds the values from there to the next one's
/// first. Both ends of every non-empty run are checked to choose k.
template <typename Choose>
std::vector<std::uint64_t> monotone_choice_counts(const Choose& choose, std::size_t n) {
    constexpr std::uint64_t kValues = std::uint64_t(1) << 32;
    std::vector<std::uint64_t> first(n + 1, kValues);
    first[0] = 0;
    for (std::size_t k = 1; k < n; ++k) {
        std::uint64_t lo = first[k - 1], hi = kValues;
        while (lo < hi) {
            const std::uint64_t mid = lo + (hi - lo) / 2;
            if (std::size_t(choose(std::uint32_t(mid))) >= k)
                hi = mid;
            else
                lo = mid + 1;
        }
        first[k] = lo;
    }
    std::vector<std::uint64_t> count(n);
    for (std::size_t k = 0; k < n; ++k) {
        count[k] = first[k + 1] - first[k];
        if (count[k] == 0) continue;
        INFO("index " << k << ", values [" << first[k] << ", " << first[k + 1] << ")");
        CHECK(std::size_t(choose(std::uint32_t(first[k]))) == k);
        CHECK(std::size_t(choose(std::uint32_t(first[k + 1] - 1))) == k);
    }
    return count;
}

/// The middle 32-bit value of index k's run of values (`count` from monotone_choice_counts), for
/// probing what a choice does inside one index's values.
inline std::uint32_t run_middle(const std::vector<std::uint64_t>& count, std::size_t k) {
    std::uint64_t begin = 0;
    for (std::size_t i = 0; i < k; ++i)
        begin += count[i];
    return std::uint32_t(begin + count[k] / 2);
}

} // namespace candela::test
