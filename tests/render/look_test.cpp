// The CS184 look of 8-bit images (--look cs184): its transfer curve against the formula that
// docs/cs184-differences.md states, and the decoding `candela compare` uses to undo it.
#include "../app/app_support.h"
#include "../support/cs184.h"

#include "candela/io/image_io.h"
#include "candela/render/output.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

using namespace candela;
using namespace candela::test;

namespace {

/// The formula of docs/cs184-differences.md ("Output looks"), written out here on its own:
/// byte = floor(255 * min(1, (sqrt(2) v)^(1/2.2))), 0 for v <= 0 and NaN.
int doc_formula(double v) {
    if (!(v > 0.0)) return 0;
    return int(std::floor(255.0 * std::min(1.0, std::pow(std::sqrt(2.0) * v, 1.0 / 2.2))));
}

} // namespace

TEST_CASE("look cs184: the transfer curve is the documented formula", "[look][quick]") {
    std::ifstream in(std::string(CANDELA_SOURCE_DIR) + "/docs/cs184-differences.md");
    REQUIRE(in);
    const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CHECK(doc.find("byte = ⌊255 · min(1, (√2 · v)^(1/2.2))⌋") != std::string::npos);
    // Values by hand from the formula (python: floor(255 * min(1, (sqrt(2) v) ** (1 / 2.2)))).
    const std::pair<float, int> table[] = {{0.f, 0},       {1e-6f, 0},   {0.001f, 12}, {0.01f, 36},
                                           {0.1f, 104},    {0.25f, 158}, {0.5f, 217},  {0.7f, 253},
                                           {0.7072f, 255}, {1.f, 255},   {5.f, 255}};
    for (const auto& [v, byte] : table) {
        INFO("v = " << v);
        CHECK(int(cs184_encode8(v)) == byte);
        CHECK(int(cs184_encode8(v)) == doc_formula(double(v)));
    }
    CHECK(cs184_encode8(-1.f) == 0);
    CHECK(cs184_encode8(std::numeric_limits<float>::quiet_NaN()) == 0);
    CHECK(cs184_encode8(std::numeric_limits<float>::infinity()) == 255);
    // A sweep of values: the curve and the formula agree everywhere.
    for (int i = 0; i <= 2000; ++i) {
        const float v = float(i) / 2000.f;
        INFO("v = " << v);
        CHECK(int(cs184_encode8(v)) == doc_formula(double(v)));
    }
}

TEST_CASE("look cs184: each byte decodes to a value inside its interval", "[look][quick]") {
    for (int b = 0; b < 255; ++b) {
        const double v = cs184_decode8(b);
        INFO("byte " << b);
        CHECK(int(cs184_encode8(float(v))) == b);
        CHECK(int(to_srgb8(float(srgb_decode8(b)), 1.f)) == b);
    }
}

TEST_CASE("look cs184: film previews use the course's curve", "[look][quick]") {
    Film film(2, 1, AovSet::parse("none"), false);
    FilmSample s;
    s.L = Rgb(0.1f, 0.25f, 2.f);
    film.add(0, 0, s);
    s.L = Rgb(0.f, 0.01f, 0.5f);
    film.add(1, 0, s);
    const std::vector<unsigned char> px = film_preview(film, 3.f, Tonemap::Filmic, Look::Cs184);
    // Exposure and tone map do not apply to the course's look.
    const std::vector<int> want = {104, 158, 255, 0, 36, 217};
    REQUIRE(px.size() == want.size());
    for (std::size_t i = 0; i < px.size(); ++i)
        CHECK(int(px[i]) == want[i]);
}

TEST_CASE("look cs184: render --look cs184 writes the EXR's values through the curve",
          "[look][app]") {
    TempDir dir("look");
    const Result r = run_candela({"render", project_scene("cornell-box.dae"), "-r", "16", "12",
                                  "-s", "4", "--adaptive", "none", "--look", "cs184", "--preview",
                                  "-f", dir / "x.exr", "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const ImageData exr = read_image(dir / "x.exr"), png = read_image(dir / "x.png");
    REQUIRE(png.width == exr.width);
    REQUIRE(png.height == exr.height);
    int clipped = 0;
    for (int y = 0; y < exr.height; ++y)
        for (int x = 0; x < exr.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const int byte = int(std::lround(png.at(x, y, c) * 255.f));
                CHECK(byte == int(cs184_encode8(exr.at(x, y,
                                                       exr.channel_index(c == 0   ? "R"
                                                                         : c == 1 ? "G"
                                                                                  : "B")))));
                clipped += byte == 255;
            }
    CHECK(clipped > 0); // the light panel is white in the course's look
    // The course's look sets exposure and curve: --exposure and --tonemap are refused with it.
    const Result both = run_candela({"render", project_scene("cornell-box.dae"), "--look", "cs184",
                                     "--exposure", "1", "-f", dir / "y.png"});
    CHECK(both.status == int(ErrorKind::Usage));
    CHECK(both.err.find("--look cs184") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "y.png"));
}
