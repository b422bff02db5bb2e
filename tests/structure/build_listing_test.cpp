// The build lists its sources by name (CMakeLists.txt, tests/CMakeLists.txt): none is globbed,
// and none in the tree is left out of the lists, which would leave a file uncompiled or a test
// file silently unrun.
#include "../support/source_text.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using candela::test::read_text;

namespace {

/// Paths (relative to `base`, '/'-separated) of the files under `dir` whose names end in `suffix`.
std::vector<std::string> files_ending(const fs::path& base, const fs::path& dir,
                                      const std::string& suffix) {
    std::vector<std::string> out;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
        const std::string name = entry.path().filename().string();
        if (!entry.is_regular_file() || name.size() < suffix.size() ||
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        out.push_back(fs::relative(entry.path(), base).generic_string());
    }
    return out;
}

} // namespace

TEST_CASE("build: no source list is globbed", "[structure][quick]") {
    const fs::path root = CANDELA_SOURCE_DIR;
    for (const fs::path& list :
         {root / "CMakeLists.txt", root / "cmake" / "LoaderSources.cmake",
          root / "tests" / "CMakeLists.txt", root / "tools" / "fuzz" / "CMakeLists.txt"}) {
        INFO(list.string());
        const std::string text = read_text(list);
        REQUIRE(!text.empty());
        CHECK(text.find("file(GLOB") == std::string::npos);
    }
}

TEST_CASE("build: every source, tool and test file is listed", "[structure][quick]") {
    const fs::path root = CANDELA_SOURCE_DIR;
    // The loader's sources are listed in cmake/LoaderSources.cmake (shared with the fuzz build).
    const std::string build =
        read_text(root / "CMakeLists.txt") + read_text(root / "cmake" / "LoaderSources.cmake");
    const std::string tests = read_text(root / "tests" / "CMakeLists.txt");
    std::vector<std::string> missing;
    std::size_t seen = 0;
    for (const char* dir : {"src", "tools"})
        for (const std::string& f : files_ending(root, root / dir, ".cpp")) {
            // tools/fuzz/ is built by its own script (tools/fuzz.sh build, part of the test
            // command) with the fuzzing compiler.
            if (f.rfind("tools/fuzz/", 0) == 0) continue;
            ++seen;
            if (build.find(f) == std::string::npos) missing.push_back(f + " (CMakeLists.txt)");
        }
    for (const std::string& f : files_ending(root / "tests", root / "tests", "_test.cpp")) {
        ++seen;
        if (tests.find(f) == std::string::npos) missing.push_back(f + " (tests/CMakeLists.txt)");
    }
    CHECK(seen > 100); // the scan found the tree
    for (const std::string& m : missing)
        UNSCOPED_INFO("not listed: " << m);
    CHECK(missing.empty());
}

TEST_CASE("build: no test name starts with a dash or holds a semicolon", "[structure][quick]") {
    // CTest runs each test case by passing its name to the test binary, which would read a name
    // such as "--flag does X" as an option and fail without running the test. And CMake splits
    // the list of names at ';', registering two halves that select no test (with -w NoTests
    // they fail; before it, eleven such tests passed without running).
    std::vector<std::string> bad;
    const auto& all = Catch::getRegistryHub().getTestCaseRegistry().getAllTests();
    for (const Catch::TestCase& t : all) {
        const std::string& name = t.getTestCaseInfo().name;
        if ((!name.empty() && name[0] == '-') || name.find(';') != std::string::npos)
            bad.push_back(name);
    }
    CHECK(all.size() > 100); // the registry holds the whole binary's tests
    for (const std::string& b : bad)
        UNSCOPED_INFO("test name starts with '-' or holds a ';': " << b);
    CHECK(bad.empty());
}
