// Direct checks of the guards added for the stress suite: each feeds the one input that used to
// reach a division by zero, an overflow or a self-occluding shadow ray.
#include "candela/accel/accel.h"
#include "candela/bsdf/bsdf.h"
#include "candela/light/light_sample.h"
#include "candela/render/integrator.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>

using namespace candela;

namespace {

/// A scene of one light and no geometry, assembled by hand rather than through SceneEditor: the
/// guards are checked on records alone, a Sphere light included.
Scene one_light_scene(const Light& light) {
    Scene scene;
    scene.materials.push_back(Material());
    scene.lights.push_back(light);
    scene.finalize();
    return scene;
}

} // namespace

TEST_CASE("guards: point light far away or at the reference point gives no sample",
          "[numerics][quick]") {
    Light point;
    point.kind = LightKind::Point;
    point.L = Rgb(10.f);
    point.p = Vec3(0.f, 1.f, 0.f);
    const Scene scene = one_light_scene(point);
    // 1e20 away the squared distance overflows float.
    CHECK_FALSE(sample_li(scene, point, Vec3(1e20f, 0.f, 0.f), Vec2(0.5f, 0.5f)).has_value());
    CHECK_FALSE(sample_li(scene, point, point.p, Vec2(0.5f, 0.5f)).has_value());
    // Within 1e-20 the inverse-square factor overflows: no sample rather than an infinite one.
    CHECK_FALSE(
        sample_li(scene, point, point.p + Vec3(1e-20f, 0.f, 0.f), Vec2(0.5f, 0.5f)).has_value());
    auto ls = sample_li(scene, point, Vec3(0.f), Vec2(0.5f, 0.5f));
    REQUIRE(ls.has_value());
    CHECK(ls->L.x == Approx(10.f));
    CHECK(ls->p_error == Vec3(0.f)); // not a point on a surface
}

TEST_CASE("guards: pdf_li with a zero normal or a point-like sphere is 0", "[numerics][quick]") {
    Light rect;
    rect.kind = LightKind::Area;
    rect.L = Rgb(1.f);
    rect.p = Vec3(0.f, 2.f, 0.f);
    rect.n = Vec3(0.f, -1.f, 0.f);
    rect.dx = Vec3(1.f, 0.f, 0.f);
    rect.dy = Vec3(0.f, 0.f, -1.f);
    const Scene scene = one_light_scene(rect);
    const Vec3 ref(0.f), wi(0.f, 1.f, 0.f);
    CHECK(pdf_li(scene, rect, ref, wi, rect.p, Vec3(0.f), 0u) == 0.f);
    CHECK(pdf_li(scene, rect, ref, wi, rect.p, rect.n, 0u) > 0.f);

    Light sphere;
    sphere.kind = LightKind::Sphere;
    sphere.L = Rgb(1.f);
    sphere.p = Vec3(0.f, 2.f, 0.f);
    sphere.radius = 0.f;
    CHECK_FALSE(sample_li(scene, sphere, ref, Vec2(0.3f, 0.7f)).has_value());
    CHECK_FALSE(sample_li(scene, sphere, sphere.p, Vec2(0.3f, 0.7f)).has_value());
    CHECK(pdf_li(scene, sphere, ref, wi, sphere.p, Vec3(0.f, -1.f, 0.f), 0u) == 0.f);
}

TEST_CASE("guards: area light samples carry an error bound for their shadow rays",
          "[numerics][quick]") {
    Light sphere;
    sphere.kind = LightKind::Sphere;
    sphere.L = Rgb(1.f);
    sphere.p = Vec3(3.f, 0.f, 0.f);
    sphere.radius = 1.f;
    const Scene scene = one_light_scene(sphere);
    for (const Vec3& ref : {Vec3(0.f), Vec3(3.f, 0.5f, 0.f)}) { // outside and inside
        auto ls = sample_li(scene, sphere, ref, Vec2(0.25f, 0.6f));
        REQUIRE(ls.has_value());
        // Positive on every axis the point has a component on, and tiny (a few ulps of |p|).
        CHECK(ls->p_error.x > 0.f);
        CHECK(max_component(ls->p_error) < 1e-5f * (1.f + max_component(vabs(ls->p_light))));
    }
}

TEST_CASE("guards: glass with a non-positive or infinite index absorbs", "[numerics][quick]") {
    Material glass;
    glass.kind = BsdfKind::Glass;
    for (float ior : {0.f, -1.5f, INFINITY}) {
        glass.ior = ior;
        CHECK_FALSE(bsdf_sample(glass, normalize(Vec3(0.3f, 0.f, 1.f)), Vec2(0.5f, 0.5f), 0.99f)
                        .has_value());
    }
    glass.ior = 1.5f;
    CHECK(bsdf_sample(glass, normalize(Vec3(0.3f, 0.f, 1.f)), Vec2(0.5f, 0.5f), 0.99f).has_value());
}

TEST_CASE("guards: the integrator rejects settings it would divide by", "[numerics][quick]") {
    Scene scene;
    scene.materials.push_back(Material());
    scene.spheres.push_back(Sphere());
    scene.finalize();
    AccelOptions opt;
    opt.kind = AccelKind::Builtin;
    std::unique_ptr<Accel> accel = make_accel(scene, opt);
    RenderSettings s;
    s.width = s.height = 4;
    s.light_samples = 0;
    CHECK_THROWS_AS(Integrator(scene, *accel, s), Error);
    s.light_samples = 1;
    s.width = 0;
    CHECK_THROWS_AS(Integrator(scene, *accel, s), Error);
    s.width = 4;
    scene.camera.lens_radius = 0.1f;
    scene.camera.focal_distance = 0.f;
    CHECK_THROWS_AS(Integrator(scene, *accel, s), Error);
    scene.camera.focal_distance = 2.f;
    CHECK_NOTHROW(Integrator(scene, *accel, s));
}
