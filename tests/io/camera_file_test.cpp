// Camera settings files whose camera-to-world matrix is not a rotation are refused with the
// file and line, exit status 3, before the scene is loaded.
#include "../app/app_support.h"
#include "../support/cs184.h"

#include "candela/io/camera_file.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <fstream>

using namespace candela;
using namespace candela::test;

namespace {

/// A camera file with the given camera-to-world line (line 4).
void write_camera(const std::string& path, const std::string& c2w) {
    std::ofstream(path) << "49.1 37.8 1.333 0.1 100\n"
                           "0 0.75 4.8 0 0.75 0\n"
                           "1.5708 0 4.8 0.1 20\n"
                        << c2w
                        << "\n"
                           "800 600 875\n"
                           "4.2 0\n";
}

} // namespace

TEST_CASE("camera files: the camera-to-world matrix must be a rotation", "[cli][quick]") {
    TempDir dir("camfile");
    const std::string path = dir / "cam.txt";
    write_camera(path, "0.999999 0 0 0 1 0 0 0 1.000001"); // rounding of six digits: accepted
    CHECK_NOTHROW(read_camera_file(path));
    const char* bad[] = {
        "0 0 0 0 0 0 0 0 0",          // all zero: renders black
        "2 0 0 0 1 0 0 0 1",          // X axis of length 2
        "1 0.3 0 0 0.953939 0 0 0 1", // unit columns, X and Y not perpendicular
    };
    for (const char* c2w : bad) {
        INFO(c2w);
        write_camera(path, c2w);
        try {
            read_camera_file(path);
            FAIL("expected an error");
        } catch (const Error& e) {
            CHECK(e.kind() == ErrorKind::Scene);
            CHECK_THAT(e.what(), Catch::StartsWith(path + ":4: "));
        }
    }
}

TEST_CASE("camera files: render refuses an all-zero matrix with status 3", "[app][quick]") {
    TempDir dir("camfile-cli");
    const std::string path = dir / "zero.txt";
    write_camera(path, "0 0 0\n0 0 0\n0 0 0");
    const Result r = run_candela({"render", project_scene("cornell-box.dae"), "-c", path, "-f",
                                  dir / "out.exr", "-r", "16", "12", "-s", "1"});
    CHECK(r.status == 3);
    CHECK_THAT(r.err, Catch::StartsWith("candela: error: " + path + ":4: the camera"));
    CHECK_FALSE(std::filesystem::exists(dir.path / "out.exr"));
}
