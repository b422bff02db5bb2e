// The choice options of `candela render` come from one table per enum (util/enum_table.h):
// parsing, printing, the choices in --help and the error for an unknown value.
#include "candela/app/cli.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <set>

using namespace candela;

namespace {

template <typename E, std::size_t N> void check_round_trip(const EnumTable<E, N>& table) {
    std::set<std::string> names;
    for (const EnumChoice<E>& c : table) {
        INFO(c.name);
        CHECK(names.insert(c.name).second);
        CHECK(std::string(enum_name(table, c.value)) == c.name);
        CHECK(parse_enum(table, "--flag", c.name) == c.value);
    }
    CHECK_THROWS_AS(parse_enum(table, "--flag", "no-such-choice"), Error);
}

std::string usage_error(const std::vector<std::string>& argv) {
    try {
        parse_render_command_line(argv);
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Usage);
        return error_line(e); // the line the user sees
    }
    FAIL("expected a usage error");
    return "";
}

std::string option_help(const std::string& name) {
    RenderArgs args;
    CLI::App app{"render"};
    add_render_options(app, args);
    const CLI::Option* o = app.get_option(name);
    return o->get_description() + " [" + o->get_default_str() + "]";
}

} // namespace

TEST_CASE("choice tables: every name parses back to its value", "[cli][quick]") {
    check_round_trip(kAccelKinds);
    check_round_trip(kTriangleTests);
    check_round_trip(kEmbreeQualities);
    check_round_trip(kSamplerKinds);
    check_round_trip(kIntegratorKinds);
    check_round_trip(kLightPaths);
    check_round_trip(kAdaptiveKinds);
    check_round_trip(kCameraModes);
    check_round_trip(kTonemaps);
    check_round_trip(kProgressModes);
    CHECK(parse_accel_kind("builtin") == AccelKind::Builtin);
    CHECK(std::string(tonemap_name(Tonemap::Filmic)) == "filmic");
    CHECK(std::string(progress_mode_name(ProgressMode::Json)) == "json");
}

TEST_CASE("choice tables: unknown values name the choices and the nearest", "[cli][quick]") {
    CHECK(usage_error({"--accel", "brutte", "s.dae"}) ==
          "candela: error: --accel: unknown value 'brutte' (expected one of: embree, builtin, "
          "brute); "
          "did you mean 'brute'?");
    CHECK(usage_error({"--tonemap", "filmc", "s.dae"}) ==
          "candela: error: --tonemap: unknown value 'filmc' (expected one of: clamp, reinhard, "
          "filmic); "
          "did you mean 'filmic'?");
    CHECK(
        usage_error({"--progress", "jsn", "s.dae"}) ==
        "candela: error: --progress: unknown value 'jsn' (expected one of: auto, bar, lines, json, "
        "none); did you mean 'json'?");
    CHECK(usage_error({"--camera", "x", "s.dae"}) ==
          "candela: error: --camera: unknown value 'x' (expected one of: framed, file)");
    // Unknown values are reported in the order finalize_render_args checks its options.
    CHECK_THAT(usage_error({"--sampler", "halton", "--accel", "optix", "s.dae"}),
               Catch::Contains("--accel"));
    CHECK_THAT(usage_error({"--adaptive", "cs148", "s.dae"}),
               Catch::Contains("did you mean 'cs184'?"));
}

TEST_CASE("choice tables: --help lists the table's choices and default", "[cli][quick]") {
    CHECK(option_help("--accel") == "Ray traversal backend: embree, builtin or brute [embree]");
    CHECK(option_help("--sampler") ==
          "sobol (Owen-scrambled, the default) or independent (the CS184 sampler) [sobol]");
    CHECK(option_help("--camera") ==
          "framed: CS184 placement around the scene bounds; file: the COLLADA pose [framed]");
    CHECK(option_help("--light-paths") ==
          "all; direct (emitters seen directly + one bounce); indirect (two or more) [all]");
    CHECK(option_help("--embree-quality") == "Embree build quality: low, medium, high [medium]");
}

TEST_CASE("choice tables: RenderArgs holds the parsed enums", "[cli][quick]") {
    const RenderArgs d = parse_render_command_line({"s.dae"});
    CHECK(d.settings.accel.kind == AccelKind::Embree);
    CHECK(d.settings.accel.triangle == TriangleTest::MollerTrumbore);
    CHECK(d.settings.accel.quality == AccelOptions::Quality::Medium);
    CHECK(d.settings.sampler == SamplerKind::Sobol);
    CHECK(d.settings.integrator == IntegratorKind::Path);
    CHECK(d.settings.light_paths == LightPaths::All);
    CHECK(d.settings.adaptive == AdaptiveKind::Relative);
    CHECK_FALSE(d.adaptive_kind);
    CHECK(d.build.camera_mode == CameraMode::Framed);
    CHECK(d.tonemap == Tonemap::Clamp);
    CHECK(d.settings.progress == ProgressMode::Auto);
    CHECK(parse_render_command_line({"-a", "32", "0.05", "s.dae"}).settings.adaptive ==
          AdaptiveKind::Cs184);

    const RenderArgs a = parse_render_command_line({"--embree-quality", "high", "--tonemap",
                                                    "reinhard", "--progress", "none", "--adaptive",
                                                    "none", "--light-paths", "direct", "s.dae"});
    CHECK(a.settings.accel.quality == AccelOptions::Quality::High);
    CHECK(a.tonemap == Tonemap::Reinhard);
    CHECK(a.settings.progress == ProgressMode::None);
    CHECK(a.adaptive_kind == AdaptiveKind::None);
    CHECK(a.settings.adaptive == AdaptiveKind::None);
    CHECK(a.settings.light_paths == LightPaths::Direct);
    // The canonical (checkpoint) arguments spell the choices by their table names.
    const std::vector<std::string> canon = canonical_render_args(a);
    CHECK(std::find(canon.begin(), canon.end(), "reinhard") != canon.end());
    CHECK(std::find(canon.begin(), canon.end(), "high") != canon.end());
}
