// The EXR as compositors read it: the standard chromaticities, half-float colour channels on
// request, a choice of compression, and a finite background depth on request.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/app/cli.h"
#include "candela/io/image_io.h"
#include "candela/render/exr_layout.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <iterator>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

const std::string kBox = project_scene("cornell-spheres.dae");

Result tiny_render(const std::string& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render", kBox, "-r",         "24",   "18", "-s",
                                     "2",      "-q", "--adaptive", "none", "-f", out};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_candela(args);
}

} // namespace

TEST_CASE("exr: Rec. 709 chromaticities in every EXR", "[app][exr]") {
    TempDir dir("exr-chroma");
    REQUIRE(tiny_render(dir / "a.exr").status == 0);
    const ImageData img = read_image(dir / "a.exr");
    const Attribute* c = img.attribute("chromaticities");
    REQUIRE(c != nullptr);
    REQUIRE(c->type == Attribute::Type::Floats);
    CHECK(c->floats == kRec709Chromaticities);
    // merge writes it too.
    REQUIRE(tiny_render(dir / "b.exr", {"--sample-offset", "2"}).status == 0);
    REQUIRE(
        run_candela({"merge", dir / "a.exr", dir / "b.exr", "-o", dir / "m.exr", "-q"}).status ==
        0);
    const ImageData merged = read_image(dir / "m.exr");
    const Attribute* m = merged.attribute("chromaticities");
    REQUIRE(m != nullptr);
    CHECK(m->floats == kRec709Chromaticities);
}

TEST_CASE("exr: --half, --compression and --background-depth", "[app][exr]") {
    TempDir dir("exr-options");
    REQUIRE(tiny_render(dir / "full.exr").status == 0);
    REQUIRE(tiny_render(dir / "half.exr",
                        {"--half", "--compression", "none", "--background-depth", "1e10"})
                .status == 0);
    const ImageData full = read_image(dir / "full.exr");
    const ImageData half = read_image(dir / "half.exr");
    REQUIRE(full.channel_names == half.channel_names);
    const int r = full.channel_index("R"), z = full.channel_index("Z"),
              n = full.channel_index("samples");
    REQUIRE(r >= 0);
    REQUIRE(z >= 0);
    const std::size_t nc = std::size_t(full.channels());
    // Half floats keep 11 significant bits: a relative error of at most 2^-11.
    constexpr float kHalfRelError = 1.f / 2048.f;
    int rounded = 0, background = 0;
    for (std::size_t p = 0; p < full.pixels.size() / nc; ++p) {
        const float a = full.pixels[p * nc + std::size_t(r)],
                    b = half.pixels[p * nc + std::size_t(r)];
        CHECK(std::abs(a - b) <= kHalfRelError * std::abs(a) + 1e-7f);
        rounded += a != b;
        // Counts and depths stay 32-bit; the background depth is the finite distance given.
        CHECK(full.pixels[p * nc + std::size_t(n)] == half.pixels[p * nc + std::size_t(n)]);
        const float fz = full.pixels[p * nc + std::size_t(z)],
                    hz = half.pixels[p * nc + std::size_t(z)];
        if (std::isinf(fz)) {
            ++background;
            CHECK(hz == 1e10f);
        } else {
            CHECK(hz == fz);
        }
    }
    CHECK(rounded > 0);    // the colours were stored as halves
    CHECK(background > 0); // the framed camera sees past the open box at the corners
    const Result bad = tiny_render(dir / "x.exr", {"--compression", "zipp"});
    CHECK(bad.status == 2);
    CHECK_THAT(bad.err, Catch::Contains("--compression"));
    const Result bad_depth = tiny_render(dir / "x.exr", {"--background-depth", "-3"});
    CHECK(bad_depth.status == 2);
    CHECK_THAT(bad_depth.err, Catch::Contains("--background-depth"));
}

TEST_CASE("exr: the EXR options survive a checkpoint's canonical arguments", "[app][exr]") {
    const RenderArgs a = parse_render_command_line(
        {"s.dae", "--half", "--compression", "piz", "--background-depth", "1e10"});
    CHECK(a.exr.compression == "piz");
    CHECK(a.exr.background_depth == 1e10f);
    CHECK(a.exr.half_channels.size() == std::size(exr::kHalfChannels));
    const RenderArgs back = parse_render_command_line(canonical_render_args(a));
    CHECK(back.exr.compression == a.exr.compression);
    CHECK(back.exr.background_depth == a.exr.background_depth);
    CHECK(back.exr.half_channels == a.exr.half_channels);
    // Without the flags: 32-bit zip with +inf background.
    const RenderArgs plain = parse_render_command_line({"s.dae"});
    CHECK(plain.exr.half_channels.empty());
    CHECK(plain.exr.compression == "zip");
    CHECK(std::isinf(plain.exr.background_depth));
}
