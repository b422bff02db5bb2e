// What candela's 8-bit images say about themselves (the software, the command, the look their
// bytes were encoded with, in PNG text chunks), and `compare` decoding them by it: by the look
// recorded, or with a warning when an image records none.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"
#include "candela/render/exr_layout.h"
#include "candela/render/setting_table.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>

using namespace candela;
using namespace candela::test;

namespace {

const std::string kBox = project_scene("cornell-spheres.dae");

/// A PNG decoded by its own curve differs from its EXR by 8-bit quantisation alone (relMSE
/// below 1e-4, docs/convergence.md); decoded by the other look's curve it is off by tens of
/// percent in most pixels (relMSE above 1e-2).
constexpr double kWrongCurveFactor = 100.0;

/// A small render of the Cornell box with `extra` options.
void render(const std::vector<std::string>& extra) {
    const Result r = run_candela(
        cat({"render", kBox, "-r", "32", "24", "-s", "4", "--adaptive", "none", "-m", "2", "-q"},
            extra));
    INFO(r.err);
    REQUIRE(r.status == 0);
}

/// "relMSE X" of compare's output.
double rel_mse_of(const std::string& out) {
    const std::size_t at = out.find("relMSE ");
    REQUIRE(at != std::string::npos);
    return std::strtod(out.c_str() + at + 7, nullptr);
}

/// The line of compare's output that says how `what` ("image" or "reference") was decoded.
std::string decoding_line(const std::string& out, const std::string& what) {
    for (const std::string& line : lines_of(out))
        if (line.rfind("  " + what + " ", 0) == 0) return line;
    FAIL("no '" << what << "' line in: " << out);
    return "";
}

} // namespace

TEST_CASE("8-bit images carry the software, the command, the look and the spp in PNG text chunks",
          "[app][metadata]") {
    TempDir dir("png-meta");
    render({"-f", dir / "mine.png"});
    const ImageData png = read_image(dir / "mine.png");
    INFO("attributes: " << [&] {
        std::string s;
        for (const Attribute& a : png.attributes)
            s += a.name + "=" + a.str() + "; ";
        return s;
    }());
    CHECK_THAT(png.meta(exr::kSoftware),
               Catch::StartsWith("candela 0.1.0 (") && Catch::EndsWith(")"));
    CHECK_THAT(png.meta(exr::kCommandLine),
               Catch::StartsWith("candela render ") && Catch::Contains("mine.png"));
    CHECK(png.meta(exr::kLook) == "candela");
    CHECK(png.meta(exr::kExposure) == "0");
    CHECK(png.meta(exr::kTonemap) == "clamp");
    CHECK(png.meta(setting_key(Setting::Spp)) == "4");
    CHECK(png.meta(setting_key(Setting::Adaptive)) == "none");

    // The course's look, as a preview beside an EXR; the EXR names the same software.
    render({"--look", "cs184", "--preview", "-f", dir / "course.exr"});
    const ImageData course = read_image(dir / "course.png");
    CHECK(course.meta(exr::kLook) == "cs184");
    CHECK(course.meta(exr::kExposure).empty()); // the course's look has no exposure to set
    const ImageData exr = read_image(dir / "course.exr");
    CHECK(exr.meta(exr::kSoftware) == course.meta(exr::kSoftware));
    CHECK(exr.meta(exr::kCommandLine) == course.meta(exr::kCommandLine));

    // The sample-rate image says what made it, and no look: its colours are not radiance.
    const Result adaptive = run_candela({"render", kBox, "-r", "32", "24", "-s", "4", "-m", "2",
                                         "-q", "-a", "2", "0.5", "-f", dir / "adaptive.png"});
    REQUIRE(adaptive.status == 0);
    const ImageData rate = read_image(dir / "adaptive_rate.png");
    CHECK(rate.meta(exr::kSoftware) == png.meta(exr::kSoftware));
    CHECK_THAT(rate.meta(exr::kCommandLine), Catch::Contains("adaptive.png"));
    CHECK(rate.meta(exr::kLook).empty());
    CHECK(rate.meta(setting_key(Setting::Spp)).empty());
    CHECK(read_image(dir / "adaptive.png").meta(setting_key(Setting::Adaptive)) == "cs184");

    // compare's error map names its command.
    const Result map = run_candela(
        {"compare", dir / "mine.png", dir / "mine.png", "--error-map", dir / "map.png", "-q"});
    REQUIRE(map.status == 0);
    CHECK_THAT(read_image(dir / "map.png").meta(exr::kCommandLine),
               Catch::StartsWith("candela compare "));
}

TEST_CASE("compare decodes candela's own PNG by the look it records, without a flag",
          "[app][metadata][compare]") {
    TempDir dir("png-look");
    // The same film as an EXR and, beside it, as a PNG in candela's default look.
    render({"--preview", "-f", dir / "x.exr"});
    const Result r = run_candela({"compare", dir / "x.png", dir / "x.exr"});
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    CHECK_THAT(decoding_line(r.out, "image"), Catch::Contains("inverse sRGB curve") &&
                                                  Catch::Contains("the look the file records"));
    CHECK(r.err.find("warning") == std::string::npos);
    // Decoded by its own curve the PNG is the EXR up to 8-bit quantisation; through the
    // course's curve (the look assumed before images recorded theirs) it is far off.
    const Result course = run_candela({"compare", dir / "x.png", dir / "x.exr", "--look", "cs184"});
    REQUIRE(course.status == 0);
    CHECK(rel_mse_of(r.out) * kWrongCurveFactor < rel_mse_of(course.out));
    // --look names another look than the file's: it wins, with a warning saying so.
    CHECK_THAT(course.err, Catch::Contains("x.png was written in look candela; decoded as "
                                           "--look cs184"));
}

TEST_CASE("compare warns once which look it assumed for 8-bit images that record none",
          "[app][metadata][compare]") {
    TempDir dir("png-nolook");
    render({"--look", "cs184", "--preview", "-f", dir / "x.exr"});
    // The same bytes without candela's text chunks, as another program would write them.
    const ImageData png = read_image(dir / "x.png");
    std::vector<unsigned char> bytes(png.pixels.size());
    for (std::size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<unsigned char>(std::lround(png.pixels[i] * 255.f));
    write_png(dir / "plain.png", png.width, png.height, bytes);
    write_png(dir / "plain2.png", png.width, png.height, bytes);
    REQUIRE(read_image(dir / "plain.png").meta(exr::kLook).empty());

    const Result r = run_candela({"compare", dir / "plain.png", dir / "plain2.png"});
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    const std::vector<std::string> lines = lines_of(r.err);
    REQUIRE(lines.size() == 1); // one warning for both images
    CHECK_THAT(lines[0], Catch::StartsWith("compare: warning: ") &&
                             Catch::Contains("plain.png and ") &&
                             Catch::Contains("plain2.png have no record of the look") &&
                             Catch::Contains("decoded in look cs184") &&
                             Catch::Contains("give --look candela"));
    CHECK_THAT(decoding_line(r.out, "image"), Catch::Contains("the look assumed"));
    // The same image with its chunks: no warning; --look given: none either.
    const Result own = run_candela({"compare", dir / "x.png", dir / "x.exr"});
    CHECK(own.status == 0);
    CHECK(own.err.empty());
    const Result named =
        run_candela({"compare", dir / "plain.png", dir / "x.exr", "--look", "cs184"});
    CHECK(named.status == 0);
    CHECK(named.err.empty());
}
