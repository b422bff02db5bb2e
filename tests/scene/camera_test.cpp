// One camera projection: the renderer's camera rays and check's come from CameraProjection.
#include "../support/cameras.h"
#include "candela/diagnostics/check.h"
#include "candela/scene/camera.h"
#include "candela/scene/procedural.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace candela;

namespace {

/// Directions of a pixel-centre ray recomputed by hand: float rounding of tan and normalize.
constexpr float kDirectionTol = 1e-5f;
/// Two float rays meeting at distance ~5: a few ulps of the focal distance.
constexpr float kFocusTol = 1e-5f;

} // namespace

TEST_CASE("camera projection: row 0 at the top, the horizontal field of view spans the width",
          "[scene][camera][quick]") {
    const Camera cam = test::sideways_camera();
    const int W = 200, H = 100;
    const CameraProjection projection(cam, W, H);
    const Vec2 centre(0.5f, 0.5f);

    // The image centre looks straight ahead.
    const Ray mid = projection.ray(0.5f * W, 0.5f * H, centre);
    CHECK(mid.o == cam.pos);
    CHECK(dot(mid.d, -cam.z) == Approx(1.f).margin(kDirectionTol));
    CHECK(mid.tmin == cam.znear);
    CHECK(mid.tmax == cam.zfar);

    // Top-left corner: left (-x) and up (+y), at half the field of view horizontally.
    const Ray tl = projection.ray(0.f, 0.f, centre);
    const float tan_h = std::tan(deg_to_rad(30.f)), tan_v = tan_h * H / W;
    const Vec3 expected = normalize(cam.x * -tan_h + cam.y * tan_v - cam.z);
    CHECK(tl.d.x == Approx(expected.x).margin(kDirectionTol));
    CHECK(tl.d.y == Approx(expected.y).margin(kDirectionTol));
    CHECK(tl.d.z == Approx(expected.z).margin(kDirectionTol));
    CHECK(dot(tl.d, cam.y) > 0.f);
    CHECK(dot(tl.d, cam.x) < 0.f);
}

TEST_CASE("camera projection: batch pinhole directions are the single rays' directions",
          "[camera][quick]") {
    // An oblique camera, so that every basis vector contributes to every coordinate.
    Camera cam = test::sideways_camera();
    cam.x = normalize(Vec3(0.3f, -0.2f, -0.9f));
    cam.z = normalize(cross(cam.x, Vec3(0.1f, 1.f, 0.2f)));
    cam.y = cross(cam.z, cam.x);
    const CameraProjection proj(cam, 173, 91);
    // 1003 film positions: not a multiple of any vector width, so the loop's tail runs too.
    std::vector<float> fx, fy;
    for (int i = 0; i < 1003; ++i) {
        fx.push_back(173.f * float((i * 37) % 1003) / 1003.f);
        fy.push_back(91.f * float((i * 101) % 1003) / 1003.f);
    }
    std::vector<float> dx(fx.size()), dy(fx.size()), dz(fx.size());
    proj.pinhole_directions(fx.size(), fx.data(), fy.data(), dx.data(), dy.data(), dz.data());
    for (std::size_t i = 0; i < fx.size(); ++i) {
        const Ray r = proj.ray(fx[i], fy[i], Vec2(0.5f, 0.5f));
        REQUIRE(dx[i] == r.d.x);
        REQUIRE(dy[i] == r.d.y);
        REQUIRE(dz[i] == r.d.z);
        const Ray b = proj.pinhole_ray(Vec3(dx[i], dy[i], dz[i]));
        REQUIRE(b.o == r.o);
        REQUIRE(b.tmin == r.tmin);
        REQUIRE(b.tmax == r.tmax);
    }
}

TEST_CASE("camera projection: a thin lens focuses the pixel's rays on one point",
          "[scene][camera][quick]") {
    Camera cam = test::sideways_camera();
    cam.lens_radius = 0.2f;
    cam.focal_distance = 5.f;
    const CameraProjection projection(cam, 64, 48);
    const Ray a = projection.ray(10.5f, 7.5f, Vec2(0.5f, 0.5f)); // lens centre
    const Ray b = projection.ray(10.5f, 7.5f, Vec2(0.9f, 0.2f));
    CHECK(a.o == cam.pos);
    CHECK_FALSE(b.o == cam.pos);
    // Both start on the lens plane and pass through the point of the focal plane (at depth
    // focal_distance along -z) that the pixel sees.
    const float ta = cam.focal_distance / dot(a.d, -cam.z);
    const float tb = cam.focal_distance / dot(b.d, -cam.z);
    const Vec3 pa = a.o + a.d * ta, pb = b.o + b.d * tb;
    CHECK(length(pa - pb) == Approx(0.f).margin(kFocusTol * cam.focal_distance));
}

TEST_CASE("check's camera rays are the renderer's rays through the pixel centres",
          "[check][camera][quick]") {
    const Scene scene = make_procedural_scene("sphere:200");
    const int W = 16, H = 12;
    const std::vector<Ray> rays = make_camera_rays(scene, W, H);
    REQUIRE(rays.size() == std::size_t(W * H));
    const CameraProjection projection(scene.camera, W, H);
    for (int py = 0; py < H; ++py)
        for (int px = 0; px < W; ++px) {
            const Ray r = projection.ray(float(px) + 0.5f, float(py) + 0.5f, Vec2(0.5f, 0.5f));
            const Ray& c = rays[std::size_t(py * W + px)];
            CHECK(c.o == r.o);
            CHECK(c.d == r.d);
            CHECK(c.tmin == r.tmin);
            CHECK(c.tmax == r.tmax);
        }
    // Row 0 is the top of the image.
    CHECK(dot(rays.front().d, scene.camera.y) > dot(rays.back().d, scene.camera.y));
}
