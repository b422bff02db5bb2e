// `candela probe` as a user runs it: its JSON is what a render writes for the pixel, and its
// splits add up; a pixel outside the frame is one error line.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

using namespace candela;
using namespace candela::test;

namespace {

/// The render's pixel and the probe's are the same float; the JSON prints floats with enough
/// digits to round-trip, and the EXR stores them as written.
constexpr double kSameFloat = 0.0;
/// A split's classes add up to the pixel up to float rounding (render/probe_test.cpp).
constexpr double kSplitSumTol = 1e-5;

} // namespace

TEST_CASE("probe --json: the pixel a render writes, split into parts that add up", "[app][probe]") {
    TempDir dir("probe-json");
    const std::string scene = project_scene("cornell-box.dae");
    const std::vector<std::string> settings = {"-r", "32", "24", "-s", "32", "--seed", "3"};
    const Result render = run_candela(
        cat({"render", scene, "--adaptive", "none", "-q", "-f", dir / "a.exr"}, settings));
    REQUIRE(render.status == 0);
    const Result probe = run_candela(cat({"probe", scene, "12", "9", "--json"}, settings));
    INFO(probe.err);
    REQUIRE(probe.status == 0);
    const nlohmann::json j = nlohmann::json::parse(probe.out);
    const ImageData image = read_image(dir / "a.exr");
    for (int c = 0; c < 3; ++c) {
        const double pixel = j["pixel"][c].get<double>();
        CHECK(std::abs(pixel - double(image.at(12, 9, c))) <= kSameFloat);
        for (const char* split :
             {"by_order", "by_light", "by_first_material", "by_first_object", "by_last_scatter"}) {
            double sum = 0.0;
            for (const auto& share : j[split])
                sum += share["rgb"][c].get<double>();
            INFO(split << " channel " << c);
            CHECK(std::abs(sum - pixel) <= kSplitSumTol * std::max(1e-3, pixel));
        }
    }
    CHECK(j["samples"] == 32);
    CHECK(j["heaviest"].size() == 3);
}

TEST_CASE("probe: a pixel outside the frame is one error line", "[app][probe]") {
    const Result r = run_candela(
        {"probe", project_scene("cornell-box.dae"), "40", "0", "-r", "32", "24", "-s", "1"});
    check_one_line(r, 2, "pixel (40, 0) is not inside the 32x24 frame");
}
