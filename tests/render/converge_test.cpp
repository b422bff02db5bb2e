// Error against run time: the error measures, the 1/N law of independent sampling, and
// `candela converge` end to end.
#include "render_support.h"

#include "candela/diagnostics/converge.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

/// A diffuse floor lit by a rectangular light, seen from above: every pixel has variance.
Scene lit_floor() {
    Scene scene;
    SceneEditor editor(scene);
    Material m;
    m.albedo = Rgb(0.6f, 0.5f, 0.4f);
    add_floor(scene, 2.f, 0.f, editor.add_material(m));
    add_rect_light(scene, Vec3(0.5f, 1.f, 0.f), Vec3(0, 0, 0.5f), Vec3(0.5f, 0, 0), Rgb(4.f));
    scene.camera = camera_looking_down(Vec3(0.f, 2.f, 0.f), 60.f);
    editor.finalize();
    return scene;
}

/// A ladder point with the figures the summary's checks read.
ConvergeRow point(const std::string& config, int spp, double seconds, double seconds_std,
                  double rel_mse) {
    ConvergeRow r;
    r.config = config;
    r.spp = spp;
    r.seconds = seconds;
    r.seconds_std = seconds_std;
    r.rel_mse = rel_mse;
    return r;
}

std::string read_all(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

} // namespace

TEST_CASE("image error: MSE and relMSE of known films", "[converge][quick]") {
    Film ref(2, 1, AovSet::parse("variance"), false), test(2, 1, AovSet::parse("none"), false);
    FilmSample a, b;
    a.L = Rgb(1.f);
    ref.add(0, 0, a);
    ref.add(1, 0, a);
    b.L = Rgb(1.5f);
    test.add(0, 0, b);
    b.L = Rgb(1.f);
    test.add(1, 0, b);
    ImageError e = image_error(test, ref);
    // One pixel off by 0.5 in every channel, one exact: MSE = 0.25 / 2.
    constexpr double kRoundoff = 1e-12; // double sums of a few floats
    CHECK(std::abs(e.mse - 0.125) < kRoundoff);
    CHECK(std::abs(e.rel_mse - 0.125 / (1.0 + kRelMseEps)) < kRoundoff);
}

TEST_CASE("time to error interpolates log-log between ladder points", "[converge][quick]") {
    std::vector<ConvergeRow> rows(2);
    rows[0].config = rows[1].config = "x";
    rows[0].seconds = 1.0;
    rows[0].rel_mse = 1e-2;
    rows[1].seconds = 100.0;
    rows[1].rel_mse = 1e-4;
    constexpr double kRoundoff = 1e-9; // exp/log of exact powers of ten
    CHECK(std::abs(time_to_error(rows, "x", 1e-3) - 10.0) < kRoundoff);
    CHECK(time_to_error(rows, "x", 1e-5) < 0.0);
    CHECK(time_to_error(rows, "y", 1e-3) < 0.0);
}

TEST_CASE("independent sampling: MSE falls as 1/N", "[converge][stat]") {
    Scene scene = lit_floor();
    RenderSettings base;
    base.width = base.height = 16;
    base.max_depth = 4;
    base.quiet = true;
    // The reference has 16x the samples of the largest rung; its own error (reported) flattens
    // the slope by less than log(1 + 1/16) / log(64) = 0.015.
    Film ref = render_reference(scene, base, 4096);
    ImageError ref_err = reference_error(ref);
    ConvergeConfig cfg = make_converge_config("uniform", base);
    std::vector<ConvergeRow> rows;
    for (int spp : {4, 16, 64, 256})
        rows.push_back(converge_point(scene, cfg, spp, 4, ref));
    const double slope = log_log_slope(rows, true);
    INFO("slope " << slope << ", reference MSE " << ref_err.mse << ", MSE at 256 spp "
                  << rows.back().mse);
    // Slope -1 for an unbiased estimator with independent samples; +-0.15 covers the spread of
    // the MSE over 4 seeds of 256 pixels (relative standard error about 5% per point).
    constexpr double kSlopeTolerance = 0.15;
    CHECK(std::abs(slope + 1.0) < kSlopeTolerance);
    CHECK(ref_err.mse < 0.1 * rows.back().mse); // the reference is far below every error
}

TEST_CASE("candela converge writes the CSV, the plot and the summary", "[converge][slow]") {
    fs::path dir = fs::temp_directory_path() / ("candela-converge-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string scene = std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae";
    const std::string cmd = std::string(CANDELA_BINARY) + " converge " + scene +
                            " -r 16 12 -m 3 --ladder 2,8 --seeds 2 --ref-spp 64 "
                            "--configs uniform,relative -q -o " +
                            (dir / "c").string() + " --cache " + (dir / "cache").string();
    REQUIRE(std::system(cmd.c_str()) == 0);
    std::string csv = read_all(dir / "c.csv");
    CHECK(csv.rfind("config,spp,mean_spp,seconds,wall_seconds,cpu_seconds,mse,mse_std,relmse,"
                    "relmse_std,efficiency,seconds_std\n",
                    0) == 0);
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 5); // header + 2 configs x 2 rungs
    CHECK(csv.find("\nuniform,8,") != std::string::npos);
    CHECK(csv.find("\nrelative,2,") != std::string::npos);
    std::string svg = read_all(dir / "c.svg");
    CHECK(svg.find("<svg") == 0);
    CHECK(svg.find("<polyline") != std::string::npos);
    std::string summary = read_all(dir / "c_summary.txt");
    CHECK(summary.find("reference: 64 spp; its estimated error") != std::string::npos);
    // The reference is cached: a second run reuses it.
    std::size_t cached = 0;
    for (const auto& f : fs::directory_iterator(dir / "cache"))
        cached += f.path().extension() == ".film";
    CHECK(cached == 1);
    REQUIRE(std::system(cmd.c_str()) == 0);
    cached = 0;
    for (const auto& f : fs::directory_iterator(dir / "cache"))
        cached += f.path().extension() == ".film";
    CHECK(cached == 1);
    fs::remove_all(dir);
}

TEST_CASE("composite converge configurations apply every part and reject conflicts",
          "[converge][quick]") {
    RenderSettings base;
    base.light_samples = 1;
    ConvergeConfig rs = make_converge_config("relative+sobol", base);
    CHECK(rs.name == "relative+sobol");
    CHECK(rs.settings.adaptive == AdaptiveKind::Relative);
    CHECK(rs.settings.sampler == SamplerKind::Sobol);
    CHECK(rs.settings.aovs.variance); // the relative part's error estimates are kept
    // The parts' settings are those of the parts alone.
    ConvergeConfig r = make_converge_config("relative", base);
    CHECK(rs.settings.adaptive_batch == r.settings.adaptive_batch);
    CHECK(rs.settings.noise_threshold == r.settings.noise_threshold);
    CHECK(r.settings.sampler == SamplerKind::Independent);

    ConvergeConfig cs = make_converge_config("cs184+sobol", base);
    CHECK(cs.settings.adaptive == AdaptiveKind::Cs184);
    CHECK(cs.settings.sampler == SamplerKind::Sobol);
    ConvergeConfig ub = make_converge_config("uniform+builtin", base);
    CHECK(ub.settings.accel.kind == AccelKind::Builtin);
    CHECK(ub.settings.adaptive == AdaptiveKind::None);
    ConvergeConfig three = make_converge_config("nomis+light4+sobol", base);
    CHECK(!three.settings.mis);
    CHECK(three.settings.light_samples == 4);
    CHECK(three.settings.sampler == SamplerKind::Sobol);
    CHECK(make_converge_config("bvh+sobol", base).settings.light_sampler == LightSamplerKind::Bvh);
    CHECK(make_converge_config("power", base).settings.light_sampler == LightSamplerKind::Power);
    CHECK_THROWS_AS(make_converge_config("power+bvh", base), Error);

    CHECK(converge_config_parts("relative+sobol") == std::vector<std::string>{"relative", "sobol"});
    CHECK(converge_config_parts("sobol") == std::vector<std::string>{"sobol"});

    CHECK_THROWS_AS(make_converge_config("relative+bogus", base), Error);
    CHECK_THROWS_AS(make_converge_config("bogus", base), Error);
    CHECK_THROWS_AS(make_converge_config("cs184+relative", base), Error);
    CHECK_THROWS_AS(make_converge_config("relative+cs184", base), Error);
    CHECK_THROWS_AS(make_converge_config("sobol+sobol", base), Error);
    CHECK_THROWS_AS(make_converge_config("sobol+", base), Error);
    CHECK_THROWS_AS(make_converge_config("+sobol", base), Error);
    CHECK_THROWS_WITH(make_converge_config("cs184+relative", base),
                      Catch::Contains("cs184") && Catch::Contains("relative"));
    CHECK_THROWS_WITH(make_converge_config("relative+bogus", base), Catch::Contains("'bogus'"));
}

TEST_CASE("candela converge compares a composite with its parts", "[converge][slow]") {
    fs::path dir =
        fs::temp_directory_path() / ("candela-converge-mix-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string scene = std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae";
    const std::string common = std::string(CANDELA_BINARY) + " converge " + scene +
                               " -r 16 12 -m 3 --ladder 2,8 --seeds 2 --ref-spp 64 -q -o " +
                               (dir / "c").string() + " --cache " + (dir / "cache").string();
    // A contradictory composite fails before any reference is rendered.
    REQUIRE(std::system((common + " --configs uniform,cs184+relative 2>/dev/null").c_str()) != 0);
    CHECK(!fs::exists(dir / "cache"));
    REQUIRE(std::system((common + " --configs uniform,sobol,relative+sobol").c_str()) == 0);
    std::string csv = read_all(dir / "c.csv");
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 7); // header + 3 configs x 2 rungs
    CHECK(csv.find("\nrelative+sobol,8,") != std::string::npos);
    std::string summary = read_all(dir / "c_summary.txt");
    INFO(summary);
    // Time to error against uniform for each, and for the composite against its one-part
    // subset present in the run (sobol), never against itself.
    auto compared = [&](const std::string& cfg, const std::string& base) {
        return summary.find(cfg + " reaches " + base + "'s relMSE") != std::string::npos ||
               summary.find(cfg + " does not reach " + base + "'s relMSE") != std::string::npos;
    };
    CHECK(compared("sobol", "uniform"));
    CHECK(compared("relative+sobol", "uniform"));
    CHECK(compared("relative+sobol", "sobol"));
    CHECK(!compared("relative+sobol", "relative+sobol"));
    CHECK(!compared("sobol", "relative+sobol"));
    fs::remove_all(dir);
}

TEST_CASE("converge says when its figures cannot be trusted", "[converge][quick]") {
    const std::vector<int> ladder = {4, 16, 64, 256};
    CHECK_THAT(reference_spp_warning(256, ladder),
               Catch::Contains("--ref-spp 256 equals the ladder's top rung (256 spp)") &&
                   Catch::Contains("--ref-spp 4096 or more"));
    CHECK_THAT(reference_spp_warning(64, ladder), Catch::Contains("is below"));
    CHECK(reference_spp_warning(kReferenceOverTopRung * 256, ladder).empty());
    CHECK(reference_spp_warning(256, {}).empty()); // equal time: no ladder

    const ConvergeRow quick = point("builtin", 4, 0.02, 0.0, 0.1);
    const ConvergeRow slow = point("uniform", 256, 2.0 * kMinTimedRenderSeconds, 0.0, 0.01);
    CHECK(short_render_warning({slow}).empty());
    CHECK_THAT(short_render_warning({slow, quick}),
               Catch::Contains("1 of 2 points") && Catch::Contains("builtin at 4 spp") &&
                   Catch::Contains("too short to time") && Catch::Contains("--time-budget"));

    CHECK(spread_text(0.0, 1) == "(one seed: no spread)");
    CHECK(spread_text(0.0012, 3) == "+- 0.0012");
}

TEST_CASE("time to error carries the render times' standard error", "[converge][quick]") {
    // Two points of one configuration whose times have relative standard errors 0.1 and 0.3.
    const ConvergeRow a = point("c", 4, 1.0, 0.1, 0.1), b = point("c", 16, 4.0, 1.2, 0.01);
    double rel = -1.0;
    // Halfway in log relMSE: halfway between the relative errors.
    const double t = time_to_error({a, b}, "c", std::sqrt(0.1 * 0.01), &rel);
    CHECK(t == Approx(2.0));
    CHECK(rel == Approx(0.2));
    // Already below at the cheapest point: that point's relative error.
    CHECK(time_to_error({a, b}, "c", 0.5, &rel) == Approx(1.0));
    CHECK(rel == Approx(0.1));
}

TEST_CASE("candela converge warns about short renders and a thin reference, and gives no "
          "spread from one seed",
          "[converge][slow]") {
    fs::path dir =
        fs::temp_directory_path() / ("candela-converge-warn-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string scene = std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae";
    const std::string cmd = std::string(CANDELA_BINARY) + " converge " + scene +
                            " -r 16 12 -m 3 --ladder 2,8 --seeds 1 --ref-spp 8 "
                            "--configs uniform,sobol -q -o " +
                            (dir / "c").string() + " --cache " + (dir / "cache").string() + " 2> " +
                            (dir / "err.txt").string();
    REQUIRE(std::system(cmd.c_str()) == 0);
    const std::string summary = read_all(dir / "c_summary.txt");
    const std::string err = read_all(dir / "err.txt");
    INFO(summary << err);
    for (const std::string& text : {summary, err}) {
        CHECK_THAT(text, Catch::Contains("--ref-spp 8 equals the ladder's top rung (8 spp)"));
        CHECK_THAT(text, Catch::Contains("too short to time"));
    }
    CHECK_THAT(summary, Catch::Contains("(one seed: no spread)"));
    CHECK_THAT(summary, !Catch::Contains("+- 0 ") && !Catch::Contains("+- 0\n"));
    fs::remove_all(dir);
}
