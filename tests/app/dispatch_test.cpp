// How the command line is dispatched: a scene file or a flag first means `render`, as with the
// CS184 binary, pbrt and Mitsuba.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>

#include <filesystem>

using namespace candela::test;
namespace fs = std::filesystem;

namespace {
const std::string kBox = project_scene("cornell-box.dae");
/// A render that takes a fraction of a second.
const std::vector<std::string> kTiny = {"-r", "16", "12", "-s", "1", "--adaptive", "none", "-q"};
} // namespace

TEST_CASE("a scene file first means render", "[app][dispatch]") {
    TempDir dir("dispatch-scene");
    std::vector<std::string> args = {kBox};
    args.insert(args.end(), kTiny.begin(), kTiny.end());
    args.insert(args.end(), {"-f", dir / "a.exr"});
    const Result r = run_candela(args);
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(dir.path / "a.exr"));
}

TEST_CASE("the CS184 order, flags then the scene, means render", "[app][dispatch]") {
    TempDir dir("dispatch-cs184");
    std::vector<std::string> args = {"-t", "1"};
    args.insert(args.end(), kTiny.begin(), kTiny.end());
    args.insert(args.end(), {"-f", dir / "b.exr", kBox});
    const Result r = run_candela(args);
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(dir.path / "b.exr"));
}

TEST_CASE("an unknown word first is still an unknown command", "[app][dispatch]") {
    const Result r = run_candela({"rendr", kBox});
    CHECK(r.status == 2);
    CHECK(r.err.find("did you mean 'render'") != std::string::npos);
    const Result version = run_candela({"--version"});
    CHECK(version.status == 0);
    CHECK(version.out.find("candela ") == 0);
}
