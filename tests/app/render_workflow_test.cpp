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

} // namespace

// --- 3: a stale checkpoint --------------------------------------------------------------------

TEST_CASE("3: a new render to the same image replaces an earlier render's checkpoint, with a note",
          "[app][workflow]") {
    TempDir dir("stale");
    const std::string out = dir / "a.exr";
    REQUIRE(interrupted_render(out).status == 5);
    REQUIRE(fs::exists(out + ".ckpt"));
    // Another render to a.exr: warned at the start, and the old checkpoint goes with its image.
    Result again =
        run_candela({"render", kBox, "-r", "8", "6", "-s", "4", "--adaptive", "none", "-f", out});
    INFO(again.err);
    CHECK(again.status == 0);
    CHECK_THAT(again.err, Catch::Contains("warning: " + out +
                                          ".ckpt is the checkpoint of an "
                                          "earlier render"));
    CHECK_FALSE(fs::exists(out + ".ckpt"));
    // Resuming it is no longer possible, so it cannot overwrite the newer a.exr.
    const std::string newer = read_text(out);
    CHECK(run_candela({"render", "--resume", out + ".ckpt", "-q"}).status == 4);
    CHECK(read_text(out) == newer);
    // A render without an earlier checkpoint says nothing about one.
    Result plain =
        run_candela({"render", kBox, "-r", "8", "6", "-s", "4", "--adaptive", "none", "-f", out});
    CHECK_THAT(plain.err, !Catch::Contains("checkpoint"));
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
