// Every shipped scene renders something with the default command, or candela says why not:
// materials.dae is a closed room whose framed camera (the CS184 placement) stands outside.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <filesystem>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {
constexpr const char* kWarning = "the framed camera is outside the closed room";
} // namespace

TEST_CASE("shipped scenes: non-black by default, or a warning", "[app][scenes]") {
    TempDir dir("shipped");
    int scenes = 0;
    for (const auto& entry : fs::directory_iterator(CANDELA_PROJECT_SCENES)) {
        if (entry.path().extension() != ".dae") continue;
        ++scenes;
        const std::string out = dir / (entry.path().stem().string() + ".exr");
        const Result r = run_candela({"render", entry.path().string(), "-r", "32", "24", "-s", "4",
                                      "--adaptive", "none", "-t", "1", "-f", out});
        INFO(entry.path().filename().string() << "\n" << r.err);
        REQUIRE(r.status == 0);
        const ImageData img = read_image(out);
        double sum = 0.0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                for (int c = 0; c < 3; ++c)
                    sum += img.at(x, y, c);
        const bool warned = r.err.find(kWarning) != std::string::npos;
        CHECK((sum > 0.0 || warned));
        if (entry.path().filename() == "materials.dae") {
            CHECK(warned);
            // Its own camera sees the room, without a warning.
            const Result file = run_candela({"render", entry.path().string(), "-r", "32", "24",
                                             "-s", "4", "--adaptive", "none", "-t", "1", "--camera",
                                             "file", "-f", dir / "file.exr"});
            CHECK(file.status == 0);
            CHECK(file.err.find(kWarning) == std::string::npos);
        } else {
            CHECK_FALSE(warned);
        }
    }
    CHECK(scenes >= 5);
}
