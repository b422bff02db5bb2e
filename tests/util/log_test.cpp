#include "candela/util/error.h"
#include "candela/util/log.h"

#include <catch2/catch.hpp>

#include <string>
#include <type_traits>
#include <utility>

using namespace candela;

TEST_CASE("Warnings are counted per text, distinct texts kept apart", "[log][quick]") {
    Diagnostics diag;
    // Many distinct texts, each repeated: a mesh with many bad faces reports each message once.
    constexpr int kDistinct = 2000; // all are printed to stderr when diag is destroyed
    for (int repeat = 0; repeat < 3; ++repeat)
        for (int i = 0; i < kDistinct; ++i)
            diag.warn("mesh.dae:" + std::to_string(i), "degenerate triangle dropped");
    CHECK(diag.warning_count() == 3u * kDistinct);
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct));

    set_verbose(false);
    diag.note("scene", "suppressed when quiet");
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct));
    set_verbose(true);
    diag.note("scene", "shown when verbose");
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct) + 1);
}

TEST_CASE("Strict diagnostics turn a warning into a scene error", "[log][quick]") {
    Diagnostics diag(true);
    try {
        diag.warn("file.dae:3", "unknown element");
        FAIL("warn() did not throw under --strict");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Scene);
        CHECK(std::string(e.what()).find("file.dae:3: error: unknown element") !=
              std::string::npos);
    }
    CHECK(diag.warning_count() == 0u);
}

// A copy would print every message twice (both destructors flush); a move hands them over.
static_assert(!std::is_copy_constructible_v<Diagnostics>, "Diagnostics must not be copied");
static_assert(!std::is_copy_assignable_v<Diagnostics>, "Diagnostics must not be copied");
static_assert(std::is_nothrow_move_constructible_v<Diagnostics>, "Diagnostics moves");

TEST_CASE("A moved Diagnostics keeps its messages; the moved-from one holds none", "[log][quick]") {
    set_log_level(LogLevel::Warning);
    Diagnostics a;
    a.warn("scene.dae:7", "unknown element");
    a.warn("scene.dae:7", "unknown element");
    Diagnostics b(std::move(a));
    CHECK(b.warning_count() == 2u);
    CHECK(b.distinct_messages() == 1u);
    CHECK(a.warning_count() == 0u); // NOLINT(bugprone-use-after-move): the state is specified
    CHECK(a.distinct_messages() == 0u);
    b.flush();
    CHECK(b.distinct_messages() == 0u);
    set_log_level(LogLevel::Info);
}
