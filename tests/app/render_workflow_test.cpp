// A render's life as a user lives it, through the real executable: an interrupted render and
// the checkpoint it leaves, the next render to the same file, resuming and merging and what the
// files then say about how they were made, the progress and the reason a render stopped, and
// the default sampler on a single pixel.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <algorithm>
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

} // namespace

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
