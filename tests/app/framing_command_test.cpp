// `render --framing cs184` and the look-from / look-at / fov flags from the command line: the
// projection the EXR records, the refusals, the checkpoint's record, and `compare --scene
// --framing`.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/app/cli.h"
#include "candela/io/image_io.h"
#include "candela/math/constants.h"
#include "candela/render/exr_layout.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

using namespace candela;
using namespace candela::test;

namespace {

const std::string kBox = project_scene("cornell-spheres.dae");

/// Pixel positions projected through two float matrices built from the same camera at two
/// sizes: float rounding of positions a few hundred pixels across.
constexpr double kPixelTol = 2e-3;

/// With the layers in the image's framing the relMSE is the two renders' noise (16 spp each:
/// a few percent per pixel, relMSE ~1e-2); in candela's framing the layers show the whole view
/// where the image shows its middle fifth, so most pixels see another surface (relMSE ~1 and
/// above; 7.9 against 0.008 when measured).
constexpr double kMisregistrationFactor = 10.0;

/// The relative difference a 7-digit aspect_ratio (1.333333 for 4:3) makes to a field of view.
constexpr double kFileAspectRounding = 1e-6;

/// A render of one 4x4 cell of a W x H frame (cheap at any size): enough for its metadata.
ImageData cell_render(const TempDir& dir, const std::string& name, int w, int h,
                      std::vector<std::string> extra = {}) {
    const std::string out = dir / name;
    std::vector<std::string> args = {"render",
                                     kBox,
                                     "-r",
                                     std::to_string(w),
                                     std::to_string(h),
                                     "-p",
                                     "0",
                                     "0",
                                     "4",
                                     "4",
                                     "-s",
                                     "1",
                                     "--adaptive",
                                     "none",
                                     "-q",
                                     "-f",
                                     out};
    args.insert(args.end(), extra.begin(), extra.end());
    const Result r = run_candela(args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    return read_image(out);
}

/// Where the EXR's worldToNDC puts world point p, in pixels of its display window.
std::array<double, 2> pixel_of(const ImageData& img, const Vec3& p) {
    const Attribute* a = img.attribute(exr::kWorldToNdcStd);
    if (!a) a = img.attribute(exr::kWorldToNdc);
    REQUIRE(a != nullptr);
    const std::array<float, 16>& m = a->m;
    double v[4] = {0, 0, 0, 0};
    const double row[4] = {p.x, p.y, p.z, 1.0};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            v[c] += row[r] * double(m[std::size_t(r * 4 + c)]);
    return {v[0] / v[3] * img.display_width(), v[1] / v[3] * img.display_height()};
}

/// World points in front of the Cornell box's camera, spread over the middle of its view.
const std::vector<Vec3> kPoints = {{0.f, 0.f, 0.f},
                                   {0.3f, 0.2f, 0.f},
                                   {-0.4f, -0.3f, 0.2f},
                                   {0.1f, -0.5f, -0.5f},
                                   {-0.2f, 0.4f, 0.5f}};

void check_usage(const std::vector<std::string>& argv, const std::string& needle) {
    INFO(needle);
    try {
        parse_render_command_line(argv);
        FAIL("expected a usage error naming " << needle);
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Usage);
        CHECK_THAT(e.what(), Catch::Contains(needle));
    }
}

/// "relMSE X" of compare's output.
double rel_mse_of(const std::string& out) {
    const std::size_t at = out.find("relMSE ");
    REQUIRE(at != std::string::npos);
    return std::strtod(out.c_str() + at + 7, nullptr);
}

} // namespace

TEST_CASE("render --framing cs184: -r 480 360 projects as the centre crop of 800x600",
          "[app][framing]") {
    TempDir dir("framing");
    const ImageData full = cell_render(dir, "full.exr", 800, 600, {"--framing", "cs184"});
    const ImageData crop = cell_render(dir, "crop.exr", 480, 360, {"--framing", "cs184"});
    const ImageData whole = cell_render(dir, "whole.exr", 480, 360);
    CHECK(crop.meta(exr::kFraming) == "cs184");
    CHECK(whole.meta(exr::kFraming) == "candela");
    for (const Vec3& p : kPoints) {
        const auto f = pixel_of(full, p), c = pixel_of(crop, p), w = pixel_of(whole, p);
        INFO(p.x << " " << p.y << " " << p.z);
        // cs184: pixel (x, y) of the crop is pixel (x + 160, y + 120) of the full view.
        CHECK(c[0] + 160.0 == Approx(f[0]).margin(kPixelTol));
        CHECK(c[1] + 120.0 == Approx(f[1]).margin(kPixelTol));
        // candela: the whole view at 0.6 times the size.
        CHECK(w[0] == Approx(f[0] * 0.6).margin(kPixelTol));
        CHECK(w[1] == Approx(f[1] * 0.6).margin(kPixelTol));
    }
    // The field of view across the image follows: tan(h/2) scales with the width.
    const double tan_full = std::tan(deg_to_rad(0.5 * std::stod(full.meta(exr::kHfovDeg))));
    const double tan_crop = std::tan(deg_to_rad(0.5 * std::stod(crop.meta(exr::kHfovDeg))));
    CHECK(tan_crop == Approx(0.6 * tan_full).epsilon(1e-6));
    // candela's framing keeps the file's xfov at every size; the course's 800-wide view is the
    // same but for the file's aspect_ratio 1.333333, a hair narrower than 4:3, which the course
    // widens (by 2.5e-7 relative).
    CHECK(std::stod(whole.meta(exr::kHfovDeg)) ==
          Approx(std::stod(full.meta(exr::kHfovDeg))).epsilon(kFileAspectRounding));
}

TEST_CASE("render --look-from, --look-at, --fov: the EXR's camera is the one asked for",
          "[app][framing]") {
    TempDir dir("look-from");
    const ImageData img =
        cell_render(dir, "a.exr", 64, 48,
                    {"--look-from", "0", "1", "6", "--look-at", "0", "1", "0", "--fov", "90"});
    CHECK(std::stod(img.meta(exr::kHfovDeg)) == 90.0);
    // The point looked at is the image centre; a point 1 to the right at depth 6 with a 90
    // degree field of view is 1/6 of the half width right of it.
    const auto c = pixel_of(img, Vec3(0.f, 1.f, 0.f));
    CHECK(c[0] == Approx(32.0).margin(kPixelTol));
    CHECK(c[1] == Approx(24.0).margin(kPixelTol));
    const auto r = pixel_of(img, Vec3(1.f, 1.f, 0.f));
    CHECK(r[0] == Approx(32.0 + 32.0 / 6.0).margin(kPixelTol));
    CHECK(r[1] == Approx(24.0).margin(kPixelTol));
}

TEST_CASE("render: bad --framing, --look-from, --look-at and --fov are refused by name",
          "[app][framing][quick]") {
    check_usage({"--fov", "0", "s.dae"}, "--fov");
    check_usage({"--fov", "180", "s.dae"}, "--fov");
    check_usage({"--fov", "-20", "s.dae"}, "--fov");
    check_usage({"--look-from", "1", "2", "3", "--look-at", "1", "2", "3", "s.dae"},
                "--look-from and --look-at");
    check_usage({"--look-from", "0", "5", "0", "--look-at", "0", "0", "0", "s.dae"},
                "straight up or down");
    check_usage({"--look-from", "nan", "0", "0", "s.dae"}, "--look-from");
    check_usage({"--look-at", "1", "2", "s.dae"}, "--look-at");
    check_usage({"--framing", "crop", "s.dae"}, "--framing");
    // From the binary: one line, the usage status, nothing rendered.
    TempDir dir("look-bad");
    check_one_line(run_candela({"render", kBox, "--fov", "180", "-f", dir / "x.exr"}),
                   int(ErrorKind::Usage), "--fov");
    CHECK_FALSE(std::filesystem::exists(dir / "x.exr"));
}

TEST_CASE("render: the framing and the view overrides are in the checkpoint's settings",
          "[app][framing][quick]") {
    const RenderArgs a =
        parse_render_command_line({"--framing", "cs184", "--look-from", "0", "1", "6.5",
                                   "--look-at", "0", "1", "0", "--fov", "35", "s.dae"});
    const std::vector<std::string> c = canonical_render_args(a);
    const RenderArgs b = parse_render_command_line(c);
    CHECK(canonical_render_args(b) == c);
    CHECK(b.build.framing == Framing::Cs184);
    CHECK(b.camera_overrides.from == Vec3(0.f, 1.f, 6.5f));
    CHECK(b.camera_overrides.at == Vec3(0.f, 1.f, 0.f));
    CHECK(b.camera_overrides.hfov_deg == 35.f);
    // A resume with another framing or view is refused, naming the option.
    const auto resuming = [&](std::vector<std::string> v) {
        v.push_back("s.dae");
        RenderArgs r = parse_render_command_line(v);
        r.given.erase("scene");
        return r;
    };
    CHECK_THROWS_WITH(check_resume_matches(resuming({"--framing", "candela"}), b, "c.ckpt"),
                      Catch::Contains("--framing is candela here but cs184"));
    CHECK_THROWS_WITH(check_resume_matches(resuming({"--fov", "40"}), b, "c.ckpt"),
                      Catch::Contains("--fov is 40 here but 35"));
    CHECK_THROWS_WITH(check_resume_matches(resuming({"--look-from", "0", "1", "7"}), b, "c.ckpt"),
                      Catch::Contains("--look-from is 0 1 7 here but 0 1 6.5"));
    CHECK_NOTHROW(check_resume_matches(resuming({"--framing", "cs184"}), b, "c.ckpt"));
}

TEST_CASE("compare --scene --framing cs184 renders the layers in the image's framing",
          "[app][framing][compare]") {
    TempDir dir("framing-compare");
    const std::string image = dir / "crop.exr";
    const Result r = run_candela({"render", kBox, "-r", "160", "120", "--framing", "cs184", "-m",
                                  "2", "-s", "16", "--adaptive", "none", "-q", "-f", image});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const std::vector<std::string> args = {"compare", image, "--scene", kBox, "-m",
                                           "2",       "-s",  "16",      "-q"};
    const Result same = run_candela(cat(args, {"--framing", "cs184"}));
    const Result other = run_candela(args);
    INFO(same.out << other.out << same.err << other.err);
    REQUIRE(same.status == 0);
    REQUIRE(other.status == 0);
    // In the image's framing only the two renders' noise differs; in the other the layers show
    // the whole view where the image shows its middle.
    CHECK(rel_mse_of(same.out) * kMisregistrationFactor < rel_mse_of(other.out));
}

TEST_CASE("merge refuses parts seen by different cameras", "[app][framing][merge]") {
    TempDir dir("framing-merge");
    cell_render(dir, "a.exr", 32, 24);
    cell_render(dir, "b.exr", 32, 24, {"--sample-offset", "1", "--fov", "30"});
    cell_render(dir, "c.exr", 32, 24, {"--sample-offset", "1", "--look-from", "0", "1", "9"});
    cell_render(dir, "d.exr", 32, 24, {"--sample-offset", "1"});
    const Result fov = run_candela({"merge", dir / "a.exr", dir / "b.exr", "-o", dir / "m.exr"});
    CHECK(fov.status == int(ErrorKind::Usage));
    CHECK_THAT(fov.err, Catch::Contains("cannot merge: candela:hfov_deg"));
    const Result pose = run_candela({"merge", dir / "a.exr", dir / "c.exr", "-o", dir / "m.exr"});
    CHECK(pose.status == int(ErrorKind::Usage));
    CHECK_THAT(pose.err, Catch::Contains("cannot merge: worldtocamera", Catch::CaseSensitive::No));
    CHECK_FALSE(std::filesystem::exists(dir / "m.exr"));
    // The same camera merges.
    CHECK(run_candela({"merge", dir / "a.exr", dir / "d.exr", "-o", dir / "m.exr", "-q"}).status ==
          0);
}
