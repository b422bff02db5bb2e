// The in-process OpenEXR reader gives the pixels and windows the image module gives.
#include "candela/io/envmap_file.h"
#include "candela/io/exr_pixels.h"
#include "candela/io/image_io.h"
#include "candela/util/error.h"

#include "../support/temp_dir.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

using namespace candela;
using candela::test::TempDir;
namespace fs = std::filesystem;

namespace {

/// A 5x3 image with values spanning many octaves (a sun 1e6x the sky, tiny and negative values)
/// placed at (2, 1) in a 9x6 display window.
ImageData sample_image() {
    ImageData img;
    img.width = 5;
    img.height = 3;
    img.x = 2;
    img.y = 1;
    img.full_width = 9;
    img.full_height = 6;
    img.channel_names = {"R", "G", "B", "extra"};
    for (int i = 0; i < 5 * 3 * 4; ++i)
        img.pixels.push_back(std::ldexp(1.f + 0.123f * float(i % 7), (i * 5) % 41 - 20) *
                             (i % 11 == 0 ? -1.f : 1.f));
    img.pixels[7 * 4 + 1] = 1e6f;
    return img;
}

} // namespace

TEST_CASE("OpenEXR's reader and the image module's agree on pixels and windows", "[image][quick]") {
    const TempDir tmp("exr-pixels");
    const fs::path dir = tmp.path;
    const ImageData img = sample_image();
    for (const bool half : {false, true}) {
        const std::string path = (dir / (half ? "half.exr" : "float.exr")).string();
        ExrOptions opt;
        if (half) opt.half_channels = {"G", "extra"};
        write_exr(path, img, opt);
        const ImageData direct = read_exr_pixels(path);
        const ImageData module = read_image(path);
        INFO((half ? "half" : "float") << " channels");
        CHECK(direct.width == module.width);
        CHECK(direct.height == module.height);
        CHECK(direct.x == module.x);
        CHECK(direct.y == module.y);
        CHECK(direct.display_width() == module.display_width());
        CHECK(direct.display_height() == module.display_height());
        CHECK(direct.attributes.empty());
        REQUIRE(direct.channels() == module.channels());
        for (const std::string& name : img.channel_names) {
            const int a = direct.channel_index(name), b = module.channel_index(name);
            const int c = img.channel_index(name);
            REQUIRE(a >= 0);
            REQUIRE(b >= 0);
            for (int y = 0; y < img.height; ++y)
                for (int x = 0; x < img.width; ++x) {
                    // Bit for bit: both convert the stored value (float, or half widened to
                    // float exactly) the same way.
                    CHECK(direct.at(x, y, a) == module.at(x, y, b));
                    if (!(half && (name == "G" || name == "extra")))
                        CHECK(direct.at(x, y, a) == img.at(x, y, c));
                }
        }
    }
}

TEST_CASE("an environment map read through OpenEXR equals one read through the image module",
          "[image][envmap][quick]") {
    const TempDir tmp("exr-envmap");
    const fs::path dir = tmp.path;
    ImageData img = sample_image();
    img.x = img.y = 0;
    img.full_width = img.full_height = 0;
    for (float& v : img.pixels)
        v = std::abs(v);
    const std::string exr = (dir / "sky.exr").string(), upper = (dir / "SKY.EXR").string();
    write_exr(exr, img);
    fs::copy_file(exr, upper);
    // The same file under an extension the OpenEXR path does not take goes through the module.
    const std::string other = (dir / "sky.openexr").string();
    fs::copy_file(exr, other);
    CHECK(is_exr_path(exr));
    CHECK(is_exr_path(upper));
    CHECK_FALSE(is_exr_path(other));
    CHECK_FALSE(is_exr_path((dir / "a.exr" / "b").string()));
    const auto a = load_envmap(exr), b = load_envmap(upper), c = load_envmap(other);
    REQUIRE(a->width() == c->width());
    REQUIRE(a->height() == c->height());
    for (int y = 0; y < a->height(); ++y)
        for (int x = 0; x < a->width(); ++x) {
            CHECK(a->texel(x, y).x == c->texel(x, y).x);
            CHECK(a->texel(x, y).y == c->texel(x, y).y);
            CHECK(a->texel(x, y).z == c->texel(x, y).z);
            CHECK(b->texel(x, y).y == c->texel(x, y).y);
        }
}

TEST_CASE("the OpenEXR reader names the file it cannot read", "[image][quick]") {
    const TempDir tmp("exr-bad");
    const fs::path dir = tmp.path;
    const std::string missing = (dir / "none.exr").string();
    const std::string text = (dir / "text.exr").string();
    std::ofstream(text) << "not an image\n";
    for (const std::string& path : {missing, text}) {
        try {
            read_exr_pixels(path);
            FAIL("read_exr_pixels should throw for " << path);
        } catch (const Error& e) {
            CHECK(e.kind() == ErrorKind::Io);
            REQUIRE(e.where());
            CHECK(e.where()->file == path);
            CHECK(e.message().rfind("cannot read image: ", 0) == 0);
        }
    }
}

TEST_CASE("an EXR map's header is read without the image module, as the module reads it",
          "[image][envmap][quick]") {
    const TempDir tmp("exr-header");
    const ImageData img = sample_image();
    const std::string path = tmp / "map.exr";
    write_exr(path, img);
    const ImageHeader direct = read_envmap_header(path), module = read_image_header(path);
    CHECK(direct.width == 5);
    CHECK(direct.height == 3);
    CHECK(direct.width == module.width);
    CHECK(direct.height == module.height);
    CHECK(direct.channels == module.channels);
    for (const std::string& name : img.channel_names)
        CHECK(std::count(direct.channel_names.begin(), direct.channel_names.end(), name) == 1);
}
