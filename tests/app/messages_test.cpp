// What the user reads: every usage error is one line in the user's terms (no CLI11 counts, no
// wrapped-around numbers), habits from other tools get a hint, a cut file says so, and
// `converge -q` still gives its result.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>

#include <fstream>

using namespace candela::test;

namespace {

const std::string kBox = project_scene("cornell-box.dae");

} // namespace

TEST_CASE("messages: usage errors are one line in the user's terms", "[app][messages]") {
    // A list option's count is CLI11's "any number", never shown.
    const Result threads = run_candela({"bench", kBox, "-t", "x"});
    check_one_line(threads, 2, "-t/--threads takes one or more whole numbers");
    CHECK_THAT(threads.err, !Catch::Contains("536870912"));
    // A negative seed or offset is named as given, not as 2^64 - 1.
    const Result seed = run_candela({"render", kBox, "--seed", "-1"});
    check_one_line(seed, 2, "--seed: -1 is out of range");
    CHECK_THAT(seed.err, !Catch::Contains("18446744073709551615"));
    check_one_line(run_candela({"render", kBox, "--sample-offset", "-5"}), 2,
                   "--sample-offset: -5 is out of range");
    // The relative sampler may give a pixel several times -s: its last index must fit too.
    const std::string near_end = std::to_string(2147483647 - 150);
    check_one_line(run_candela({"render", kBox, "--sample-offset", near_end, "-s", "100"}), 2,
                   "the relative sampler's largest count per pixel");
    // merge's output is -o; render's -o is CS184's accumulate flag.
    check_one_line(run_candela({"merge", "a.exr", "b.exr", "-o", "m.exr", "-f", "x.exr"}), 2,
                   "the output file is '-o' here");
    // The same hint when -o is missing altogether: the unknown option is the mistake.
    check_one_line(run_candela({"merge", "a.exr", "b.exr", "-f", "m.exr"}), 2,
                   "the output file is '-o' here");
    check_one_line(run_candela({"render", kBox, "-o", "out.exr"}), 2, "the output file is -f");
    check_one_line(run_candela({"rendr", kBox}), 2, "did you mean 'render'?");
}

TEST_CASE("messages: bench refuses what it cannot measure", "[app][messages]") {
    check_one_line(run_candela({"bench", kBox, "--embree-isa", "avx9"}), 2, "unknown ISA 'avx9'");
    check_one_line(run_candela({"bench", kBox, "--rays", "0"}), 2, "--rays must be >= 1");
}

TEST_CASE("messages: a truncated scene file ends early", "[app][messages]") {
    TempDir dir("truncated");
    const std::string cut = dir / "cut.dae";
    {
        std::ifstream in(kBox);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::ofstream(cut) << text.substr(0, text.size() / 2);
    }
    check_one_line(run_candela({"info", cut}), 3, "the file ends early");
}

TEST_CASE("converge: -q still prints the summary and an equal error is reached",
          "[app][messages]") {
    TempDir dir("converge-q");
    const Result r = run_candela(
        {"converge", kBox, "-r",        "16",      "12",        "--ladder",        "1,2",
         "--seeds",  "1",  "--ref-spp", "16",      "--configs", "uniform,builtin", "-t",
         "1",        "-q", "-o",        dir / "c", "--cache",   dir / "cache"});
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    // -q leaves errors and warnings: these renders are too short to time and the reference is
    // thin, and it says so; no progress or notes.
    for (const std::string& line : lines_of(r.err))
        CHECK_THAT(line, Catch::StartsWith("converge: warning: "));
    CHECK_THAT(r.err, Catch::Contains("too short to time"));
    CHECK_THAT(r.out, Catch::Contains("most efficient at the last point"));
    // builtin traces the same rays as embree: the same image, so the same error.
    CHECK_THAT(r.out, Catch::Contains("builtin reaches uniform's relMSE") ||
                          Catch::Contains("builtin matches uniform's relMSE"));
    CHECK_THAT(r.out, !Catch::Contains("does not reach"));
}
