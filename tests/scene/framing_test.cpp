// The camera's framing (--framing: candela's field of view spanning every -r, or the course's
// crop of the 800x600 view, spec §3.2) and the look-from / look-at / field-of-view overrides
// (spec §11.1), on the camera alone.
#include "../support/cameras.h"
#include "../support/cs184.h"
#include "candela/io/collada.h"
#include "candela/math/constants.h"
#include "candela/scene/builder.h"
#include "candela/scene/camera.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace candela;

namespace {

/// Two float unit directions computed along different paths (a field of view through tan and
/// atan and back, film positions scaled by another width): a few float rounding units.
constexpr float kDirectionTol = 2e-6f;
/// The spec's screenDist table (§3.2) gives its angles to 3 decimals.
constexpr double kTableTol = 5e-4;
/// xfov of the course's CB and bunny cameras (spec §3.2).
constexpr float kCourseXfov = 49.13434f;

/// The camera of the course's CB scenes: at (0, 0.75, 4.8023), looking along -z (spec §3.1).
Camera course_camera() {
    Camera c;
    c.pos = Vec3(0.f, 0.75f, 4.8023f);
    c.target = Vec3(0.f, 0.75f, 0.f);
    c.hfov_deg = kCourseXfov;
    return c;
}

Camera framed(Camera c, Framing framing, int width) {
    frame_camera(c, framing, width);
    return c;
}

void check_direction(const Vec3& got, const Vec3& want) {
    CHECK(got.x == Approx(want.x).margin(kDirectionTol));
    CHECK(got.y == Approx(want.y).margin(kDirectionTol));
    CHECK(got.z == Approx(want.z).margin(kDirectionTol));
}

double hfov_at(Framing framing, int width) {
    return double(framed(course_camera(), framing, width).hfov_deg);
}

} // namespace

TEST_CASE("framing cs184: a 480x360 image is the centre crop of the 800x600 view, ray for ray",
          "[scene][camera][framing][quick]") {
    const Camera camera = test::sideways_camera();
    const CameraProjection full(framed(camera, Framing::Cs184, 800), 800, 600);
    const CameraProjection crop(framed(camera, Framing::Cs184, 480), 480, 360);
    // Pixel (x, y) of the crop is pixel (x + 160, y + 120) of the full view: every pixel's
    // centre, and its corners (a sample anywhere in the pixel).
    for (int y = 0; y < 360; y += 7)
        for (int x = 0; x < 480; x += 7)
            for (const float d : {0.f, 0.5f, 1.f}) {
                const float fx = float(x) + d, fy = float(y) + d;
                INFO("pixel " << x << " " << y << " + " << d);
                check_direction(crop.pinhole_direction(fx, fy),
                                full.pinhole_direction(fx + 160.f, fy + 120.f));
            }
    // The last row and column too.
    check_direction(crop.pinhole_direction(480.f, 360.f), full.pinhole_direction(640.f, 480.f));
    // candela's framing shows the whole view at any size instead: the crop's corner is the
    // full view's corner.
    const CameraProjection whole(framed(camera, Framing::Candela, 480), 480, 360);
    check_direction(whole.pinhole_direction(0.f, 0.f),
                    CameraProjection(camera, 800, 600).pinhole_direction(0.f, 0.f));
}

TEST_CASE("framing cs184: the field of view at each size is the spec's screenDist table",
          "[scene][camera][framing][quick]") {
    // spec §3.2: screenDist 875 px for the CB cameras; hFov = 2 atan(W / (2 screenDist)).
    CHECK(hfov_at(Framing::Cs184, 800) == Approx(49.134).margin(kTableTol));
    CHECK(hfov_at(Framing::Cs184, 480) == Approx(30.676).margin(kTableTol));
    CHECK(hfov_at(Framing::Cs184, 640) == Approx(40.176).margin(kTableTol));
    CHECK(hfov_at(Framing::Cs184, 1024) == Approx(60.667).margin(kTableTol));
    // The vertical ones follow the aspect (camera.h): 23.249 at 480x360.
    const float tan_v = std::tan(deg_to_rad(0.5f * float(hfov_at(Framing::Cs184, 480)))) * 0.75f;
    CHECK(rad_to_deg(2.0 * std::atan(double(tan_v))) == Approx(23.249).margin(kTableTol));
    // candela's framing keeps the file's at every width.
    CHECK(hfov_at(Framing::Candela, 480) == double(kCourseXfov));
}

TEST_CASE("framing cs184: the file camera's field of view is the course's 800x600 window's",
          "[scene][camera][framing][quick]") {
    const double window = double(kCs184WindowWidth) / double(kCs184WindowHeight);
    DescCamera wide; // xfov with a 16:9 aspect: wider than 4:3, the horizontal one is kept
    wide.xfov = kCourseXfov;
    wide.aspect_ratio = 16.f / 9.f;
    CHECK(wide.course_hfov_deg(window) == kCourseXfov);
    CHECK(wide.hfov_deg() == kCourseXfov);
    DescCamera square; // xfov and yfov both 40: narrower than 4:3, the course widens it
    square.xfov = 40.f;
    square.yfov = 40.f;
    const double widened = rad_to_deg(2.0 * std::atan(std::tan(deg_to_rad(20.0)) * 4.0 / 3.0));
    CHECK(square.course_hfov_deg(window) == Approx(widened).epsilon(1e-6));
    CHECK(square.hfov_deg() == 40.f);
    DescCamera tall; // yfov alone: the course's hFov is its default 50 unless yfov needs more
    tall.yfov = 60.f;
    tall.aspect_ratio = 1.f;
    const double from_yfov = rad_to_deg(2.0 * std::atan(std::tan(deg_to_rad(30.0)) * 4.0 / 3.0));
    CHECK(tall.course_hfov_deg(window) == Approx(from_yfov).epsilon(1e-6));
}

TEST_CASE("framing cs184: a course scene's camera is built with the 800x600 window's view",
          "[scene][camera][framing]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Diagnostics diag;
    BuildOptions build;
    build.framing = Framing::Cs184;
    Scene scene = load_scene(test::cs184_scene("CBspheres.dae"), build, diag);
    CHECK(scene.camera.hfov_deg == Approx(49.134).margin(kTableTol));
    frame_camera(scene.camera, Framing::Cs184, 480);
    CHECK(scene.camera.hfov_deg == Approx(30.676).margin(kTableTol));
}

TEST_CASE("camera overrides: look-from, look-at and fov give the hand-computed rays",
          "[scene][camera][framing][quick]") {
    Camera c = test::sideways_camera();
    // From (3, 1, 0) toward (0, 1, 0): looking along -x, so right is -z and up is +y; a 90
    // degree field of view puts the right edge at 45 degrees.
    CameraOverrides o;
    o.from = Vec3(3.f, 1.f, 0.f);
    o.at = Vec3(0.f, 1.f, 0.f);
    o.hfov_deg = 90.f;
    apply_camera_overrides(c, o);
    CHECK(c.pos == Vec3(3.f, 1.f, 0.f));
    CHECK(c.target == Vec3(0.f, 1.f, 0.f));
    const int W = 200, H = 100;
    const CameraProjection p(c, W, H);
    const float s = 1.f / std::sqrt(2.f);
    check_direction(p.pinhole_direction(100.f, 50.f), Vec3(-1.f, 0.f, 0.f)); // centre
    check_direction(p.pinhole_direction(200.f, 50.f), Vec3(-s, 0.f, -s));    // right edge
    check_direction(p.pinhole_direction(0.f, 50.f), Vec3(-s, 0.f, s));       // left edge
    // Top edge: tan(vertical half angle) = tan 45 * H / W = 0.5.
    check_direction(p.pinhole_direction(100.f, 0.f), normalize(Vec3(-1.f, 0.5f, 0.f)));

    // Looking down at 45 degrees from (0, 2, 2) at the origin: right stays +x, and the image's
    // up tilts forward, toward -z.
    Camera d = test::sideways_camera();
    CameraOverrides down;
    down.from = Vec3(0.f, 2.f, 2.f);
    down.at = Vec3(0.f);
    apply_camera_overrides(d, down);
    CHECK(d.hfov_deg == 60.f); // no --fov: the camera's is kept
    const CameraProjection q(d, W, H);
    check_direction(q.pinhole_direction(100.f, 50.f), Vec3(0.f, -s, -s));
    check_direction(d.x, Vec3(1.f, 0.f, 0.f));
    check_direction(d.y, Vec3(0.f, s, -s));

    // Only --look-at: the camera stays where it is and turns.
    Camera e = test::sideways_camera(); // at (1, 2, 3)
    CameraOverrides at_only;
    at_only.at = Vec3(1.f, 2.f, -7.f);
    apply_camera_overrides(e, at_only);
    CHECK(e.pos == Vec3(1.f, 2.f, 3.f));
    check_direction(CameraProjection(e, W, H).pinhole_direction(100.f, 50.f), Vec3(0.f, 0.f, -1.f));
}

TEST_CASE("camera overrides: nonsense is refused, naming the flag",
          "[scene][camera][framing][quick]") {
    const auto refused = [](const CameraOverrides& o, const std::string& needle) {
        Camera c = test::sideways_camera();
        try {
            apply_camera_overrides(c, o);
            FAIL("expected a refusal naming " << needle);
        } catch (const Error& e) {
            CHECK(e.kind() == ErrorKind::Usage);
            CHECK_THAT(e.what(), Catch::Contains(needle));
        }
    };
    for (const float fov : {0.f, 180.f, -10.f, 200.f, std::nanf("")}) {
        CameraOverrides o;
        o.hfov_deg = fov;
        INFO(fov);
        refused(o, "--fov");
    }
    refused({Vec3(1.f, 2.f, 3.f), Vec3(1.f, 2.f, 3.f), std::nullopt},
            "--look-from and --look-at: the eye is at the point it looks at");
    refused({Vec3(0.f, 5.f, 0.f), Vec3(0.f), std::nullopt}, "straight up or down");
    refused({Vec3(0.f, -5.f, 0.f), Vec3(0.f), std::nullopt}, "straight up or down");
    // One point with the camera's other: at (1, 2, 3), looking at (1, 9, 3) is straight up.
    refused({std::nullopt, Vec3(1.f, 9.f, 3.f), std::nullopt}, "--look-at");
}
