#include "candela/app/cli.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <unistd.h>

using namespace candela;

namespace {
RenderArgs parse(std::vector<std::string> argv) {
    return parse_render_command_line(argv);
}

void check_usage_error(std::vector<std::string> argv, const std::string& needle) {
    try {
        parse(std::move(argv));
        FAIL("expected a usage error mentioning " << needle);
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Usage);
        CHECK_THAT(e.what(), Catch::Contains(needle));
    }
}
} // namespace

TEST_CASE("CS184 short flags map to render settings", "[cli][quick]") {
    RenderArgs a = parse({"-s", "64",  "-l",  "4",   "-t", "2",   "-m",   "5",
                          "-o", "0",   "-b",  "0.1", "-d", "3.5", "-f",   "out.png",
                          "-r", "480", "360", "-H",  "-a", "16",  "0.02", "scene.dae"});
    const RenderSettings& s = a.settings;
    CHECK(a.scene == "scene.dae");
    CHECK(s.spp == 64);
    CHECK(s.light_samples == 4);
    CHECK(s.threads == 2);
    CHECK(s.max_depth == 5);
    CHECK_FALSE(s.accumulate);
    CHECK(*a.lens_radius == Approx(0.1f));
    CHECK(*a.focal_distance == Approx(3.5f));
    CHECK(a.output == "out.png");
    CHECK(s.width == 480);
    CHECK(s.height == 360);
    CHECK(s.hemisphere);
    CHECK(s.adaptive == AdaptiveKind::Cs184);
    CHECK(s.adaptive_batch == 16);
    CHECK(s.adaptive_tol == Approx(0.02f));
}

TEST_CASE("long forms and defaults", "[cli][quick]") {
    RenderArgs d = parse({"dir/CBbunny.dae"});
    CHECK(d.output == "CBbunny.exr");
    CHECK(d.settings.width == 800);
    CHECK(d.settings.height == 600);
    CHECK(d.settings.accumulate);
    CHECK(d.settings.accel.kind == AccelKind::Embree);
    CHECK_FALSE(d.lens_radius.has_value());
    RenderArgs a = parse({"--spp",        "8",
                          "--threads",    "1",
                          "--output",     "x.exr",
                          "--resolution", "64",
                          "48",           "--accel=builtin",
                          "--triangle",   "watertight",
                          "--seed",       "99",
                          "--sampler",    "sobol",
                          "--integrator", "direct",
                          "--no-mis",     "--aov",
                          "depth,normal", "--light-paths",
                          "indirect",     "--camera",
                          "file",         "s.dae"});
    CHECK(a.settings.accel.kind == AccelKind::Builtin);
    CHECK(a.settings.accel.triangle == TriangleTest::Watertight);
    CHECK(a.settings.seed == 99);
    CHECK(a.settings.sampler == SamplerKind::Sobol);
    CHECK(a.settings.integrator == IntegratorKind::Direct);
    CHECK_FALSE(a.settings.mis);
    CHECK(a.settings.aovs.depth);
    CHECK_FALSE(a.settings.aovs.albedo);
    CHECK(a.settings.light_paths == LightPaths::Indirect);
    CHECK(a.build.camera_mode == CameraMode::File);
}

TEST_CASE("the noise threshold and -a's tolerance are kept apart", "[cli][quick]") {
    const RenderSettings engine;
    RenderArgs d = parse({"s.dae"});
    CHECK(d.settings.adaptive == AdaptiveKind::Relative);
    CHECK(d.settings.noise_threshold == kDefaultNoiseThreshold);
    CHECK(d.settings.adaptive_tol == engine.adaptive_tol);
    RenderArgs n = parse({"--noise-threshold", "0.07", "s.dae"});
    CHECK(n.settings.noise_threshold == Approx(0.07f));
    CHECK(n.settings.adaptive_tol == engine.adaptive_tol);
    // -a with the relative sampler: its TOLERANCE is the threshold.
    RenderArgs r = parse({"-a", "8", "0.3", "--adaptive", "relative", "s.dae"});
    CHECK(r.settings.noise_threshold == Approx(0.3f));
    CHECK(r.settings.adaptive_tol == engine.adaptive_tol);
    RenderArgs c = parse({"-a", "8", "0.3", "s.dae"});
    CHECK(c.settings.adaptive == AdaptiveKind::Cs184);
    CHECK(c.settings.adaptive_tol == Approx(0.3f));
}

TEST_CASE("region flag counts rows from the bottom like CS184", "[cli][quick]") {
    RenderArgs a = parse({"-r", "100", "80", "-p", "10", "0", "20", "30", "s.dae"});
    CHECK(a.settings.region.x == 10);
    CHECK(a.settings.region.y == 50);
    CHECK(a.settings.region.w == 20);
    CHECK(a.settings.region.h == 30);
}

TEST_CASE("bad flags give usage errors that name the flag", "[cli][quick]") {
    check_usage_error({"-s", "0", "s.dae"}, "-s/--spp");
    check_usage_error({"-s", "-3", "s.dae"}, "-s/--spp");
    check_usage_error({"-s", "abc", "s.dae"}, "abc");
    check_usage_error({"-r", "100000", "100000", "s.dae"}, "-r/--resolution");
    check_usage_error({"-r", "0", "10", "s.dae"}, "-r/--resolution");
    check_usage_error({"-r", "10", "s.dae"}, "resolution");
    check_usage_error({"-t", "-1", "s.dae"}, "-t/--threads");
    check_usage_error({"-m", "-1", "s.dae"}, "-m/--max-depth");
    check_usage_error({"-b", "-0.5", "s.dae"}, "-b/--lens-radius");
    check_usage_error({"-d", "0", "s.dae"}, "-d/--focal-distance");
    check_usage_error({"-a", "0", "0.05", "s.dae"}, "-a");
    check_usage_error({"-a", "32", "-1", "s.dae"}, "-a");
    check_usage_error({"-p", "0", "0", "900", "10", "s.dae"}, "-p/--region");
    check_usage_error({"--accel", "optix", "s.dae"}, "--accel");
    check_usage_error({"--sampler", "halton", "s.dae"}, "--sampler");
    check_usage_error({"--aov", "albedo,foo", "s.dae"}, "--aov");
    check_usage_error({"-f", "out.xyz", "s.dae"}, "-f/--output");
    check_usage_error({"--bogus", "s.dae"}, "--bogus");
    check_usage_error({}, "scene");
}

TEST_CASE("CS184 camera settings file", "[cli][quick]") {
    std::string path = "/tmp/candela-cam-" + std::to_string(::getpid()) + ".txt";
    {
        std::ofstream f(path);
        f << "49.1 37.8 1.333 0.1 100\n"
             "0 0.75 4.8 0 0.75 0\n"
             "1.5708 0 4.8 0.1 20\n"
             "1 0 0 0 1 0 0 0 1\n"
             "800 600 875\n"
             "4.2 0.05\n";
    }
    Scene scene;
    apply_camera_file(path, scene);
    CHECK(scene.camera.hfov_deg == Approx(49.1f));
    CHECK(scene.camera.pos.z == Approx(4.8f));
    CHECK(scene.camera.z.z == Approx(1.f));
    CHECK(scene.camera.lens_radius == Approx(0.05f));
    CHECK(scene.camera.focal_distance == Approx(4.2f));
    {
        std::ofstream f(path);
        f << "49.1 37.8 1.333 0.1 100\n0 0.75 nan\n";
    }
    try {
        apply_camera_file(path, scene);
        FAIL("expected an error");
    } catch (const Error& e) {
        CHECK_THAT(e.what(), Catch::StartsWith(path + ":2: "));
    }
    std::remove(path.c_str());
}

TEST_CASE("canonical arguments hold absolute paths and parse back to the same settings",
          "[cli][quick]") {
    RenderArgs a = parse({"-s",
                          "64",
                          "-r",
                          "48",
                          "36",
                          "-p",
                          "1",
                          "2",
                          "30",
                          "20",
                          "-a",
                          "8",
                          "0.05",
                          "--adaptive",
                          "relative",
                          "-H",
                          "--no-mis",
                          "-b",
                          "0.1",
                          "-c",
                          "cam.txt",
                          "-e",
                          "sky.exr",
                          "--seed",
                          "9",
                          "-t",
                          "3",
                          "-q",
                          "--checkpoint-every",
                          "5",
                          "-f",
                          "out/x.exr",
                          "dir/s.dae"});
    const std::vector<std::string> c = canonical_render_args(a);
    // Paths are absolute; runtime options (-t, -q, --checkpoint-every) are not stored.
    for (const std::string& p :
         {c.front(), c[std::size_t(std::find(c.begin(), c.end(), "--output") - c.begin() + 1)]})
        CHECK(p.front() == '/');
    CHECK(std::find(c.begin(), c.end(), "--threads") == c.end());
    CHECK(std::find(c.begin(), c.end(), "--quiet") == c.end());
    CHECK(std::find(c.begin(), c.end(), "--checkpoint-every") == c.end());
    RenderArgs b = parse(c);
    CHECK(canonical_render_args(b) == c);
    CHECK(b.settings.spp == 64);
    CHECK(b.settings.width == 48);
    CHECK(b.settings.region.y == a.settings.region.y);
    CHECK(b.settings.adaptive == AdaptiveKind::Relative);
    CHECK(b.settings.hemisphere);
    CHECK_FALSE(b.settings.mis);
    CHECK(*b.lens_radius == 0.1f);
    CHECK(b.settings.seed == 9);
    CHECK(b.settings.threads == 0);
    // A resume may change runtime options but no image setting.
    auto resuming = [&](std::vector<std::string> v) {
        v.push_back("dir/s.dae");
        RenderArgs r = parse(v);
        r.given.erase("scene");
        return r;
    };
    CHECK_NOTHROW(check_resume_matches(resuming({"-t", "8", "--progress", "json"}), b, "c.ckpt"));
    CHECK_THROWS_WITH(check_resume_matches(resuming({"-m", "5"}), b, "c.ckpt"),
                      Catch::Contains("-m/--max-depth is 5 here but") &&
                          Catch::Contains("-t/--threads"));
    // A refinement raises -s or lowers the noise threshold; the other way is refused by name.
    CHECK_NOTHROW(check_resume_matches(resuming({"-s", "65"}), b, "c.ckpt"));
    const RenderArgs plain = parse({"dir/s.dae"}); // the relative sampler, threshold 0.02
    CHECK_NOTHROW(check_resume_matches(resuming({"--noise-threshold", "0.01"}), plain, "c.ckpt"));
    CHECK_NOTHROW(check_resume_matches(resuming({"--noise-threshold", "0"}), plain, "c.ckpt"));
    CHECK_THROWS_WITH(check_resume_matches(resuming({"-s", "63"}), b, "c.ckpt"),
                      Catch::Contains("refusing to refine: -s/--spp is 63 here but 64") &&
                          Catch::Contains("may only raise it"));
    CHECK_THROWS_WITH(check_resume_matches(resuming({"--noise-threshold", "0.5"}), plain, "c.ckpt"),
                      Catch::Contains("--noise-threshold is 0.5 here but 0.02") &&
                          Catch::Contains("may only lower it"));
    // -a's tolerance is that render's threshold: --noise-threshold cannot refine it.
    CHECK_THROWS_WITH(check_resume_matches(resuming({"--noise-threshold", "0.01"}), b, "c.ckpt"),
                      Catch::Contains("does not stop at a noise threshold (it uses -a)"));
}

TEST_CASE("error lines have one shape and suggestions are near misses only", "[cli][quick]") {
    CHECK(error_line(Error(ErrorKind::Scene, SourceLoc{"a.dae", 3}, "bad thing")) ==
          "candela: error: a.dae:3: bad thing");
    CHECK(error_line(Error(ErrorKind::Usage, "-s/--spp: 0")) == "candela: error: -s/--spp: 0");
    CHECK(nearest_name("rendr", {"render", "info", "merge"}) == "render");
    CHECK(nearest_name("--sp", {"--spp", "--seed", "-s"}) == "--spp");
    CHECK(nearest_name("--light", {"--light-samples", "--light-paths"}).empty()); // ambiguous
    CHECK(nearest_name("--frobnicate", {"--spp", "--seed"}).empty());
    CHECK(nearest_name("--tonemp", {"--tonemap", "--triangle"}) == "--tonemap");
}
