// A render's life as a user lives it, through the real executable: an interrupted render and
// the checkpoint it leaves, the next render to the same file, resuming and merging and what the
// files then say about how they were made, the progress and the reason a render stopped, and
// the default sampler on a single pixel.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

const std::string kBox = project_scene("cornell-box.dae");
const std::string kSpheres = project_scene("cornell-spheres.dae");

/// Runs `args` with JSON progress, waits until passes are finishing (the first progress line)
/// and interrupts it once: it stops after the pass, writing the image and its checkpoint.
Result interrupt_once(const std::vector<std::string>& args) {
    Proc p(cat(args, {"--progress", "json"}));
    REQUIRE(p.wait_for("\"event\":\"progress\"", 120.0));
    p.signal(SIGINT);
    Result r;
    r.status = p.wait(120.0);
    r.out = p.out;
    r.err = p.err;
    return r;
}

/// A long render of uniform one-sample passes to `out` (plus `extra`), interrupted once.
Result interrupted_render(const std::string& out, const std::vector<std::string>& extra = {}) {
    return interrupt_once(cat({"render", kSpheres, "-r", "12", "9", "-s", "100000", "--adaptive",
                               "none", "--pass-spp", "1", "-t", "1", "-f", out},
                              extra));
}

/// The sample index range [sample_offset, sample_end) that a render's pixels used.
std::pair<int, int> used_range(const ImageData& img) {
    const Attribute* first = img.attribute("candela:sample_offset");
    const Attribute* end = img.attribute("candela:sample_end");
    REQUIRE(first != nullptr);
    REQUIRE(end != nullptr);
    return {first->i, end->i};
}

/// The largest value of the `samples` channel (finite samples of the busiest pixel).
float most_samples(const ImageData& img) {
    const int c = img.channel_index("samples");
    REQUIRE(c >= 0);
    float most = 0.f;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            most = std::max(most, img.at(x, y, c));
    return most;
}

} // namespace

// --- 2: sample ranges under the default sampler ---------------------------------------------

TEST_CASE("2: docs/distributed.md's sample-range recipe merges without repeating a sample index",
          "[app][workflow]") {
    // The recipe as docs/distributed.md "Merging without MPI" gives it, run at a small
    // resolution.
    const std::string doc = read_text(std::string(CANDELA_SOURCE_DIR) + "/docs/distributed.md");
    const std::regex render_line("candela render scene\\.dae (-s [0-9]+ --sample-offset [0-9]+) +"
                                 "-f (part[0-9]\\.exr)( +#.*)?");
    std::vector<std::pair<std::string, std::string>> parts; // flags, file
    for (const std::string& line : lines_of(doc)) {
        std::smatch m;
        if (std::regex_match(line, m, render_line)) parts.emplace_back(m[1].str(), m[2].str());
    }
    REQUIRE(parts.size() == 2);
    REQUIRE(doc.find("\ncandela merge " + parts[0].second + " " + parts[1].second +
                     " -o frame.exr") != std::string::npos);
    TempDir dir("recipe");
    std::vector<ImageData> images;
    for (const auto& [flags, file] : parts) {
        std::vector<std::string> args = {"render", kBox, "-r", "12", "9", "-q", "-f", dir / file};
        std::istringstream words(flags);
        for (std::string w; words >> w;)
            args.push_back(w);
        REQUIRE(run_candela(args).status == 0);
        images.push_back(read_image(dir / file));
    }
    Result merged = run_candela(
        {"merge", dir / parts[0].second, dir / parts[1].second, "-o", dir / "frame.exr", "-q"});
    INFO(merged.err);
    REQUIRE(merged.status == 0);
    // No index is used twice: the first part's pixels stop short of the second part's offset.
    const auto [first0, end0] = used_range(images[0]);
    const auto [first1, end1] = used_range(images[1]);
    CHECK(first0 < end0);
    CHECK(end0 <= first1);
    CHECK(first1 < end1);
    // Exact: every pixel's samples are the parts' samples added.
    const ImageData m = read_image(dir / "frame.exr");
    const int c = m.channel_index("samples");
    int differ = 0;
    for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x)
            differ += m.at(x, y, c) != images[0].at(x, y, c) + images[1].at(x, y, c);
    CHECK(differ == 0);
}

TEST_CASE("2: parts whose pixels really used overlapping indices are refused", "[app][workflow]") {
    // -s is a budget under the default sampler: offsets -s apart are not disjoint.
    TempDir dir("overlap");
    const std::vector<std::string> common = {"-r", "12", "9", "-s", "32", "-q", "--seed", "4"};
    REQUIRE(run_candela(cat({"render", kBox, "-f", dir / "a.exr"}, common)).status == 0);
    REQUIRE(run_candela(cat({"render", kBox, "--sample-offset", "32", "-f", dir / "b.exr"}, common))
                .status == 0);
    const ImageData a = read_image(dir / "a.exr");
    // The precondition of the refusal: a pixel of the first part went past its -s.
    REQUIRE(most_samples(a) > 32.f);
    CHECK(used_range(a).second == int(most_samples(a))); // no dropped samples in this scene
    Result r = run_candela({"merge", dir / "a.exr", dir / "b.exr", "-o", dir / "m.exr"});
    CHECK(r.status == 2);
    CHECK_THAT(r.err, Catch::Contains("overlap") && Catch::Contains("[32, "));
    CHECK_FALSE(fs::exists(dir / "m.exr"));
}

// --- 3: an earlier render's checkpoint -------------------------------------------------------

TEST_CASE("3: the same command again never starts over an interrupted render's checkpoint",
          "[app][workflow]") {
    TempDir dir("earlier-ckpt");
    const std::string out = dir / "a.exr", ckpt = out + ".ckpt";
    const std::vector<std::string> again = {"render", kSpheres,     "-r", "64", "48",
                                            "-s",     "100000",     "-t", "1",  "--adaptive",
                                            "none",   "--pass-spp", "1",  "-f", out};
    REQUIRE(interrupt_once(again).status == 5);
    REQUIRE(fs::exists(ckpt));
    const std::string image = read_text(out), checkpoint = read_text(ckpt);
    // The same command again (not --resume): refused before any work, saying how to go on.
    const Result refused = run_candela(again);
    INFO(refused.err);
    CHECK(refused.status == 2);
    CHECK_THAT(refused.err, Catch::Contains("candela render --resume " + ckpt) &&
                                Catch::Contains("--overwrite"));
    CHECK(read_text(out) == image);
    CHECK(read_text(ckpt) == checkpoint);
    const std::uint64_t earlier = std::uint64_t(read_image(out).attribute("candela:samples")->d);
    REQUIRE(earlier > 0);

    // --overwrite, interrupted with fewer samples: the earlier checkpoint stays. Both renders run
    // about a second of one-sample passes, this one of 4 pixels against 3072 and with 64 light
    // samples a vertex: measured at idle, 0.08 million samples against 1.8 million, a margin
    // that does not hang on the machine's speed (neither render can finish first).
    {
        const Result r = interrupt_once({"render", kSpheres, "-r", "2", "2", "-s", "10000000", "-l",
                                         "64", "-t", "1", "--adaptive", "none", "--pass-spp", "1",
                                         "-f", out, "--overwrite"});
        INFO(r.err);
        CHECK(r.status == 5);
        REQUIRE(std::uint64_t(read_image(out).attribute("candela:samples")->d) < earlier);
        CHECK(read_text(ckpt) == checkpoint);
        CHECK_THAT(r.err, Catch::Contains("kept the earlier render's checkpoint " + ckpt));
    }
    // --overwrite, finished with fewer samples: kept too.
    const std::vector<std::string> small = {"render", kSpheres, "-r", "64",
                                            "48",     "-s",     "1",  "--adaptive",
                                            "none",   "-f",     out,  "--overwrite"};
    const Result fewer = run_candela(small);
    INFO(fewer.err);
    CHECK(fewer.status == 0);
    CHECK(read_text(ckpt) == checkpoint);
    // --overwrite with more samples than the earlier render: now it goes, and says so.
    const std::uint64_t pixels = 64 * 48;
    const std::string more = std::to_string(earlier / pixels + 1);
    const Result larger = run_candela({"render", kSpheres, "-r", "64", "48", "-s", more,
                                       "--adaptive", "none", "-f", out, "--overwrite"});
    INFO(larger.err);
    CHECK(larger.status == 0);
    CHECK_FALSE(fs::exists(ckpt));
    CHECK_THAT(larger.err, Catch::Contains("removed the earlier render's checkpoint " + ckpt));
    // A render without an earlier checkpoint says nothing about one.
    const Result plain =
        run_candela({"render", kBox, "-r", "8", "6", "-s", "4", "--adaptive", "none", "-f", out});
    CHECK(plain.status == 0);
    CHECK_THAT(plain.err, !Catch::Contains("checkpoint"));
}

TEST_CASE("3: a file that is not a checkpoint at the checkpoint path is not replaced",
          "[app][workflow]") {
    TempDir dir("foreign-ckpt");
    const std::string out = dir / "a.exr", notes = dir / "notes.txt";
    { std::ofstream(notes) << "mine\n"; }
    const Result r =
        run_candela({"render", kBox, "-r", "8", "6", "-s", "2", "-f", out, "--checkpoint", notes});
    INFO(r.err);
    CHECK(r.status == 2);
    CHECK_THAT(r.err, Catch::Contains("not a candela checkpoint"));
    CHECK(read_text(notes) == "mine\n");
    CHECK_FALSE(fs::exists(out));
}

// --- 4: provenance ----------------------------------------------------------------------------

TEST_CASE("4: a resumed image keeps its first command and every session's and a merge lists its "
          "parts'",
          "[app][workflow]") {
    TempDir dir("provenance");
    const std::string out = dir / "r.exr", ckpt = out + ".ckpt";
    REQUIRE(interrupted_render(out, {"--seed", "6"}).status == 5);
    REQUIRE(interrupt_once({"render", "--resume", ckpt, "-t", "2"}).status == 5);
    const ImageData r = read_image(out);
    CHECK(r.attribute("candela:sessions")->i == 2);
    // The command that reproduces the image is the first one (a resume is bit-identical) ...
    const std::string first = r.meta("candela:command_line");
    CHECK_THAT(first, Catch::StartsWith("candela render " + kSpheres + " -r 12 9 -s 100000 ") &&
                          Catch::Contains("--seed 6"));
    // ... and every session's command follows, one a line.
    CHECK(lines_of(r.meta("candela:session_commands")) ==
          std::vector<std::string>{first,
                                   "candela render --resume " + ckpt + " -t 2 --progress json"});

    // A merge: its own command, and the commands of its parts in an order that can be run.
    const std::vector<std::string> common = {"-r", "8", "6", "-s", "2", "--adaptive", "none", "-q"};
    const std::vector<std::string> a = cat({"render", kBox, "-f", dir / "a.exr"}, common);
    const std::vector<std::string> b =
        cat({"render", kBox, "--sample-offset", "2", "-f", dir / "b.exr"}, common);
    const std::vector<std::string> c =
        cat({"render", kBox, "--sample-offset", "4", "-f", dir / "c.exr"}, common);
    for (const auto& args : {a, b, c})
        REQUIRE(run_candela(args).status == 0);
    REQUIRE(
        run_candela({"merge", dir / "a.exr", dir / "b.exr", "-o", dir / "ab.exr", "-q"}).status ==
        0);
    REQUIRE(run_candela({"merge", dir / "ab.exr", dir / "c.exr", "-o", dir / "abc.exr"}).status ==
            0);
    const ImageData m = read_image(dir / "abc.exr");
    CHECK(m.meta("candela:command_line") ==
          "candela merge " + (dir / "ab.exr") + " " + (dir / "c.exr") + " -o " + (dir / "abc.exr"));
    auto text = [](const std::vector<std::string>& args) {
        std::string s = "candela";
        for (const std::string& w : args)
            s += " " + w;
        return s;
    };
    CHECK(lines_of(m.meta("candela:part_commands")) ==
          std::vector<std::string>{text(a), text(b),
                                   "candela merge " + (dir / "a.exr") + " " + (dir / "b.exr") +
                                       " -o " + (dir / "ab.exr") + " -q",
                                   text(c)});
}

// --- 5, 7: progress and the reason a render stopped -------------------------------------------

TEST_CASE("5, 7: a default render's progress ends at 100 % with the reason it stopped",
          "[app][workflow]") {
    TempDir dir("stop");
    Result j = run_candela({"render", kBox, "-r", "16", "12", "-s", "64", "-q", "--progress",
                            "json", "-f", dir / "j.exr"});
    INFO(j.out);
    REQUIRE(j.status == 0);
    const std::vector<std::string> lines = lines_of(j.out);
    REQUIRE(lines.size() >= 3);
    CHECK_THAT(lines[lines.size() - 2],
               Catch::Contains("\"event\":\"progress\"") && Catch::Contains("\"fraction\":1.0,"));
    const std::string& done = lines.back();
    CHECK_THAT(done, Catch::Contains("\"event\":\"done\"") && Catch::Contains("\"fraction\":1.0,"));
    const std::regex reason("\"stop\":\"(noise_threshold|budget_spent|nothing_to_gain)\","
                            "\"stop_reason\":\"(noise threshold 0.02 reached \\(estimated "
                            "[0-9.e-]+\\) at [0-9]+ % of the budget|budget spent \\(estimated "
                            "noise [0-9.e-]+\\)|no pixel needed more samples .*)\"");
    CHECK(std::regex_search(done, reason));

    // The same reasons for people, and -s named for what it is.
    Result h = run_candela(
        {"render", kBox, "-r", "16", "12", "-s", "64", "--progress", "none", "-f", dir / "h.exr"});
    INFO(h.err);
    CHECK_THAT(h.err, Catch::Contains("16x12, budget 64 samples/pixel (adaptive, stops at noise "
                                      "threshold 0.02)"));
    CHECK(std::regex_search(h.err, std::regex("\n  stopped        (noise threshold|budget "
                                              "spent|no pixel needed)")));
    // A generous budget ends at the noise threshold, well before the budget.
    Result t = run_candela({"render", kBox, "-r", "8", "6", "-s", "4096", "--noise-threshold",
                            "0.2", "-q", "--progress", "json", "-f", dir / "t.exr"});
    CHECK_THAT(lines_of(t.out).back(), Catch::Contains("\"stop\":\"noise_threshold\"") &&
                                           Catch::Contains("\"stop_reason\":\"noise threshold "
                                                           "0.2 reached (estimated 0.") &&
                                           Catch::Contains("\"fraction\":1.0,"));
    // Uniform sampling says samples, not a budget.
    Result u = run_candela({"render", kBox, "-r", "8", "6", "-s", "4", "--adaptive", "none",
                            "--progress", "none", "-f", dir / "u.exr"});
    CHECK_THAT(u.err, Catch::Contains("8x6, 4 samples/pixel,") &&
                          Catch::Contains("  stopped        all 4 samples/pixel taken"));
}

// --- 6: the bar fits the terminal -------------------------------------------------------------

TEST_CASE("6: the progress bar fits a 60-column terminal", "[app][workflow]") {
    TempDir dir("bar");
    ::setenv("COLUMNS", "60", 1);
    Result r = run_candela({"render", kBox, "-r", "48", "36", "-s", "64", "-t", "1", "--progress",
                            "bar", "-f", dir / "b.exr"});
    ::unsetenv("COLUMNS");
    REQUIRE(r.status == 0);
    // Every redraw of the bar ('\r' before it) stays within 59 columns.
    int redraws = 0;
    for (std::size_t at = r.err.find('\r'); at != std::string::npos;
         at = r.err.find('\r', at + 1)) {
        const std::size_t end = r.err.find_first_of("\r\n", at + 1);
        const std::string line = r.err.substr(at + 1, end - at - 1);
        INFO(line);
        CHECK(line.size() <= 59);
        CHECK_THAT(line, Catch::StartsWith("["));
        ++redraws;
    }
    CHECK(redraws >= 1);
    CHECK_THAT(r.err, Catch::Contains("100.0%"));
}

// --- 8: one pixel -----------------------------------------------------------------------------

TEST_CASE("8: a 1x1 region takes its -s samples under the default sampler", "[app][workflow]") {
    TempDir dir("pixel");
    const std::string out = dir / "p.exr";
    Result r = run_candela(
        {"render", kBox, "-r", "16", "12", "-p", "5", "5", "1", "1", "-s", "256", "-q", "-f", out});
    REQUIRE(r.status == 0);
    const ImageData img = read_image(out);
    REQUIRE(img.width == 1);
    REQUIRE(img.height == 1);
    // Not the 16 of the first pass: with no neighbours, the error estimate is not trusted.
    CHECK(img.at(0, 0, img.channel_index("samples")) > 16.f);
    CHECK(img.at(0, 0, img.channel_index("samples")) == 256.f);
}

// --- 16: machine-readable interrupts ----------------------------------------------------------

TEST_CASE("16: --progress json marks the signal and names the checkpoint, also under -q",
          "[app][workflow]") {
    TempDir dir("json-interrupt");
    const std::string out = dir / "i.exr";
    const Result r = interrupted_render(out, {"-q"});
    INFO(r.out);
    CHECK(r.status == 5);
    CHECK_THAT(r.err, !Catch::Contains("continue with")); // -q: the hint is in the JSON alone
    const std::vector<std::string> lines = lines_of(r.out);
    REQUIRE(lines.size() >= 3);
    CHECK_THAT(r.out, Catch::Contains("{\"event\":\"signal\",\"signal\":\"SIGINT\",\"count\":1,"
                                      "\"action\":\"stop after the current pass\"}\n"));
    const std::string& done = lines.back();
    CHECK_THAT(done,
               Catch::Contains("\"event\":\"done\"") && Catch::Contains("\"status\":5") &&
                   Catch::Contains("\"stop\":\"interrupted\"") &&
                   Catch::Contains("\"checkpoint\":\"" + out + ".ckpt\"") &&
                   Catch::Contains("\"resume\":\"candela render --resume " + out + ".ckpt\""));
}

TEST_CASE("16: JSON progress never goes back, and an interrupted render's done event is not "
          "below its last progress event",
          "[app][workflow]") {
    TempDir dir("json-monotone");
    // The default sampler, whose progress is a share of a budget it estimates as it goes (with
    // a threshold it never reaches: at 12x9 the default 0.02 ends the render within a second).
    Proc p({"render", kSpheres, "-r", "12", "9", "-s", "100000", "--noise-threshold", "1e-6", "-t",
            "1", "-q", "--progress", "json", "-f", dir / "m.exr"});
    // Two progress events (a second apart): the render is well into its passes.
    const std::string event = "\"event\":\"progress\"";
    REQUIRE(p.wait_for(event, 120.0));
    const Stopwatch waited;
    while (p.out.find(event, p.out.find(event) + 1) == std::string::npos && waited.seconds() < 120)
        p.wait_for("text no event holds", 0.2);
    REQUIRE(p.out.find(event, p.out.find(event) + 1) != std::string::npos);
    p.signal(SIGINT);
    REQUIRE(p.wait(120.0) == 5);
    INFO(p.out);
    double last = 0.0;
    bool done = false;
    for (const std::string& line : lines_of(p.out)) {
        const nlohmann::json e = nlohmann::json::parse(line);
        if (e["event"] != "progress" && e["event"] != "done") continue;
        const double fraction = e["fraction"].get<double>();
        INFO(line);
        CHECK(fraction >= last);
        last = fraction;
        done = e["event"] == "done";
    }
    CHECK(done);
}

TEST_CASE("the sample-rate image's legend is on stderr and in the EXR beside it",
          "[app][workflow]") {
    TempDir dir("rate-legend");
    const Result png = run_candela(
        {"render", kBox, "-r", "8", "6", "-s", "16", "--progress", "none", "-f", dir / "x.png"});
    INFO(png.err);
    REQUIRE(png.status == 0);
    // The default sampler's ramp ends at the most samples a pixel can get.
    const std::regex line("\n  rate image     " + (dir / "x_rate.png") +
                          ": blue 0, green [0-9.]+, red [0-9]+ or more samples per pixel");
    CHECK(std::regex_search(png.err, line));
    REQUIRE(run_candela({"render", kBox, "-r", "8", "6", "-s", "16", "-q", "--preview", "-f",
                         dir / "y.exr"})
                .status == 0);
    CHECK(fs::exists(dir / "y_rate.png"));
    CHECK_THAT(read_image(dir / "y.exr").meta("candela:rate_legend"),
               Catch::StartsWith("blue 0, green "));
    // No rate image, no legend.
    const Result uniform = run_candela({"render", kBox, "-r", "8", "6", "-s", "2", "--adaptive",
                                        "none", "--progress", "none", "-f", dir / "u.png"});
    CHECK_THAT(uniform.err, !Catch::Contains("rate image"));
}
