// `candela bench` from the command line: it views a scene file as the render command does
// (-e, --camera, -c), so that the scenes a user renders with those options can be measured.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <set>
#include <utility>

using namespace candela::test;

namespace {

/// Closest-hit and shadow rays of a render.
using RayCounts = std::pair<std::uint64_t, std::uint64_t>;

std::vector<std::string> joined(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

} // namespace

TEST_CASE("bench --render views a scene as the render command does", "[app][render_bench]") {
    TempDir dir("bench-view");
    // Any lat-long image is an environment map: a small render of the box is one.
    const std::string env = dir / "env.exr";
    REQUIRE(run_candela({"render", project_scene("cornell-box.dae"), "-r", "16", "8", "-s", "1",
                         "-q", "-f", env})
                .status == 0);
    const std::string scene = project_scene("open-sky.dae");
    const std::vector<std::string> view = {"-e", env, "--camera", "file"};

    // A uniform Sobol render of seed 1: the bench's first configuration.
    auto render_counts = [&](const std::vector<std::string>& extra) {
        const Result r = run_candela(
            joined({"render", scene, "-r", "24", "16", "-s", "2", "-t", "1", "--adaptive", "none",
                    "--seed", "1", "-q", "--progress", "json", "-f", dir / "r.exr"},
                   extra));
        INFO(r.err);
        REQUIRE(r.status == 0);
        const nlohmann::json done = nlohmann::json::parse(lines_of(r.out).back());
        REQUIRE(done["event"] == "done");
        return RayCounts{done["rays"].get<std::uint64_t>(),
                         done["shadow_rays"].get<std::uint64_t>()};
    };
    auto bench_counts = [&](const std::vector<std::string>& extra) {
        const Result r = run_candela(
            joined({"bench", "--render", scene, "-r", "24", "16", "-s", "2", "-t", "1",
                    "--render-rounds", "1", "--min-seconds", "0.01", "--seed", "1", "--json"},
                   extra));
        INFO(r.err);
        REQUIRE(r.status == 0);
        const nlohmann::json rep = nlohmann::json::parse(r.out);
        const nlohmann::json& row = rep.at("rows").at(0);
        REQUIRE(row.at("config") == "uniform");
        return RayCounts{row.at("camera_rays").get<std::uint64_t>() +
                             row.at("bounce_rays").get<std::uint64_t>(),
                         row.at("shadow_rays").get<std::uint64_t>()};
    };

    // The view changes the render's rays (the environment is sampled, the camera moves), and
    // the bench traces exactly the rays the render command traces, with the view and without.
    const RayCounts viewed = render_counts(view);
    CHECK(viewed != render_counts({}));
    CHECK(bench_counts(view) == viewed);
    CHECK(bench_counts({}) == render_counts({}));

    check_one_line(run_candela({"bench", "--render", "--procedural", "sphere:100", "-e", env}), 2,
                   "not to --procedural");
    check_one_line(run_candela({"bench", "--render", scene, "--camera", "side"}), 2,
                   "unknown value 'side'");
    check_one_line(run_candela({"bench", "--render", scene, "-c", dir / "none.cam"}), 4,
                   "cannot open camera file");
}

TEST_CASE("bench --render refuses the ray-rate bench's flags instead of ignoring them",
          "[app][render_bench]") {
    const std::string scene = project_scene("cornell-box.dae");
    for (const std::vector<std::string>& flag :
         std::vector<std::vector<std::string>>{{"--accel", "builtin"},
                                               {"--triangle", "watertight"},
                                               {"--embree-isa", "avx512"},
                                               {"--rays", "1000"},
                                               {"--no-raw"}}) {
        std::vector<std::string> args = {"bench", "--render", scene};
        args.insert(args.end(), flag.begin(), flag.end());
        check_one_line(run_candela(args), 2, flag[0] + " applies to the ray-rate bench only");
    }
}

TEST_CASE("bench -t takes a comma list and leaves the scene its own and figures come with their "
          "range and n/a for what was not measured",
          "[app][render_bench]") {
    const std::string scene = project_scene("cornell-box.dae");
    const std::vector<std::string> quick = {"--accel", "embree",        "--rays",
                                            "2000",    "--min-seconds", "0.02"};
    const Result j = run_candela(joined({"bench", "-t", "1,2", scene, "--json"}, quick));
    INFO(j.err);
    REQUIRE(j.status == 0);
    const nlohmann::json rep = nlohmann::json::parse(j.out);
    CHECK(rep.at("scene") == scene);
    std::set<int> threads;
    for (const nlohmann::json& r : rep.at("results")) {
        threads.insert(r.at("threads").get<int>());
        CHECK(r.at("rounds") == 5);
        CHECK(r.at("mrays_per_s_min").get<double>() <= r.at("mrays_per_s").get<double>());
        CHECK(r.at("mrays_per_s").get<double>() <= r.at("mrays_per_s_max").get<double>());
    }
    CHECK(threads == std::set<int>{1, 2});
    // The raw Embree scene's memory is not asked for: null, not 0.
    for (const nlohmann::json& b : rep.at("builds"))
        if (b.at("accel") == "embree-raw") CHECK(b.at("memory_bytes").is_null());
    // A bad value names itself alone, not the scene after it.
    const Result bad = run_candela({"bench", "-t", "x", scene});
    CHECK(bad.status == 2);
    CHECK_THAT(bad.err, !Catch::Contains(scene));

    // The text: medians with their range; without the raw loops, their ratios are n/a.
    const Result t = run_candela(joined({"bench", "-t", "1", scene, "--no-raw"}, quick));
    INFO(t.out);
    REQUIRE(t.status == 0);
    CHECK_THAT(t.out, Catch::Contains("Mrays/s (range)"));
    CHECK_THAT(t.out, Catch::Contains("embree/raw n/a"));
}

TEST_CASE("bench shows its progress on stderr when asked, and only then off a terminal",
          "[app][render_bench]") {
    const std::vector<std::string> args = {
        "bench",  "-t",     "1",    "--procedural",  "sphere:200", "--accel",
        "embree", "--rays", "1000", "--min-seconds", "0.01",       "--no-raw"};
    const Result bar = run_candela(cat(args, {"--progress", "bar"}));
    REQUIRE(bar.status == 0);
    CHECK_THAT(bar.err, Catch::Contains("100.0%"));
    // Not a terminal: no progress by default.
    const Result plain = run_candela(args);
    REQUIRE(plain.status == 0);
    CHECK_THAT(plain.err, !Catch::Contains("%"));
    check_one_line(run_candela(cat(args, {"--progress", "json"})), 2,
                   "--progress json is not offered");
}
