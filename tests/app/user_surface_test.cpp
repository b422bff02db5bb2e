// The user's side of `candela`, item by item: nothing lost (outputs checked before any work,
// the image written when a checkpoint cannot be), nothing surprising (refusals, warnings, one
// error format, quiet defaults, Ctrl-C), images that composite (alpha, depth, data windows,
// metadata, exact merges), previews, the flag table and the installed manual page.
#include "../support/cameras.h"
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/app/cli.h"
#include "candela/io/image_io.h"
#include "candela/render/output.h"
#include "candela/scene/camera.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

const std::string kBox = project_scene("cornell-box.dae");
const std::string kSpheres = project_scene("cornell-spheres.dae");

/// A request that would take far longer than a second to render (640x480, 256 spp): anything
/// refused quickly on it was refused before any work.
const std::vector<std::string> kBigRequest = {"-r", "640", "480", "-s", "256"};

/// How much longer than a process that does nothing a refusal may take: checking arguments and
/// paths is microseconds of work, loading and rendering this request is many seconds.
constexpr double kRefusalSeconds = 1.0;

/// Runs kept for a timing: the fastest of them is the least disturbed by other work on the
/// machine (the tests share two cores with builds and other tests).
constexpr int kTimingRuns = 3;

/// Start-up of the executable with its image module (OpenImageIO, loaded on the first image
/// read or write, which the output checks of a render do), measured in the same test: a merge
/// that loads the module to read an input that is not an image (text named .exr), and stops
/// there.
double startup_seconds() {
    double best = 1e30;
    TempDir dir("startup");
    const std::string a = dir / "a.exr", b = dir / "b.exr", never = dir / "never.exr";
    for (const std::string& p : {a, b})
        std::ofstream(p) << "not an image\n";
    for (int i = 0; i < kTimingRuns; ++i) {
        Result r = run_candela({"merge", "-o", never, a, b});
        REQUIRE(r.status == 4);
        REQUIRE(r.err.find("not an image") != std::string::npos);
        best = std::min(best, r.seconds);
    }
    return best;
}

/// Runs `args` kTimingRuns times; the last result with the fastest time.
Result timed_run(const std::vector<std::string>& args) {
    Result best;
    best.seconds = 1e30;
    for (int i = 0; i < kTimingRuns; ++i) {
        Result r = run_candela(args);
        const double fastest = std::min(best.seconds, r.seconds);
        best = r;
        best.seconds = fastest;
    }
    return best;
}

/// Checks an error output: one `candela: error: ...` line (and, for usage errors, the hint
/// line), none of CLI11's or tinyxml2's wording.
void check_error_output(const Result& r, const std::string& needle) {
    INFO("stderr: " << r.err);
    const std::vector<std::string> lines = lines_of(r.err);
    REQUIRE(!lines.empty());
    CHECK_THAT(lines[0], Catch::StartsWith("candela: error: "));
    CHECK_THAT(lines[0], Catch::Contains(needle));
    CHECK(lines.size() <= 2);
    if (lines.size() == 2) CHECK_THAT(lines[1], Catch::StartsWith("Run 'candela help'"));
    for (const char* internal : {"At Most", "At Least", "is required", "Could not convert",
                                 "The following argument", "XML_ERROR", "ErrorID", "Expected"})
        CHECK_THAT(r.err, !Catch::Contains(internal));
}

/// Reads an attribute and checks its type.
const Attribute& attr(const ImageData& img, const std::string& name, Attribute::Type type) {
    const Attribute* a = img.attribute(name);
    INFO("attribute " << name);
    REQUIRE(a != nullptr);
    CHECK(a->type == type);
    return *a;
}

/// Removes directory `p` while a render may be writing a checkpoint into it: a file created
/// during remove_all makes its final step fail (directory not empty), so it is tried again.
void remove_while_written(const fs::path& p) {
    constexpr int kAttempts = 1000; // each attempt races one checkpoint write at most
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
        std::error_code ec;
        fs::remove_all(p, ec);
        if (!ec && !fs::exists(p)) return;
    }
    FAIL("could not remove " << p.string());
}

} // namespace

// --- 1, 2: outputs checked before any work; the image survives a failed checkpoint ----------

TEST_CASE("1-2: unwritable outputs are refused before any work", "[app][user]") {
    TempDir dir("outputs");
    fs::create_directories(dir.path / "out.exr");    // -f names a directory
    fs::create_directories(dir.path / "prev.png");   // the preview's path is a directory
    fs::create_directories(dir.path / "r_rate.png"); // the sample-rate image's path too
    const double startup = startup_seconds();
    struct Case {
        std::vector<std::string> args;
        int status;
        const char* needle;
    };
    const std::vector<Case> cases = {
        {{"-f", dir / "out.exr"}, 4, "directory"},
        {{"-f", dir / "missing/x.exr"}, 4, "does not exist"},
        {{"-f", dir / "x.exr", "--checkpoint", dir / "missing/x.ckpt"}, 4, "checkpoint"},
        {{"-f", dir / "prev.exr", "--preview"}, 4, "prev.png"},
        {{"-f", dir / "r.png", "-a", "16", "0.05"}, 4, "r_rate.png"},
        {{"-f", kBox}, 2, "-f/--output"}, // never the scene itself
    };
    for (const Case& c : cases) {
        Result r = timed_run(cat(cat({"render", kBox}, kBigRequest), c.args));
        INFO(r.err);
        CHECK(r.status == c.status);
        check_error_output(r, c.needle);
        CHECK(r.seconds - startup < kRefusalSeconds);
    }
    // Nothing written by any refused run.
    std::size_t entries = 0;
    for (const auto& e : fs::directory_iterator(dir.path)) {
        (void)e;
        ++entries;
    }
    CHECK(entries == 3);
}

TEST_CASE("1: the image is written when the checkpoint cannot be", "[app][user]") {
    TempDir dir("ckpt-fail");
    fs::create_directories(dir.path / "ck");
    const std::string out = dir / "img.exr";
    SECTION("on an interrupt") {
        Proc p(cat({"render", kSpheres, "-f", out, "--checkpoint", dir / "ck/c.ckpt", "--progress",
                    "json", "--pass-spp", "1", "--adaptive", "none", "-t", "1"},
                   {"-r", "160", "120", "-s", "4096"}));
        // After the first progress line (a second into the render) some passes are done.
        REQUIRE(p.wait_for("\"event\":\"progress\"", 120.0));
        remove_while_written(dir.path / "ck"); // the checkpoint's directory disappears
        p.signal(SIGINT);
        const int status = p.wait(120.0);
        INFO(p.err);
        CHECK(status == 4);
        REQUIRE(fs::exists(out));
        const ImageData img = read_image(out);
        CHECK(img.meta("candela:interrupted") == "1");
        CHECK(img.at(80, 60, img.channel_index("samples")) >= 1.f);
        CHECK_THAT(p.err, Catch::Contains("candela: error: " + dir / "ck/c.ckpt") &&
                              Catch::Contains("the image holds"));
    }
    SECTION("during --checkpoint-every, the render goes on") {
        Proc p(cat({"render", kSpheres, "-f", out, "--checkpoint", dir / "ck/c.ckpt",
                    "--checkpoint-every", "0.001", "--progress", "json", "--pass-spp", "2",
                    "--adaptive", "none"},
                   {"-r", "48", "36", "-s", "64"}));
        REQUIRE(p.wait_for("\"event\":\"start\"", 120.0));
        remove_while_written(dir.path / "ck");
        const int status = p.wait(300.0);
        INFO(p.err);
        CHECK(status == 0);
        CHECK(fs::exists(out));
    }
}

// --- 3, 4: values and combinations --------------------------------------------------------------

TEST_CASE("3: -o takes only 0 and 1", "[app][user]") {
    for (const char* v : {"7", "-3", "2"}) {
        Result r = run_candela(cat({"render", kBox, "-o", v}, kBigRequest));
        CHECK(r.status == 2);
        check_error_output(r, "-o/--accumulate");
    }
    CHECK(parse_render_command_line({"-o", "0", "s.dae"}).settings.accumulate == false);
    CHECK(parse_render_command_line({"-o", "1", "s.dae"}).settings.accumulate == true);
}

TEST_CASE("4: inputs are checked before the scene is loaded", "[app][user]") {
    TempDir dir("inputs");
    { std::ofstream(dir.path / "bad-cam.txt") << "49 37 1.3 0.1 100\n0 0 nope\n"; }
    const double startup = startup_seconds();
    struct Case {
        std::vector<std::string> args;
        int status;
        const char* needle;
    };
    const std::vector<Case> cases = {
        {{"render", kBox, "-c", dir / "missing.txt"}, 4, "No such file or directory"},
        {{"render", kBox, "-c", dir / "bad-cam.txt"}, 3, "bad-cam.txt:2:"},
        {{"render", kBox, "-e", dir / "missing.exr"}, 4, "No such file or directory"},
        {{"render", kBox, "-e", kBox}, 4, "not an image"},
        {{"render", kBox, "--sampler", "halton"}, 2, "--sampler"},
    };
    for (const Case& c : cases) {
        Result r = timed_run(cat(c.args, cat(kBigRequest, {"-f", dir / "o.exr"})));
        CHECK(r.status == c.status);
        check_error_output(r, c.needle);
        CHECK(r.seconds - startup < kRefusalSeconds);
    }
    // converge: a bad configuration before the scene and the reference render.
    Result conv = timed_run({"converge", kBox, "--ref-spp", "100000", "--configs", "uniform,bogus",
                             "-o", dir / "c", "--cache", dir / "cache"});
    CHECK(conv.status == 2);
    check_error_output(conv, "bogus");
    CHECK(conv.seconds - startup < kRefusalSeconds);
    CHECK_FALSE(fs::exists(dir.path / "cache"));
    CHECK_FALSE(fs::exists(dir.path / "o.exr"));
}

TEST_CASE("4: flags that do nothing warn, and fail under --strict", "[app][user]") {
    struct Case {
        std::vector<std::string> args;
        const char* flag;
    };
    const std::vector<Case> cases = {
        {{"--exposure", "1", "-f", "x.exr"}, "--exposure"},
        {{"--tonemap", "filmic", "-f", "x.exr"}, "--tonemap"},
        {{"--aov", "depth", "-f", "x.png"}, "--aov"},
        {{"--preview", "-f", "x.png"}, "--preview"},
        {{"-H", "--integrator", "normals"}, "-H/--hemisphere"},
        {{"--light-sampler", "bvh", "--integrator", "normals"}, "--light-sampler"},
        {{"--noise-threshold", "0.1", "--adaptive", "none"}, "--noise-threshold"},
        {{"--pass-spp", "4"}, "--pass-spp"},
        {{"--triangle", "watertight"}, "--triangle"},
        {{"--embree-robust", "--accel", "builtin"}, "--embree-robust"},
        {{"--embree-quality", "high", "--accel", "brute"}, "--embree-quality"},
    };
    for (const Case& c : cases) {
        INFO(c.flag);
        RenderArgs a = parse_render_command_line(cat(c.args, {"s.dae"}));
        REQUIRE(a.warnings.size() == 1);
        CHECK_THAT(a.warnings[0], Catch::StartsWith(c.flag));
        try {
            parse_render_command_line(cat(c.args, {"--strict", "s.dae"}));
            FAIL("no error under --strict");
        } catch (const Error& e) {
            CHECK(e.kind() == ErrorKind::Usage);
            CHECK_THAT(e.what(), Catch::Contains(c.flag) && Catch::Contains("--strict"));
        }
    }
    // The same flags in a combination where they act: no warning.
    CHECK(parse_render_command_line({"--exposure", "1", "-f", "x.png", "s.dae"}).warnings.empty());
    CHECK(parse_render_command_line({"--exposure", "1", "--preview", "s.dae"}).warnings.empty());
    CHECK(parse_render_command_line({"--triangle", "watertight", "--accel", "builtin", "s.dae"})
              .warnings.empty());
    // On the command line: a warning line, the render goes on; an error under --strict.
    TempDir dir("noop");
    Result w = run_candela(
        {"render", kBox, "-r", "8", "6", "-s", "1", "--exposure", "2", "-f", dir / "w.exr"});
    CHECK(w.status == 0);
    CHECK_THAT(w.err, Catch::Contains("candela: warning: --exposure has no effect"));
    Result s = run_candela(
        cat({"render", kBox, "--exposure", "2", "--strict", "-f", dir / "s.exr"}, kBigRequest));
    CHECK(s.status == 2);
    check_error_output(s, "--exposure");
}

// --- 5, 6: alpha, depth, windows ----------------------------------------------------------------

TEST_CASE("5: alpha is coverage and background depth is +inf", "[app][user]") {
    TempDir dir("alpha");
    const std::string out = dir / "a.exr";
    REQUIRE(
        run_candela({"render", kSpheres, "-r", "64", "48", "-s", "16", "-q", "-f", out}).status ==
        0);
    const ImageData img = read_image(out);
    const int A = img.channel_index("A"), Z = img.channel_index("Z"),
              n = img.channel_index("samples");
    REQUIRE(A >= 0);
    REQUIRE(Z >= 0);
    // The framed camera sees past the open box at the image corners: background.
    for (auto [x, y] : {std::pair{0, 0}, std::pair{63, 0}, std::pair{0, 47}, std::pair{63, 47}}) {
        INFO("corner " << x << ", " << y);
        CHECK(img.at(x, y, n) == 16.f);
        CHECK(img.at(x, y, A) == 0.f);
        CHECK(std::isinf(img.at(x, y, Z)));
        CHECK(img.at(x, y, Z) > 0.f);
        CHECK(img.at(x, y, 0) == 0.f); // no light from the (empty) background: premultiplied
    }
    // Inside the box every sample hits; at its silhouette only some do.
    CHECK(img.at(32, 24, A) == 1.f);
    CHECK(std::isfinite(img.at(32, 24, Z)));
    int partial = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float a = img.at(x, y, A);
            partial += a > 0.f && a < 1.f;
            // A is a count of hits over the count of samples.
            const float hits = a * img.at(x, y, n);
            CHECK(std::abs(hits - std::round(hits)) < 1e-3f);
        }
    CHECK(partial > 0);
}

TEST_CASE("6, 8: a region render keeps its place, and merged regions give the frame",
          "[app][user]") {
    TempDir dir("regions");
    const std::vector<std::string> common = {"-r", "40", "30", "-s",     "8",
                                             "-m", "3",  "-q", "--seed", "5"};
    const std::string full = dir / "full.exr";
    REQUIRE(run_candela(cat({"render", kSpheres, "-f", full}, common)).status == 0);
    // Four cells (CS184: x y dx dy, rows from the bottom), one of them odd-sized.
    const std::vector<std::vector<std::string>> cells = {{"0", "0", "17", "13"},
                                                         {"17", "0", "23", "13"},
                                                         {"0", "13", "17", "17"},
                                                         {"17", "13", "23", "17"}};
    std::vector<std::string> merge = {"merge"};
    for (std::size_t k = 0; k < cells.size(); ++k) {
        const std::string part = dir / ("part" + std::to_string(k) + ".exr");
        REQUIRE(run_candela(cat(cat({"render", kSpheres, "-f", part, "-p"}, cells[k]), common))
                    .status == 0);
        merge.push_back(part);
    }
    // The data window of the cell x=17 y=0 dx=23 dy=13 in a 40x30 frame: top row 30-13 = 17.
    const ImageData p1 = read_image(dir / "part1.exr");
    CHECK(p1.width == 23);
    CHECK(p1.height == 13);
    CHECK(p1.x == 17);
    CHECK(p1.y == 17);
    CHECK(p1.display_width() == 40);
    CHECK(p1.display_height() == 30);
    // Merging the cells assembles the frame: every channel bit-identical to the full render.
    const std::string merged = dir / "merged.exr";
    merge.insert(merge.end(), {"-o", merged, "-q"});
    REQUIRE(run_candela(merge).status == 0);
    const ImageData f = read_image(full), m = read_image(merged);
    CHECK(m.x == 0);
    CHECK(m.y == 0);
    REQUIRE(m.width == f.width);
    REQUIRE(m.height == f.height);
    REQUIRE(m.channel_names == f.channel_names);
    CHECK(std::memcmp(m.pixels.data(), f.pixels.data(), f.pixels.size() * sizeof(float)) == 0);
    CHECK(m.meta("candela:spp") == "8");
}

TEST_CASE("8: merged sample ranges keep samples, alpha and depth bit-identical", "[app][user]") {
    TempDir dir("ranges");
    const std::vector<std::string> common = {"-r", "24", "18", "-m", "3", "-q", "--seed", "2"};
    REQUIRE(
        run_candela(cat({"render", kSpheres, "-s", "12", "-f", dir / "full.exr"}, common)).status ==
        0);
    REQUIRE(run_candela(cat({"render", kSpheres, "-s", "5", "-f", dir / "a.exr"}, common)).status ==
            0);
    REQUIRE(run_candela(
                cat({"render", kSpheres, "-s", "7", "--sample-offset", "5", "-f", dir / "b.exr"},
                    common))
                .status == 0);
    REQUIRE(
        run_candela({"merge", dir / "a.exr", dir / "b.exr", "-o", dir / "m.exr", "-q"}).status ==
        0);
    const ImageData f = read_image(dir / "full.exr"), m = read_image(dir / "m.exr");
    REQUIRE(f.channel_names == m.channel_names);
    for (const char* ch : {"samples", "A", "Z"}) {
        INFO(ch);
        const int c = f.channel_index(ch);
        int differ = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x)
                differ += std::memcmp(&f.pixels[(std::size_t(y) * f.width + x) * f.channels() + c],
                                      &m.pixels[(std::size_t(y) * m.width + x) * m.channels() + c],
                                      sizeof(float)) != 0;
        CHECK(differ == 0);
    }
}

// --- 7: metadata ---------------------------------------------------------------------------------

TEST_CASE("7: the EXR describes itself with typed attributes", "[app][user]") {
    TempDir dir("meta");
    const std::string out = dir / "m.exr";
    REQUIRE(run_candela({"render",     kSpheres, "-r", "32",  "24",
                         "-s",         "4",      "-q", "-H",  "--no-mis",
                         "-b",         "0.05",   "-d", "4.2", "--light-paths",
                         "direct",     "-o",     "0",  "-m",  "2",
                         "--rr-depth", "5",      "-a", "2",   "0.1",
                         "-f",         out})
                .status == 0);
    const ImageData img = read_image(out);
    using T = Attribute::Type;
    CHECK_THAT(attr(img, "Software", T::String).text, Catch::StartsWith("candela 0.1.0 ("));
    CHECK_THAT(attr(img, "candela:command_line", T::String).text,
               Catch::StartsWith("candela render ") && Catch::Contains("--no-mis"));
    CHECK(attr(img, "candela:spp", T::Int).i == 4);
    CHECK(attr(img, "candela:max_depth", T::Int).i == 2);
    CHECK(attr(img, "candela:accumulate", T::Int).i == 0);
    CHECK(attr(img, "candela:hemisphere", T::Int).i == 1);
    CHECK(attr(img, "candela:mis", T::Int).i == 0);
    CHECK(attr(img, "candela:rr_depth", T::Int).i == 5);
    CHECK(attr(img, "candela:light_samples", T::Int).i == 1);
    CHECK(attr(img, "candela:seed", T::Int).i == 0);
    CHECK(attr(img, "candela:sample_offset", T::Int).i == 0);
    CHECK(attr(img, "candela:lens_radius", T::Float).f == 0.05f);
    CHECK(attr(img, "candela:focal_distance", T::Float).f == 4.2f);
    CHECK(attr(img, "candela:light_paths", T::String).text == "direct");
    CHECK(attr(img, "candela:adaptive", T::String).text == "cs184");
    CHECK(attr(img, "candela:adaptive_batch", T::Int).i == 2);
    CHECK(attr(img, "candela:adaptive_tol", T::Float).f == 0.1f);
    CHECK(attr(img, "candela:noise_threshold", T::Float).f == 0.f); // cs184 has none
    CHECK(attr(img, "candela:render_seconds", T::Double).d > 0.0);
    CHECK(attr(img, "candela:sessions", T::Int).i == 1);
    CHECK(attr(img, "candela:samples", T::Double).d > 0.0);
    CHECK(attr(img, "candela:interrupted", T::Int).i == 0);
    // The camera matrices (OpenEXR standard attributes, row vectors): the framed camera looks
    // at the centre of the bounds, which lands in the middle of the frame.
    const Attribute& w2c = attr(img, "worldToCamera", T::Matrix44);
    const Attribute& w2n = attr(img, "worldToNDC", T::Matrix44);
    const double target[4] = {0.0, 0.8, 0.0, 1.0}; // cornell-spheres: bounds centre
    double c[4] = {}, n[4] = {};
    for (int k = 0; k < 4; ++k)
        for (int r = 0; r < 4; ++r) {
            c[k] += target[r] * w2c.m[std::size_t(4 * r + k)];
            n[k] += target[r] * w2n.m[std::size_t(4 * r + k)];
        }
    // Tolerance: float matrices of unit-scale scenes.
    constexpr double kMatrixTol = 1e-5;
    CHECK(c[0] == Approx(0.0).margin(kMatrixTol));
    CHECK(c[1] == Approx(0.0).margin(kMatrixTol));
    CHECK(c[2] > 0.0); // in front of the camera (+z is the viewing direction)
    CHECK(n[0] / n[3] == Approx(0.5).margin(kMatrixTol));
    CHECK(n[1] / n[3] == Approx(0.5).margin(kMatrixTol));
}

TEST_CASE("7: world_to_ndc maps camera rays to their pixels", "[app][user]") {
    const Camera cam = test::sideways_camera();
    const int W = 200, H = 100;
    const std::array<float, 16> M = world_to_ndc_matrix(cam, W, H);
    // The renderer's ray through film point (fx, fy).
    const CameraProjection projection(cam, W, H);
    for (auto [fx, fy] : {std::pair{0.f, 0.f}, std::pair{200.f, 100.f}, std::pair{37.5f, 81.f}}) {
        const Ray r = projection.ray(fx, fy, Vec2(0.5f, 0.5f));
        const Vec3 p = r.o + r.d * 7.f;
        double v[4] = {};
        for (int k = 0; k < 4; ++k)
            v[k] = p.x * M[std::size_t(k)] + p.y * M[std::size_t(4 + k)] +
                   p.z * M[std::size_t(8 + k)] + M[std::size_t(12 + k)];
        CHECK(v[0] / v[3] == Approx(fx / W).margin(1e-5));
        CHECK(v[1] / v[3] == Approx(fy / H).margin(1e-5));
        CHECK(v[2] / v[3] > 0.0);
        CHECK(v[2] / v[3] < 1.0);
    }
}

// --- 9: messages
// -----------------------------------------------------------------------------------

TEST_CASE("9: one error format, plain reasons, suggestions, help", "[app][user]") {
    TempDir dir("errors");
    {
        std::ofstream(dir.path / "empty.dae");
        std::ofstream(dir.path / "mesh.obj") << "v 0 0 0\n";
    }
    struct Case {
        std::vector<std::string> args;
        int status;
        const char* needle;
    };
    const std::vector<Case> cases = {
        {{"render", dir / "none.dae"}, 4, "none.dae: cannot open scene file: No such file"},
        {{"render", dir / "empty.dae"}, 3, "empty.dae: empty file"},
        {{"render", dir / "mesh.obj"}, 3, "only COLLADA (.dae) scenes are read"},
        {{"info", dir / "empty.dae"}, 3, "empty file"},
        {{"render", "/dev/null"}, 3, "/dev/null: empty file"},
        {{"rendr", kBox}, 2, "did you mean 'render'?"},
        {{"render", kBox, "--sp", "4"}, 2, "did you mean '--spp'?"},
        {{"render", kBox, "-s", "4", "-s", "8"}, 2, "-s/--spp was given 2 times"},
        {{"render", kBox, "-r", "10"}, 2, "-r/--resolution takes 2 whole numbers"},
        {{"render", kBox, "-s", "abc"}, 2, "'abc' is not a whole number"},
        {{"render", kBox, "-t", "999999999999"}, 2, "-t/--threads: '999999999999' is out of range"},
        {{"info"}, 2, "SCENE is missing"},
        {{"merge", dir / "a.exr", "-o", dir / "b.exr"}, 4, "No such file or directory"},
        {{}, 2, "no command given"},
    };
    for (const Case& c : cases) {
        const bool render = !c.args.empty() && c.args[0] == "render";
        Result r = run_candela(render ? cat(c.args, {"-f", dir / "o.exr"}) : c.args);
        INFO(c.needle);
        CHECK(r.status == c.status);
        if (c.args.empty()) {
            // The command list first, then the error.
            CHECK_THAT(r.err, Catch::Contains("candela: error: no command given"));
            continue;
        }
        check_error_output(r, c.needle);
    }
    CHECK_FALSE(fs::exists(dir.path / "o.exr"));
    // `help COMMAND` is `COMMAND --help`; every help ends with the exit statuses.
    Result h1 = run_candela({"help", "render"}), h2 = run_candela({"render", "--help"});
    CHECK(h1.status == 0);
    CHECK(h1.out == h2.out);
    for (const std::vector<std::string>& args :
         std::vector<std::vector<std::string>>{{"--help"}, {"help"}, {"help", "merge"}}) {
        Result h = run_candela(args);
        CHECK(h.status == 0);
        CHECK_THAT(h.out,
                   Catch::Contains("Exit status:") && Catch::EndsWith("70  internal error\n"));
    }
}

// --- 10: interrupts and resume ------------------------------------------------------------------

/// The second Ctrl-C writes and exits "at once": within this, where the pass it cuts short
/// would take tens of minutes.
constexpr double kImmediateExitSeconds = 10.0;

TEST_CASE("10: Ctrl-C says it stops after the pass and a second one ends the process at once",
          "[app][user]") {
    TempDir dir("sigint");
    const std::string out = dir / "i.exr";
    // A finished image is already at the output path.
    REQUIRE(run_candela({"render", kSpheres, "-r", "8", "6", "-s", "2", "-q", "-f", out}).status ==
            0);
    const std::string before = read_text(out);
    // One pass covers the whole render, so only the second signal can end it early.
    Proc p({"render", kSpheres, "-r", "320", "240", "-s", "100000", "--pass-spp", "100000",
            "--adaptive", "none", "-t", "1", "-f", out, "--progress", "json"});
    REQUIRE(p.wait_for("\"event\":\"start\"", 120.0));
    p.signal(SIGINT);
    CHECK(p.wait_for("stopping after the current pass", 1.0, true));
    const auto t0 = Proc::Clock::now();
    p.signal(SIGINT);
    const int status = p.wait(30.0);
    const double seconds = std::chrono::duration<double>(Proc::Clock::now() - t0).count();
    INFO(p.err);
    CHECK(status == 5);
    // At once: long before the pass would end (tens of minutes at this setting); the bound
    // allows for process exit on a machine shared by many jobs.
    CHECK(seconds < kImmediateExitSeconds);
    // No pass finished: nothing is written, and the image that was there is left as it was.
    CHECK(read_text(out) == before);
    CHECK_FALSE(fs::exists(out + ".ckpt"));
    CHECK_THAT(p.err, Catch::Contains("nothing written (" + out + " left as it was)"));
}

TEST_CASE("10: a checkpoint resumes from any directory and refusals say what may change",
          "[app][user]") {
    TempDir dir("resume-anywhere");
    fs::create_directories(dir.path / "work");
    fs::create_directories(dir.path / "elsewhere");
    fs::copy_file(kSpheres, dir.path / "work/scene.dae");
    // Relative paths, from the working directory of the render.
    Proc p({"render", "scene.dae", "-r", "24", "18", "-s", "64", "--pass-spp", "1", "--adaptive",
            "none", "-t", "1", "-f", "out.exr", "--checkpoint-every", "1e-6", "--progress", "json"},
           (dir.path / "work").string());
    REQUIRE(p.wait_for("\"event\":\"start\"", 120.0));
    const fs::path ckpt = dir.path / "work/out.exr.ckpt";
    for (int i = 0; i < 2000 && !fs::exists(ckpt); ++i)
        ::usleep(5000);
    p.signal(SIGINT);
    REQUIRE(p.wait(120.0) == 5);
    REQUIRE(fs::exists(ckpt));
    const ImageData partial = read_image((dir.path / "work/out.exr").string());
    const double first_seconds = partial.attribute("candela:render_seconds")->d;
    // A changed setting: refused, naming it and the options that may change.
    Result refused = run_candela({"render", "--resume", ckpt.string(), "-m", "3"},
                                 (dir.path / "elsewhere").string());
    CHECK(refused.status == 2);
    check_error_output(refused, "-m/--max-depth is 3 here but 8 in the checkpoint");
    CHECK_THAT(refused.err, Catch::Contains("-t/--threads") && Catch::Contains("--progress"));
    // From another directory: the paths in the checkpoint are absolute.
    Result resumed = run_candela({"render", "--resume", ckpt.string(), "-q", "-t", "2"},
                                 (dir.path / "elsewhere").string());
    INFO(resumed.err);
    CHECK(resumed.status == 0);
    const ImageData done = read_image((dir.path / "work/out.exr").string());
    CHECK(done.at(5, 5, done.channel_index("samples")) == 64.f);
    CHECK(done.attribute("candela:sessions")->i == 2);
    CHECK(done.attribute("candela:render_seconds")->d >= first_seconds);
    CHECK_FALSE(fs::exists(dir.path / "elsewhere/out.exr"));
}

// --- 11: quiet by default -----------------------------------------------------------------------

TEST_CASE(
    "11: own scenes render without notes and -v and info show them and rate image only with -a",
    "[app][user]") {
    TempDir dir("quiet");
    for (const char* scene : {"cornell-box.dae", "cornell-spheres.dae", "glass.dae", "glossy.dae",
                              "lights.dae", "materials.dae"}) {
        INFO(scene);
        std::vector<std::string> args = {"render", project_scene(scene), "-r", "8", "6", "-s", "1",
                                         "-f",     dir / "q.exr"};
        // A closed room: the framed camera warns (shipped_scenes_test.cpp); its own does not.
        if (std::string(scene) == "materials.dae") args.insert(args.end(), {"--camera", "file"});
        Result r = run_candela(args);
        CHECK(r.status == 0);
        CHECK_THAT(r.err, !Catch::Contains("note:") && !Catch::Contains("warning:") &&
                              !Catch::Contains("left out"));
    }
    Result v =
        run_candela({"render", kSpheres, "-r", "8", "6", "-s", "1", "-v", "-f", dir / "v.exr"});
    CHECK_THAT(v.err, Catch::Contains("candela: note: ") && Catch::Contains("left out"));
    Result info = run_candela({"info", kSpheres});
    CHECK_THAT(info.out, Catch::Contains("no delta-BSDF paths"));
    // -q and --log-level on every subcommand.
    for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
             {"info", kBox, "-q"},
             {"info", kBox, "--log-level", "error"},
             {"check", kBox, "-q", "--camera-rays", "8", "--bounce-rays", "10", "--shadow-rays",
              "10", "--edge-rays", "10"},
             // (error: the bench warns when the machine's load exceeds its cores)
             {"bench", kBox, "--log-level", "error", "--rays", "100", "--min-seconds", "0.01", "-t",
              "1", "--no-raw"},
             {"render", kBox, "-r", "8", "6", "-s", "1", "--log-level", "error", "-f",
              dir / "l.exr"}}) {
        Result r = run_candela(args);
        INFO(args[0]);
        CHECK(r.status == 0);
        CHECK(r.err.empty());
    }
    CHECK(run_candela({"info", kBox, "--log-level", "loud"}).status == 2);
    // The sample-rate image: only for adaptive renders, and reported.
    Result plain = run_candela(
        {"render", kBox, "-r", "8", "6", "-s", "2", "--adaptive", "none", "-f", dir / "p.png"});
    CHECK(plain.status == 0);
    CHECK_FALSE(fs::exists(dir.path / "p_rate.png"));
    Result adaptive = run_candela(
        {"render", kBox, "-r", "8", "6", "-s", "4", "-a", "2", "0.05", "-f", dir / "a.png"});
    CHECK(adaptive.status == 0);
    CHECK(fs::exists(dir.path / "a_rate.png"));
    CHECK_THAT(adaptive.err,
               Catch::Contains("wrote " + (dir / "a.png") + ", " + (dir / "a_rate.png")));
}

// --- 12: stats and machine-readable progress ---------------------------------------------------

TEST_CASE("12: the summary ends with a stats block and --progress json prints JSON lines",
          "[app][user]") {
    TempDir dir("stats");
    Result r = run_candela(
        {"render", kSpheres, "-r", "16", "12", "-s", "8", "-a", "2", "0.05", "-f", dir / "s.exr"});
    CHECK(r.status == 0);
    const std::regex block("stats:\n"
                           "  samples/pixel  mean [0-9.]+, min [0-9]+, max [0-9]+ .*\n"
                           "  by region      mean samples/pixel, top row first:\n"
                           "(( +[0-9]+)+\n)+"
                           "  stopped .*\n"
                           "  samples .*\n"
                           "  rays .*\n"
                           "  time +[0-9.]+ s: start-up [0-9.]+, load [0-9.]+, build [0-9.]+, "
                           "render [0-9.]+, write [0-9.]+\n"
                           "  peak memory +[0-9.]+ [KMG]iB\n$");
    INFO(r.err);
    CHECK(std::regex_search(r.err, block));

    Result j = run_candela({"render", kSpheres, "-r", "16", "12", "-s", "8", "-q", "--progress",
                            "json", "-f", dir / "j.exr"});
    CHECK(j.status == 0);
    CHECK(j.err.empty()); // -q: nothing for humans, the JSON for the farm on stdout
    const std::vector<std::string> lines = lines_of(j.out);
    REQUIRE(lines.size() >= 3);
    for (const std::string& l : lines) {
        CHECK_THAT(l, Catch::StartsWith("{\"event\":\"") && Catch::EndsWith("}"));
    }
    CHECK_THAT(lines.front(), Catch::Contains("\"event\":\"start\""));
    CHECK_THAT(lines[lines.size() - 2],
               Catch::Contains("\"event\":\"progress\"") && Catch::Contains("\"fraction\":1.0,"));
    CHECK_THAT(lines.back(), Catch::Contains("\"event\":\"done\"") &&
                                 Catch::Contains("\"status\":0") &&
                                 Catch::Contains("\"peak_memory_bytes\":") &&
                                 Catch::Contains("\"render\":") && Catch::Contains("\"startup\":"));
}

// --- 13, 15: the flag table, the manual page, -o in other commands ---------------------------

namespace {

/// Every flag `candela COMMAND --help` lists ("-s", "--spp", ...).
std::set<std::string> help_flags(const std::string& command) {
    Result h = run_candela({command, "--help"});
    REQUIRE(h.status == 0);
    std::set<std::string> flags;
    const std::regex opt("^  (-[^ ]+)");
    for (const std::string& line : lines_of(h.out)) {
        std::smatch m;
        if (!std::regex_search(line, m, opt)) continue;
        std::stringstream names(m[1].str());
        std::string name;
        while (std::getline(names, name, ','))
            flags.insert(name);
    }
    flags.erase("-h");
    flags.erase("--help");
    return flags;
}

} // namespace

TEST_CASE("13: docs/usage.md's flag table is the render --help", "[app][user]") {
    const std::string readme = read_text(std::string(CANDELA_SOURCE_DIR) + "/docs/usage.md");
    // The table: rows "| `-s N` | `--spp` | ... |" between "| flag |" and the next blank line.
    const std::size_t start = readme.find("| flag | long form |");
    REQUIRE(start != std::string::npos);
    const std::size_t end = readme.find("\n\n", start);
    std::set<std::string> table;
    const std::regex cell("`(-{1,2}[a-zA-Z][a-zA-Z0-9-]*)");
    for (const std::string& row : lines_of(readme.substr(start, end - start))) {
        // Only the first two cells name flags.
        std::size_t c1 = row.find('|', 1), c2 = row.find('|', c1 + 1);
        if (c1 == std::string::npos || c2 == std::string::npos) continue;
        const std::string names = row.substr(0, c2);
        for (std::sregex_iterator it(names.begin(), names.end(), cell), e; it != e; ++it)
            table.insert((*it)[1].str());
    }
    const std::set<std::string> help = help_flags("render");
    for (const std::string& f : help) {
        INFO("in --help, not in the table of docs/usage.md: " << f);
        CHECK(table.count(f) == 1);
    }
    for (const std::string& f : table) {
        INFO("in the table of docs/usage.md, not in --help: " << f);
        CHECK(help.count(f) == 1);
    }
    // -o is CS184's accumulate in render and the output file in merge and converge.
    CHECK(help_flags("merge").count("-o") == 1);
    CHECK_THAT(run_candela({"merge", "--help"}).out, Catch::Contains("output file"));
    CHECK_THAT(run_candela({"converge", "--help"}).out, Catch::Contains("Output prefix"));
}

TEST_CASE("15: the manual page holds every command's --help", "[app][user]") {
    Result man = run_candela({"help", "--man"});
    REQUIRE(man.status == 0);
    CHECK_THAT(man.out, Catch::StartsWith(".TH CANDELA 1"));
    const std::string built = read_text(std::string(CANDELA_MAN_PAGE));
    CHECK(built == man.out); // the page the build wrote, and that cmake --install installs
    for (const char* cmd : {"render", "info", "check", "bench", "converge", "merge"}) {
        CHECK_THAT(man.out, Catch::Contains(std::string(".SS ") + cmd));
        for (const std::string& flag : help_flags(cmd)) {
            std::string escaped;
            for (char ch : flag)
                escaped += ch == '-' ? std::string("\\-") : std::string(1, ch);
            INFO(cmd << " " << flag);
            CHECK_THAT(man.out, Catch::Contains(escaped));
        }
    }
}

// --- 14: previews
// ---------------------------------------------------------------------------------

TEST_CASE("14: -f writes any format OpenImageIO writes and tone maps", "[app][user]") {
    TempDir dir("previews");
    for (const char* ext : {".png", ".jpg", ".tif", ".hdr", ".exr"}) {
        const std::string out = dir / (std::string("p") + ext);
        Result r = run_candela({"render", kBox, "-r", "16", "12", "-s", "2", "-q", "--tonemap",
                                ext == std::string(".png") ? "filmic" : "clamp", "-f", out});
        INFO(ext << " " << r.err);
        CHECK(r.status == 0);
        const ImageHeader h = read_image_header(out);
        CHECK(h.width == 16);
        CHECK(h.height == 12);
    }
    CHECK(run_candela({"render", kBox, "--tonemap", "aces", "-f", dir / "x.png"}).status == 2);
    // The tone maps: clamp clips, reinhard and filmic compress, all stay in [0, 1] and keep order.
    const Rgb bright(8.f, 4.f, 1.f);
    CHECK(tonemap_color(bright, 1.f, Tonemap::Clamp).x == 8.f);
    for (Tonemap t : {Tonemap::Reinhard, Tonemap::Filmic}) {
        INFO(tonemap_name(t));
        float prev = -1.f;
        for (float v : {0.f, 0.01f, 0.1f, 0.5f, 1.f, 4.f, 100.f, 1e6f}) {
            const float y = tonemap_color(Rgb(v), 1.f, t).y;
            CHECK(y >= 0.f);
            CHECK(y <= 1.f);
            CHECK(y >= prev);
            prev = y;
        }
        CHECK(tonemap_color(Rgb(0.f), 1.f, t) == Rgb(0.f));
    }
    // Exposure scales before the tone map: +1 stop of v is v doubled.
    CHECK(tonemap_color(Rgb(0.3f), 2.f, Tonemap::Filmic) ==
          tonemap_color(Rgb(0.6f), 1.f, Tonemap::Filmic));
}

// --- 16: a clone without the CS184 scenes -------------------------------------------------------

TEST_CASE("16: a CS184-scene test reports itself skipped when the scenes are absent",
          "[app][user]") {
    // This test binary, run on one CS184 test with the scene folder pointed elsewhere.
    char self[4096] = {};
    const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
    REQUIRE(n > 0);
    const std::string cmd = "CANDELA_CS184_SCENES=/nonexistent '" + std::string(self) +
                            "' 'builder: CBempty keeps its panel as a mesh light' 2>&1";
    FILE* p = ::popen(cmd.c_str(), "r");
    REQUIRE(p != nullptr);
    std::string out;
    char buf[4096];
    std::size_t got;
    while ((got = std::fread(buf, 1, sizeof buf, p)) > 0)
        out.append(buf, got);
    const int st = ::pclose(p);
    INFO(out);
    CHECK(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 0);
    CHECK_THAT(out, Catch::Contains("SKIPPED: needs the CS184 scenes in /nonexistent"));
}

TEST_CASE("15: cmake --install installs a candela that finds its image module", "[app][user]") {
    TempDir dir("install");
    const std::string build = fs::path(CANDELA_MAN_PAGE).parent_path().string();
    const std::string log = dir / "install.log";
    REQUIRE(std::system(("cmake --install '" + build + "' --prefix '" + dir.path.string() +
                         "' > '" + log + "' 2>&1")
                            .c_str()) == 0);
    const fs::path bin = dir.path / "bin" / "candela";
    REQUIRE(fs::exists(bin));
    CHECK(read_text(log).find("share/man/man1/candela.1") != std::string::npos);
    // The installed binary loads the installed module (LD_DEBUG names each file it maps), not
    // the one in the build tree.
    const std::string out = dir / "a.exr";
    const std::string cmd =
        "LD_DEBUG=files '" + bin.string() + "' render '" + std::string(CANDELA_PROJECT_SCENES) +
        "/cornell-box.dae' -r 8 6 -s 1 -q -f '" + out + "' > '" + (dir / "render.log") + "' 2>&1";
    CHECK(std::system(cmd.c_str()) == 0);
    CHECK(fs::exists(out));
    const std::string loaded = read_text(dir / "render.log");
    const std::regex module_line("file=([^ ]*libcandela_image\\.so)");
    std::smatch m;
    REQUIRE(std::regex_search(loaded, m, module_line));
    CHECK(fs::path(m[1].str()).lexically_normal().string().rfind(dir.path.string(), 0) == 0);
}
