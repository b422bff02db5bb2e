#include "candela/util/error.h"
#include "candela/util/log.h"

#include <catch2/catch.hpp>

#include <string>

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
