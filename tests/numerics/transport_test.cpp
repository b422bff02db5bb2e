// Stiff light transport and guard cases of the numerical-stability suite. The cases live in the
// library (src/numerics/transport_*.cpp) so that tools/numerics_report prints the same figures;
// each test runs one group of cases at the Quick size and requires every row to meet its
// expectation (rows marked reported_only document a limit and carry no requirement).
#include "candela/numerics/transport_cases.h"

#include <catch2/catch.hpp>

using namespace candela::numerics;

namespace {

/// Checks every row with a requirement and that the case produced the rows it documents.
void check_rows(const std::vector<StressResult>& rows, std::size_t expected_rows) {
    REQUIRE(rows.size() == expected_rows);
    for (const StressResult& r : rows) {
        INFO(r.name << " | " << r.method << " | expected " << r.expected << " | measured "
                    << r.measured);
        CHECK(!r.group.empty());
        if (r.reported_only) continue;
        CHECK(r.pass);
    }
}

} // namespace

TEST_CASE("stiff transport: furnace with albedo 0.99 and 0.999, roulette on and off",
          "[numerics][stat]") {
    // Two albedos x (radiance, path length) + the truncated series without roulette.
    check_rows(furnace_cases(StressSize::Quick), 5);
}

TEST_CASE("stiff transport: near-delta microfacet alpha 1e-4 and 1e-3", "[numerics][stat]") {
    // Two alphas x (three BSDF-level angles + two rendered angles).
    check_rows(near_delta_microfacet_cases(StressSize::Quick), 10);
}

TEST_CASE("stiff transport: glass IOR 1.0001 and 3.5, total internal reflection trap",
          "[numerics][stat]") {
    // Enclosure: 2 IORs x (sphere, cube); slab: with and without; TIR trap: 2 views.
    check_rows(dielectric_cases(StressSize::Quick), 8);
}

TEST_CASE("stiff transport: conductor with k = 0", "[numerics][stat]") {
    check_rows(conductor_k0_cases(StressSize::Quick), 3);
}

TEST_CASE("stiff transport: 1e-6-area light of radiance 1e8 beside a dim large light",
          "[numerics][stat]") {
    const std::vector<StressResult> rows = tiny_light_cases(StressSize::Quick);
    check_rows(rows, 3);
    // The hemisphere-sampling row is a documented limit, but it must still be finite.
    CHECK(rows.back().reported_only);
    CHECK(rows.back().pass);
}

TEST_CASE("stiff transport: camera inside closed objects", "[numerics][quick]") {
    check_rows(camera_inside_cases(StressSize::Quick), 6);
}

TEST_CASE("guards: extreme inputs to BSDF and light functions, poisoned render",
          "[numerics][quick]") {
    check_rows(guard_cases(), 6);
}
