#include "candela/io/image_io.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <unistd.h>

using namespace candela;
namespace fs = std::filesystem;

namespace {
fs::path fresh_dir(const std::string& name) {
    fs::path d =
        fs::temp_directory_path() / ("candela-test-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}
} // namespace

TEST_CASE("EXR round trip keeps channels, values and metadata", "[image][quick]") {
    fs::path dir = fresh_dir("exr");
    ImageData img;
    img.width = 3;
    img.height = 2;
    img.channel_names = {"R", "G", "B", "A", "samples"};
    for (int i = 0; i < 3 * 2 * 5; ++i)
        img.pixels.push_back(0.25f * float(i) - 1.f);
    img.attributes = {{"candela:seed", "42"}};
    std::string path = (dir / "a.exr").string();
    write_exr(path, img);
    ImageData back = read_image(path);
    CHECK(back.width == 3);
    CHECK(back.height == 2);
    CHECK(back.channel_index("samples") >= 0);
    CHECK(back.meta("candela:seed") == "42");
    for (const auto& name : img.channel_names) {
        int c0 = img.channel_index(name), c1 = back.channel_index(name);
        REQUIRE(c1 >= 0);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x)
                CHECK(back.at(x, y, c1) == img.at(x, y, c0));
    }
    // Nothing but the image is left in the directory (no temporary files).
    CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}) == 1);
    fs::remove_all(dir);
}

TEST_CASE("a write into a missing directory fails cleanly and leaves nothing", "[image][quick]") {
    fs::path dir = fresh_dir("missing");
    ImageData img;
    img.width = img.height = 1;
    img.channel_names = {"R", "G", "B"};
    img.pixels = {1, 2, 3};
    std::string path = (dir / "no" / "such" / "a.exr").string();
    try {
        write_exr(path, img);
        FAIL("write_exr should throw");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Io);
        CHECK(std::string(e.what()).find(path) == 0);
    }
    CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}) == 0);
    fs::remove_all(dir);
}

TEST_CASE("sRGB preview quantisation", "[image][quick]") {
    CHECK(to_srgb8(0.f, 1.f) == 0);
    CHECK(to_srgb8(-1.f, 1.f) == 0);
    CHECK(to_srgb8(std::nanf(""), 1.f) == 0);
    CHECK(to_srgb8(1.f, 1.f) == 255);
    CHECK(to_srgb8(100.f, 1.f) == 255);
    CHECK(to_srgb8(0.5f, 2.f) == 255);
    // sRGB(0.18) = 0.4614 -> 118
    CHECK(to_srgb8(0.18f, 1.f) == 118);
}
