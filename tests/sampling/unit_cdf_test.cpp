// The integer CDF: every index is chosen by exactly pmf * 2^32 of the 32-bit uniforms, and the
// rounding of weights to units keeps every positive weight.
#include "candela/sampling/rng.h"
#include "candela/sampling/unit_cdf.h"
#include "candela/util/error.h"

#include "../support/exact_count.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// Checks that the values of u choosing each index, counted exactly, are pmf * 2^32: the
/// realised probability equals pmf() to within 2^-32 (in fact exactly).
void check_exact(const UnitCdf& t) {
    const std::vector<std::uint64_t> count = monotone_choice_counts(
        [&t](std::uint32_t u) {
            float remapped = 0.f;
            return t.sample(u, &remapped);
        },
        t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
        INFO("index " << i << " of " << t.size() << ": " << count[i] << " values, pmf "
                      << t.pmf(i));
        CHECK(std::abs(std::ldexp(double(count[i]), -32) - double(t.pmf(i))) <= 0x1p-32);
        CHECK(std::ldexp(double(count[i]), -32) == double(t.pmf(i)));
    }
}

} // namespace

TEST_CASE("unit CDF: realised probabilities equal pmf exactly", "[sampling][quick]") {
    Pcg32 rng(2025, 3);
    for (int trial = 0; trial < 40; ++trial) {
        const std::size_t n = 1 + std::size_t(rng.next_float() * (trial < 20 ? 8 : 400));
        std::vector<double> w(n);
        for (double& x : w) {
            // Weights spread over twelve decades, some exactly zero.
            const float r = rng.next_float();
            x = r < 0.1f ? 0.0 : std::pow(10.0, 12.0 * double(rng.next_float()));
        }
        INFO("trial " << trial << ", " << n << " weights");
        const std::vector<std::uint32_t> units = round_to_units(w);
        const UnitCdf t(units);
        check_exact(t);
        double sum = 0.0;
        for (double x : w)
            sum += x;
        bool overshoot = false; // the one-unit minimums took units from the largest shares
        std::uint64_t given = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const double share = sum > 0.0 ? w[i] / sum * UnitCdf::kUnits : 0.0;
            given += w[i] > 0.0 ? std::max<std::uint64_t>(1, std::uint64_t(share)) : 0;
        }
        overshoot = sum > 0.0 && given > UnitCdf::kUnits;
        for (std::size_t i = 0; i < n; ++i) {
            if (sum > 0.0 && w[i] == 0.0) {
                CHECK(units[i] == 0u);
                continue;
            }
            // Nothing that weighs is left out, and rounding moves a share by under one unit.
            CHECK(units[i] >= 1u);
            const double share =
                sum > 0.0 ? w[i] / sum * UnitCdf::kUnits : double(UnitCdf::kUnits) / double(n);
            if (!overshoot) CHECK(std::abs(double(units[i]) - share) < 1.0 + 1e-6);
        }
    }
}

TEST_CASE("unit CDF: a weight 1e6 times the rest and one near zero", "[sampling][quick]") {
    // A float CDF inverted by a 24-bit float realises multiples of 2^-24 only, and gives the
    // near-zero weight behind the large one an interval of zero width: both checks below fail.
    std::vector<double> w(64, 1.0);
    w[17] = 1e6;
    w[18] = 1e-9;
    const UnitCdf t(round_to_units(w));
    check_exact(t);
    CHECK(t.units(18) == 1u); // chosen, with the one unit it is given
    CHECK(t.pmf(17) > 0.98f);
}

TEST_CASE("unit CDF: the remapped coordinate covers its index's range evenly",
          "[sampling][quick]") {
    const UnitCdf t(std::vector<std::uint32_t>{1u, UnitCdf::kUnits - 2u, 1u});
    // Index 0 holds u in [0, 512): the centres (2k + 1) / 1024, exact, averaging 1/2.
    double sum = 0.0;
    float previous = -1.f;
    for (std::uint32_t u = 0; u < 512; ++u) {
        float x = 0.f;
        REQUIRE(t.sample(u, &x) == 0u);
        CHECK(x == float(2 * u + 1) / 1024.f);
        CHECK(x > previous);
        previous = x;
        sum += x;
    }
    CHECK(sum / 512.0 == 0.5);
    float x = 0.f;
    CHECK(t.sample(512u, &x) == 1u);
    CHECK(x >= 0.f);
    CHECK(t.sample(0xffffffffu, &x) == 2u);
    CHECK(x < 1.f);
    // One index holding everything: u itself, at 24 bits.
    const UnitCdf one(std::vector<std::uint32_t>{UnitCdf::kUnits});
    CHECK(one.sample(0x80000000u, &x) == 0u);
    CHECK(x == 0.5f);
    CHECK(one.sample(0xffffffffu, &x) == 0u);
    CHECK(x < 1.f);
}

TEST_CASE("unit CDF: rounding many weights", "[sampling][quick]") {
    // 6500 equal weights: each share is 1290.6 units; round-to-nearest for each would hand out
    // 6500 * 0.4 units more than there are.
    {
        const std::vector<std::uint32_t> u = round_to_units(std::vector<double>(6500, 1.0));
        for (std::uint32_t x : u)
            CHECK((x == 1290u || x == 1291u));
        CHECK_NOTHROW(UnitCdf(u));
    }
    // 100000 weights of which all but one are far below a unit: each keeps one unit, paid for
    // by the large one.
    {
        std::vector<double> w(100000, 1e-12);
        w[5] = 1.0;
        const std::vector<std::uint32_t> u = round_to_units(w);
        CHECK(u[5] == UnitCdf::kUnits - 99999u);
        CHECK(u[0] == 1u);
        CHECK(u[99999] == 1u);
        check_exact(UnitCdf(u));
    }
    // All zero: uniform, 2^23 = 3 * 2796202 + 2, the remainder one each to the first two.
    {
        const std::vector<std::uint32_t> u = round_to_units({0.0, 0.0, 0.0});
        CHECK(u[0] == UnitCdf::kUnits / 3 + 1);
        CHECK(u[1] == UnitCdf::kUnits / 3 + 1);
        CHECK(u[2] == UnitCdf::kUnits / 3);
    }
    CHECK_THROWS_AS(round_to_units({}), Error);
    CHECK_THROWS_AS(round_to_units({1.0, -1.0}), Error);
    CHECK_THROWS_AS(round_to_units({1.0, std::nan("")}), Error);
    CHECK_THROWS_AS(UnitCdf(std::vector<std::uint32_t>{}), Error);
    CHECK_THROWS_AS(UnitCdf(std::vector<std::uint32_t>{1u, 2u}), Error);
    CHECK_THROWS_AS(UnitCdf(std::vector<std::uint32_t>{UnitCdf::kUnits, 1u}), Error);
}

TEST_CASE("weights_to_units: floors, nearest units and bad input", "[sampling][quick]") {
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
        INFO("trial " << trial << ", " << n << " weights");
        REQUIRE(units.size() == n);
        // A valid table: the units sum to probability 1, and the chooser realises them exactly.
        const UnitCdf cdf(units);
        check_exact(cdf);
        double sum = 0.0;
        std::size_t positive = 0;
        for (double x : w) {
            sum += x;
            positive += x > 0.0;
        }
        for (std::size_t i = 0; i < n; ++i) {
            const double pmf = double(units[i]) * 0x1p-23;
            if (sum > 0.0 && w[i] == 0.0) {
                CHECK(units[i] == 0u);
                continue;
            }
            // The floor: at least 1/64 / m of the selection, less one unit of rounding.
            const double floor = sum > 0.0 ? 1.0 / 64.0 / double(positive) : 1.0 / double(n);
            CHECK(pmf >= floor - 0x1p-23);
            // Rounding to units moves a share by at most half a unit (the largest absorbs the
            // rest, at most half a unit per other index).
            const double want = sum > 0.0 ? (63.0 / 64.0) * w[i] / sum + floor : 1.0 / double(n);
            CHECK(std::abs(pmf - want) <= 0.5 * double(n) * 0x1p-23);
        }
    }
    CHECK_THROWS_AS(weights_to_units({1.0, -1.0}, 0.0), Error);
    CHECK_THROWS_AS(weights_to_units({}, 0.0), Error);
    // All zero: uniform.
    const std::vector<std::uint32_t> u = weights_to_units({0.0, 0.0}, 0.0);
    CHECK(u[0] == kProbabilityUnits / 2);
    CHECK(u[1] == kProbabilityUnits / 2);
}
