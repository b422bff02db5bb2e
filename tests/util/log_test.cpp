#include "candela/util/error.h"
#include "candela/util/log.h"

#include <catch2/catch.hpp>

#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

using namespace candela;

TEST_CASE("Warnings are counted per text, distinct texts kept apart", "[log][quick]") {
    Diagnostics diag;
    // Many distinct texts, each repeated: a mesh with many bad faces reports each message once.
    constexpr int kDistinct = 2000; // all are printed to stderr when diag is destroyed
    for (int repeat = 0; repeat < 3; ++repeat)
        for (int i = 0; i < kDistinct; ++i)
            diag.warn(SourceLoc{"mesh.dae", i}, "degenerate triangle dropped");
    CHECK(diag.warning_count() == 3u * kDistinct);
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct));

    set_verbose(false);
    diag.note(SourceLoc{"scene"}, "suppressed when quiet");
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct));
    set_verbose(true);
    diag.note(SourceLoc{"scene"}, "shown when verbose");
    CHECK(diag.distinct_messages() == static_cast<std::size_t>(kDistinct) + 1);
}

TEST_CASE("Strict diagnostics turn a warning into a scene error", "[log][quick]") {
    Diagnostics diag(true);
    try {
        diag.warn(SourceLoc{"file.dae", 3}, "unknown element");
        FAIL("warn() did not throw under --strict");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Scene);
        REQUIRE(e.where());
        CHECK(e.where()->file == "file.dae");
        CHECK(e.where()->line == 3);
        CHECK(e.message() == "unknown element (--strict)");
        CHECK(error_line(e) == "candela: error: file.dae:3: unknown element (--strict)");
    }
    CHECK(diag.warning_count() == 0u);
}

// A copy would print every message twice (both destructors flush); a move hands them over.
static_assert(!std::is_copy_constructible_v<Diagnostics>, "Diagnostics must not be copied");
static_assert(!std::is_copy_assignable_v<Diagnostics>, "Diagnostics must not be copied");
static_assert(std::is_nothrow_move_constructible_v<Diagnostics>, "Diagnostics moves");

TEST_CASE("A moved Diagnostics keeps its messages and the moved-from one holds none",
          "[log][quick]") {
    set_log_level(LogLevel::Warning);
    Diagnostics a;
    a.warn(SourceLoc{"scene.dae", 7}, "unknown element");
    a.warn(SourceLoc{"scene.dae", 7}, "unknown element");
    Diagnostics b(std::move(a));
    CHECK(b.warning_count() == 2u);
    CHECK(b.distinct_messages() == 1u);
    CHECK(a.warning_count() == 0u); // NOLINT(bugprone-use-after-move): the state is specified
    CHECK(a.distinct_messages() == 0u);
    b.flush();
    CHECK(b.distinct_messages() == 0u);
    set_log_level(LogLevel::Info);
}

TEST_CASE("Warnings from many threads at once are all counted, each text kept once",
          "[log][quick]") {
    set_log_level(LogLevel::Warning);
    constexpr int kThreads = 8, kPerThread = 5000, kTexts = 3;
    // Fresh objects, warned by every thread from the start: the threads race on the first
    // record as well as on the count.
    for (int round = 0; round < 4; ++round) {
        Diagnostics diag;
        std::vector<std::thread> threads;
        for (int t = 0; t < kThreads; ++t)
            threads.emplace_back([&diag] {
                for (int i = 0; i < kPerThread; ++i)
                    diag.warn(SourceLoc{"many.dae", 1 + i % kTexts}, "shared warning");
            });
        for (std::thread& t : threads)
            t.join();
        CHECK(diag.warning_count() == std::size_t(kThreads) * kPerThread);
        CHECK(diag.distinct_messages() == std::size_t(kTexts));
        diag.flush(); // three lines, with their counts
    }
    set_log_level(LogLevel::Info);
}

TEST_CASE("print_warning and warn_or_refuse: one shape, the log level and --strict",
          "[log][quick]") {
    CHECK(warning_text("x") == "candela: warning: x");
    CHECK(warning_text("y", "compare") == "compare: warning: y");
    CHECK(strict_text("z") == "z (--strict)");
    CHECK_THROWS_WITH(warn_or_refuse("the camera is outside", true, ErrorKind::Scene),
                      "the camera is outside (--strict)");
    try {
        warn_or_refuse("w", true, ErrorKind::Usage);
        FAIL("--strict must refuse");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Usage);
    }
    CHECK_NOTHROW(warn_or_refuse("w", false, ErrorKind::Usage));
}
