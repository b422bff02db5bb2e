// Refining a finished render from the command line: the prediction is printed before the
// refinement, in the stats block beside the time taken, and in the JSON done event.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>

using namespace candela::test;
namespace fs = std::filesystem;

TEST_CASE("a refinement predicts its time and says how far off it was", "[app][refine]") {
    TempDir dir("refine-cli");
    const std::string out = dir / "a.exr", ckpt = out + ".ckpt";
    const Result first =
        run_candela({"render", project_scene("cornell-box.dae"), "-r", "32", "24", "-s", "8",
                     "--adaptive", "none", "-q", "--keep-checkpoint", "-f", out});
    REQUIRE(first.status == 0);
    REQUIRE(fs::exists(ckpt));
    const Result text = run_candela({"render", "--resume", ckpt, "-s", "16", "--keep-checkpoint"});
    INFO(text.err);
    REQUIRE(text.status == 0);
    CHECK_THAT(text.err, Catch::Contains("candela: refining ") &&
                             Catch::Contains("about 6.14e+03 more samples, predicted ") &&
                             Catch::Contains("  prediction     "));
    const Result json =
        run_candela({"render", "--resume", ckpt, "-s", "24", "-q", "--progress", "json"});
    REQUIRE(json.status == 0);
    const std::vector<std::string> lines = lines_of(json.out);
    REQUIRE_FALSE(lines.empty());
    const nlohmann::json done = nlohmann::json::parse(lines.back());
    CHECK(done["event"] == "done");
    CHECK(done["predicted_render_s"].get<double>() > 0.0);
    CHECK(done["spp_max"] == 24);
    CHECK_FALSE(fs::exists(ckpt)); // kept only when asked
}
