// The exact alias table: every index is chosen by exactly pmf * 2^32 of the 32-bit uniforms.
#include "candela/sampling/alias_table.h"
#include "candela/sampling/rng.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;

namespace {

/// The number of 32-bit values choosing each index, counted from the table's buckets and
/// thresholds (bucket i = [ceil(i 2^32 / n), ceil((i+1) 2^32 / n)), recomputed here), and a
/// check that sample() agrees at both ends of every run of values that choose one index.
std::vector<std::uint64_t> count_choices(const AliasTable& t) {
    const std::uint64_t n = t.size();
    std::vector<std::uint64_t> count(n, 0);
    auto begin = [n](std::uint64_t i) { return ((i << 32) + n - 1) / n; };
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t b = begin(i), e = begin(i + 1), thr = t.threshold(i);
        REQUIRE(b == t.bucket_begin(i));
        REQUIRE(thr >= b);
        REQUIRE(thr <= e);
        REQUIRE(t.alias(i) < n);
        count[i] += thr - b;
        count[t.alias(i)] += e - thr;
        // Both ends of both runs.
        if (thr > b) {
            CHECK(t.sample(std::uint32_t(b)) == i);
            CHECK(t.sample(std::uint32_t(thr - 1)) == i);
        }
        if (e > thr) {
            CHECK(t.sample(std::uint32_t(thr)) == t.alias(i));
            CHECK(t.sample(std::uint32_t(e - 1)) == t.alias(i));
        }
    }
    return count;
}

void check_exact(const AliasTable& t) {
    const std::vector<std::uint64_t> count = count_choices(t);
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        INFO("index " << i << " of " << t.size());
        // pmf is a float exactly equal to the realised fraction count / 2^32: no tolerance.
        CHECK(double(t.pmf(i)) == std::ldexp(double(count[i]), -32));
        total += count[i];
    }
    CHECK(total == (std::uint64_t(1) << 32));
}

} // namespace

TEST_CASE("alias table: realised probabilities equal pmf exactly", "[sampling][quick]") {
    Pcg32 rng(2024, 11);
    for (int trial = 0; trial < 60; ++trial) {
        const std::size_t n = 1 + std::size_t(rng.next_float() * (trial < 30 ? 8 : 300));
        std::vector<double> w(n);
        for (double& x : w) {
            // Powers spread over nine decades, some exactly zero.
            const float r = rng.next_float();
            x = r < 0.1f ? 0.0 : std::pow(10.0, 9.0 * double(rng.next_float()));
        }
        const std::vector<std::uint32_t> units = weights_to_units(w, 1.0 / 64.0);
        const AliasTable t(units);
        INFO("trial " << trial << ", " << n << " weights");
        check_exact(t);
        double sum = 0.0;
        std::size_t positive = 0;
        for (double x : w) {
            sum += x;
            positive += x > 0.0;
        }
        for (std::size_t i = 0; i < n; ++i) {
            if (sum > 0.0 && w[i] == 0.0) {
                CHECK(t.pmf(i) == 0.f);
                continue;
            }
            // The floor: at least 1/64 / m of the selection, less one unit of rounding.
            const double floor = sum > 0.0 ? 1.0 / 64.0 / double(positive) : 1.0 / double(n);
            CHECK(double(t.pmf(i)) >= floor - 0x1p-23);
            // Rounding to units moves a share by at most half a unit (the largest absorbs the
            // rest, at most half a unit per other index).
            const double want = sum > 0.0 ? (63.0 / 64.0) * w[i] / sum + floor : 1.0 / double(n);
            CHECK(std::abs(double(t.pmf(i)) - want) <= 0.5 * double(n) * 0x1p-23);
        }
    }
}

TEST_CASE("alias table: whole buckets, one index and bad input", "[sampling][quick]") {
    // Equal shares of a power of two: every bucket is whole.
    const AliasTable even(std::vector<std::uint32_t>(4, AliasTable::kUnits / 4));
    check_exact(even);
    CHECK(even.sample(0u) == 0u);
    CHECK(even.sample(0xffffffffu) == 3u);
    const AliasTable one(std::vector<std::uint32_t>{AliasTable::kUnits});
    CHECK(one.sample(12345u) == 0u);
    CHECK(one.pmf(0) == 1.f);
    CHECK(one.pmf(1) == 0.f);
    // The smallest share, one unit, is realised exactly too.
    const AliasTable tiny(std::vector<std::uint32_t>{1u, AliasTable::kUnits - 1u});
    check_exact(tiny);
    CHECK(tiny.pmf(0) == 0x1p-23f);
    CHECK_THROWS_AS(AliasTable(std::vector<std::uint32_t>{}), Error);
    CHECK_THROWS_AS(AliasTable(std::vector<std::uint32_t>{1u, 2u}), Error);
    CHECK_THROWS_AS(weights_to_units({1.0, -1.0}, 0.0), Error);
    CHECK_THROWS_AS(weights_to_units({}, 0.0), Error);
    // All zero: uniform.
    const std::vector<std::uint32_t> u = weights_to_units({0.0, 0.0}, 0.0);
    CHECK(u[0] == AliasTable::kUnits / 2);
    CHECK(u[1] == AliasTable::kUnits / 2);
}
