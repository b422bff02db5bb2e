#pragma once
// The CS184 course scenes beside the repository (../shared/scenes/cs184). They are not part of
// candela, so a clone without them must still pass its whole suite: a test that reads them
// starts with CANDELA_SKIP_WITHOUT_CS184(), which ends it with a "SKIPPED:" warning when the
// folder is absent. tests/CMakeLists.txt registers every test with that marker as CTest's
// SKIP_REGULAR_EXPRESSION, so CTest reports such a test as skipped, not passed.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace candela::test {

/// The folder of the CS184 scenes: CANDELA_CS184_SCENES from the environment when set (to
/// check the skip path in a full checkout), else ../shared/scenes/cs184 from the source tree.
inline const std::string& cs184_dir() {
    static const std::string dir = [] {
        const char* env = std::getenv("CANDELA_CS184_SCENES");
        return env ? std::string(env) : std::string(CANDELA_SHARED_SCENES);
    }();
    return dir;
}

inline bool cs184_available() {
    std::error_code ec;
    return std::filesystem::is_directory(cs184_dir(), ec);
}

/// Path of one CS184 scene (check cs184_available() first).
inline std::string cs184_scene(const std::string& name) {
    return cs184_dir() + "/" + name;
}

/// Path of one of candela's own scenes (scenes/ in the repository).
inline std::string project_scene(const std::string& name) {
    return std::string(CANDELA_PROJECT_SCENES) + "/" + name;
}

} // namespace candela::test

/// Ends the current test case, reported as skipped by CTest, when the CS184 scenes are absent.
#define CANDELA_SKIP_WITHOUT_CS184()                                                               \
    do {                                                                                           \
        if (!candela::test::cs184_available()) {                                                   \
            WARN("SKIPPED: needs the CS184 scenes in " << candela::test::cs184_dir()               \
                                                       << ", which this clone does not have "      \
                                                          "(README \"Tests\")");                   \
            return;                                                                                \
        }                                                                                          \
    } while (0)
