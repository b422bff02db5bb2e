// Error is data (a kind, an optional place, a plain message); the user's one line is made of it
// once, by error_line() and warning_line().
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <string>

using namespace candela;

TEST_CASE("error: a located error keeps its place and its plain message apart", "[error][quick]") {
    const Error e(ErrorKind::Scene, SourceLoc{"scenes/box.dae", 12}, "unknown element <foo>");
    CHECK(e.kind() == ErrorKind::Scene);
    REQUIRE(e.where());
    CHECK(e.where()->file == "scenes/box.dae");
    CHECK(e.where()->line == 12);
    CHECK(e.message() == "unknown element <foo>");
    CHECK(std::string(e.what()) == "scenes/box.dae:12: unknown element <foo>");
    CHECK(error_line(e) == "candela: error: scenes/box.dae:12: unknown element <foo>");
    CHECK(warning_line(e) == "candela: warning: scenes/box.dae:12: unknown element <foo>");
}

TEST_CASE("error: a file without a line, and no place at all", "[error][quick]") {
    const Error file_only(ErrorKind::Io, SourceLoc{"out.exr.ckpt"}, "checkpoint is truncated");
    REQUIRE(file_only.where());
    CHECK(file_only.where()->line == 0);
    CHECK(error_line(file_only) == "candela: error: out.exr.ckpt: checkpoint is truncated");

    const Error plain(ErrorKind::Usage, "-s/--spp: 0 is out of range [1, 16777216]");
    CHECK(!plain.where());
    CHECK(plain.message() == std::string(plain.what()));
    CHECK(error_line(plain) == "candela: error: -s/--spp: 0 is out of range [1, 16777216]");
    CHECK(static_cast<int>(plain.kind()) == 2); // the exit status of a usage error
}

TEST_CASE("error: a failed check is an internal error naming the source line", "[error][quick]") {
    try {
        CANDELA_CHECK(1 + 1 == 3, "arithmetic is broken");
        FAIL("the check did not throw");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Internal);
        CHECK(!e.where()); // a place in candela's source, not in an input file
        CHECK_THAT(error_line(e), Catch::StartsWith("candela: error: internal error at "
                                                    "error_test.cpp:") &&
                                      Catch::Contains("arithmetic is broken (1 + 1 == 3)"));
    }
}
