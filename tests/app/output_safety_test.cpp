// Nothing a user made is replaced unasked: no command writes over a file it reads or over
// another file it writes (under any name of that file), the default output name keeps an
// earlier image under a numbered name, and the small refusals and notes around outputs, resumes
// and merges say what they mean.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/app/cli.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <set>
#include <unistd.h>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

const std::string kBox = project_scene("cornell-box.dae");

/// A tiny finished render of the Cornell box to `out` (any format).
void tiny_render(const std::string& out, const std::vector<std::string>& extra = {}) {
    const Result r = run_candela(
        cat({"render", kBox, "-r", "16", "12", "-s", "2", "--adaptive", "none", "-q", "-f", out},
            extra));
    INFO(r.err);
    REQUIRE(r.status == 0);
}

/// A command line as one string, for the test's log.
std::string join_args(const std::vector<std::string>& args) {
    std::string s;
    for (const std::string& a : args)
        s += (s.empty() ? "" : " ") + a;
    return s;
}

/// The names of the files in `dir`.
std::set<std::string> entries(const fs::path& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.insert(e.path().filename().string());
    return names;
}

} // namespace

// --- one rule for every command's outputs -----------------------------------------------------

TEST_CASE("no output of any command is one of its inputs or another of its outputs",
          "[app][outputs]") {
    TempDir dir("outputs-rule");
    const std::string mine = dir / "mine.png", ref = dir / "ref.exr", env = dir / "env.exr";
    tiny_render(mine);
    tiny_render(ref);
    tiny_render(env);
    tiny_render(dir / "env.png");
    fs::create_hard_link(ref, dir.path / "ref-link.exr");
    fs::create_symlink(env, dir.path / "env-link.exr");
    const std::set<std::string> before = entries(dir.path);
    const std::string mine_bytes = read_text(mine), env_bytes = read_text(env),
                      ref_bytes = read_text(ref);
    const std::vector<std::string> tiny = {"-r", "16", "12", "-s", "2", "--adaptive", "none"};
    struct Case {
        std::vector<std::string> args;
        const char* needle;
    };
    const std::vector<Case> cases = {
        // The image being judged, by the same name and by another name of it.
        {{"compare", mine, ref, "--error-map", mine},
         "--error-map and the image being compared name the same file"},
        {{"compare", "mine.png", ref, "--error-map", "./mine.png"},
         "--error-map and the image being compared name the same file"},
        {{"compare", mine, ref, "--error-map", dir / "sub/../ref.exr"},
         "--error-map and the reference image name the same file"},
        // A render's environment map, directly, through a symbolic link, through its preview.
        {cat({"render", kBox, "-e", env, "-f", env}, tiny),
         "-f/--output and -e/--env name the same file"},
        {cat({"render", kBox, "-e", dir / "env-link.exr", "-f", env}, tiny),
         "-f/--output and -e/--env name the same file"},
        {cat({"render", kBox, "-e", dir / "env.png", "-f", env, "--preview"}, tiny),
         "--preview's PNG and -e/--env name the same file"},
        // Two outputs of one render: the image and its checkpoint (a file not there yet, under
        // two spellings of its name).
        {cat({"render", kBox, "-f", dir / "same.exr", "--checkpoint", dir / "x/../same.exr"}, tiny),
         "--checkpoint and -f/--output name the same file"},
        {cat({"render", kBox, "-f", dir / "new.png", "--checkpoint", dir / "new_rate.png", "-a",
              "16", "0.05"},
             {"-r", "16", "12", "-s", "2"}),
         "--checkpoint and the sample-rate image name the same file"},
        // merge: an input as the output, through a hard link.
        {{"merge", ref, env, "-o", dir / "ref-link.exr"},
         "-o/--output and an input name the same file"},
    };
    for (const Case& c : cases) {
        const Result r = run_candela(c.args, dir.path.string());
        INFO(join_args(c.args));
        check_one_line(r, 2, c.needle);
    }
    // Nothing was written, and the inputs are as they were.
    CHECK(entries(dir.path) == before);
    CHECK(read_text(mine) == mine_bytes);
    CHECK(read_text(env) == env_bytes);
    CHECK(read_text(ref) == ref_bytes);
}

// --- the default output name ------------------------------------------------------------------

TEST_CASE("the default output name keeps an earlier image under a numbered name",
          "[app][outputs]") {
    TempDir dir("default-name");
    fs::copy_file(kBox, dir.path / "box.dae");
    const std::vector<std::string> render = {"render", "box.dae", "-r",         "16",   "12",
                                             "-s",     "2",       "--adaptive", "none", "-q"};
    REQUIRE(run_candela(render, dir.path.string()).status == 0);
    const std::string first = read_text(dir / "box.exr");
    const Result second = run_candela(cat(render, {"--seed", "2"}), dir.path.string());
    INFO(second.err);
    REQUIRE(second.status == 0);
    CHECK_THAT(second.err, Catch::Contains("kept the earlier box.exr as box.1.exr"));
    CHECK(read_text(dir / "box.1.exr") == first);
    CHECK(read_text(dir / "box.exr") != first);
    // The next one takes the first free number.
    REQUIRE(run_candela(render, dir.path.string()).status == 0);
    CHECK(fs::exists(dir.path / "box.2.exr"));
    // -f names the file to write: it is replaced, as asked.
    const Result named = run_candela(cat(render, {"-f", "box.exr"}), dir.path.string());
    REQUIRE(named.status == 0);
    CHECK_THAT(named.err, !Catch::Contains("kept the earlier"));
    CHECK(entries(dir.path) ==
          std::set<std::string>{"box.dae", "box.exr", "box.1.exr", "box.2.exr"});
}

// --- small refusals and notes -----------------------------------------------------------------

TEST_CASE("render: --noise-threshold is a fraction below 1", "[app][outputs]") {
    for (const char* v : {"2", "1"}) {
        const Result r = run_candela({"render", kBox, "--noise-threshold", v});
        check_one_line(r, 2, "--noise-threshold: " + std::string(v) + " is not in [0, 1)");
        CHECK_THAT(r.err, Catch::Contains("relative RMS error") && Catch::Contains("0.02 = 2 %"));
    }
    // The relative sampler's -a TOLERANCE is the same threshold.
    check_one_line(run_candela({"render", kBox, "-a", "16", "3", "--adaptive", "relative"}), 2,
                   "-a: the tolerance 3 is the relative sampler's noise threshold");
    CHECK(
        parse_render_command_line({"s.dae", "--noise-threshold", "0.5"}).settings.noise_threshold ==
        0.5f);
    CHECK(parse_render_command_line({"s.dae", "--noise-threshold", "0"}).settings.noise_threshold ==
          0.f);
    // CS184's -a keeps its own tolerance, whatever its size.
    CHECK(parse_render_command_line({"s.dae", "-a", "16", "3"}).settings.adaptive_tol == 3.f);
}

TEST_CASE("render: --rr-depth beyond -m warns that roulette never starts", "[app][outputs]") {
    const RenderArgs late = parse_render_command_line({"s.dae", "--rr-depth", "9", "-m", "3"});
    REQUIRE(late.warnings.size() == 1);
    CHECK_THAT(late.warnings[0], Catch::StartsWith("--rr-depth has no effect with -m/--max-depth "
                                                   "3: Russian roulette would start at bounce 9"));
    // At -m 3, roulette at bounce 3 still cuts paths before their last vertex.
    CHECK(parse_render_command_line({"s.dae", "--rr-depth", "3", "-m", "3"}).warnings.empty());
    CHECK_THROWS_AS(parse_render_command_line({"s.dae", "--rr-depth", "9", "-m", "3", "--strict"}),
                    Error);
}

TEST_CASE("a finished refinement says it removed its checkpoint", "[app][outputs]") {
    TempDir dir("refine-removes");
    const std::string out = dir / "a.exr", ckpt = out + ".ckpt";
    tiny_render(out, {"--keep-checkpoint"});
    REQUIRE(fs::exists(ckpt));
    const Result refined = run_candela({"render", "--resume", ckpt, "-s", "4"});
    INFO(refined.err);
    REQUIRE(refined.status == 0);
    CHECK_FALSE(fs::exists(ckpt));
    CHECK_THAT(refined.err, Catch::Contains("removed the checkpoint " + ckpt) &&
                                Catch::Contains("--keep-checkpoint keeps it"));
}

TEST_CASE("render: --resume of a file that is not a checkpoint is a malformed input",
          "[app][outputs]") {
    TempDir dir("resume-image");
    const std::string image = dir / "image.exr";
    tiny_render(image);
    check_one_line(run_candela({"render", "--resume", image}), int(ErrorKind::Scene),
                   "not a candela checkpoint");
    // A checkpoint that is not there cannot be read: a file error, as before.
    check_one_line(run_candela({"render", "--resume", dir / "missing.ckpt"}), int(ErrorKind::Io),
                   "cannot open checkpoint");
}

TEST_CASE("merge names a PNG input and the same file given twice", "[app][outputs]") {
    TempDir dir("merge-inputs");
    const std::string a = dir / "a.exr", png = dir / "b.png";
    tiny_render(a);
    tiny_render(png);
    check_one_line(run_candela({"merge", a, png, "-o", dir / "m.exr"}), 2,
                   png + ": not a candela EXR render");
    const Result twice =
        run_candela({"merge", "a.exr", "./a.exr", "-o", "m.exr"}, dir.path.string());
    check_one_line(twice, 2, "./a.exr: the same file twice (as a.exr)");
    CHECK_FALSE(fs::exists(dir.path / "m.exr"));
}
