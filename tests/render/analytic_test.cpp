// Renders of scenes with closed-form radiance, checked by a z-test whose bound comes from the
// estimator's own variance (render_support.h). Every test runs with Embree and the builtin BVH.
#include "../support/chi2.h"
#include "candela/bsdf/bsdf.h"
#include "render_support.h"

#include <catch2/catch.hpp>

using namespace candela;
using namespace candela::test;

namespace {

RenderSettings small_settings(AccelKind accel, int size, int spp) {
    RenderSettings s;
    s.width = s.height = size;
    s.spp = spp;
    s.threads = 0;
    s.quiet = true;
    s.accel.kind = accel;
    s.aovs = AovSet::parse("variance");
    s.seed = 7;
    return s;
}

AccelKind accel_param() {
    return GENERATE(AccelKind::Embree, AccelKind::Builtin);
}

} // namespace

TEST_CASE("furnace: a glowing diffuse sphere seen from inside has radiance Le/(1-a)",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    const float albedo = GENERATE(0.5f, 0.9f);
    const float Le = 1.f;
    const Scene scene = make_furnace_scene(albedo, Le);

    RenderSettings s = small_settings(accel, 16, 64);
    s.max_depth = 100000; // the hard cap never binds: roulette ends the paths
    Film film = render_film(scene, s);
    Estimate e = film_estimate(film);
    const double expected = Le / (1.0 - albedo);
    INFO("albedo " << albedo << " accel " << accel_kind_name(accel) << ": mean " << e.mean << " +- "
                   << e.std_err << ", expected " << expected);
    REQUIRE(e.std_err > 0.0);
    CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
    // The estimate must be informative: its standard error is a small fraction of the value.
    CHECK(e.std_err < 0.02 * expected);
}

TEST_CASE("diffuse plane under a uniform sky has radiance albedo * L", "[render][stat]") {
    const AccelKind accel = accel_param();
    Scene scene;
    SceneEditor editor(scene);
    Material m;
    m.albedo = Rgb(0.5f, 0.25f, 0.75f);
    add_floor(scene, 1000.f, 0.f, editor.add_material(m));
    Light sky;
    sky.kind = LightKind::Ambient;
    sky.L = Rgb(2.f);
    editor.add_light(sky);
    scene.camera = camera_looking_down(Vec3(0, 1, 0), 60.f);
    editor.finalize();

    for (bool mis : {true, false}) {
        RenderSettings s = small_settings(accel, 8, 64);
        s.max_depth = 4;
        s.mis = mis;
        Film film = render_film(scene, s);
        Estimate e = film_estimate(film);
        const double expected = luminance(m.albedo * sky.L);
        INFO("mis " << mis << ": mean " << e.mean << " +- " << e.std_err << ", expected "
                    << expected);
        REQUIRE(e.std_err > 0.0);
        CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
        CHECK(e.std_err < 0.02 * expected);
    }
}

namespace {
/// Irradiance at the origin (normal +y) from a uniform polygonal luminaire of radiance L:
/// Lambert's formula E = L/2 * sum_i angle_i * dot(n, unit(v_i x v_{i+1})).
double polygon_irradiance(const std::vector<Vec3d>& verts, double L) {
    double sum = 0.0;
    for (std::size_t i = 0; i < verts.size(); ++i) {
        Vec3d a = normalize(verts[i]), b = normalize(verts[(i + 1) % verts.size()]);
        double angle = std::acos(std::max(-1.0, std::min(1.0, dot(a, b))));
        Vec3d c = normalize(cross(a, b));
        sum += angle * c.y;
    }
    return 0.5 * L * std::abs(sum);
}
} // namespace

TEST_CASE("irradiance from a rectangular light on a plane matches the closed form",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    Scene scene;
    SceneEditor editor(scene);
    Material m;
    m.albedo = Rgb(0.5f);
    add_floor(scene, 10.f, 0.f, editor.add_material(m));
    // A 1 x 2 light, 1 unit up, shifted off-centre, facing down.
    const Vec3 c(0.3f, 1.f, -0.2f), dx(1.f, 0.f, 0.f), dy(0.f, 0.f, 2.f);
    const float Le = 5.f;
    add_rect_light(scene, c, dx, dy, Rgb(Le));
    // A camera with a tiny field of view sees only the point below it, the origin.
    scene.camera = camera_looking_down(Vec3(0, 0.5f, 0), 1e-3f);
    editor.finalize();
    std::vector<Vec3d> verts;
    for (const Vec3& v : scene.meshes[1].positions)
        verts.push_back(Vec3d(v));
    verts.resize(4);
    const double E = polygon_irradiance(verts, Le);
    const double expected = 0.5 / double(kPi) * E;

    for (bool hemisphere : {false, true}) {
        RenderSettings s = small_settings(accel, 4, 256);
        s.max_depth = 1;
        s.hemisphere = hemisphere;
        s.integrator = IntegratorKind::Direct;
        s.light_samples = 4;
        Film film = render_film(scene, s);
        Estimate e = film_estimate(film);
        INFO("hemisphere " << hemisphere << ": mean " << e.mean << " +- " << e.std_err
                           << ", expected " << expected);
        REQUIRE(e.std_err > 0.0);
        CHECK(std::abs(e.mean - expected) < kZBound * e.std_err);
        CHECK(e.std_err < 0.03 * expected);
    }
}

// ---- Furnace of every material: an object inside a uniform environment ----------------------
//
// The camera and a sphere of the material under test sit inside a large emissive sphere of
// radiance 1 (a uniform environment; the enclosure only emits). A lossless object (white
// Lambertian, white mirror, white smooth glass, smooth refraction: a ray refracted into a
// sphere meets its far side at the angle it entered, so it never totally reflects) leaves the
// radiance at 1 everywhere. The rough materials lose their single-scattering energy: they are
// compared across estimators (MIS, --no-mis, -H where it sees every lobe) and against the
// bound 1; the rough conductor seen at normal incidence also against its directional albedo
// from quadrature (a convex object sees only the environment, so L is that albedo).

namespace {

/// Radius of the emissive enclosure; the object has radius 0.5 at the origin.
constexpr float kEnclosureRadius = 20.f;
/// Float accumulation of 16384 unit-weight paths: the mean of exactly-1 samples is 1 to ~1e-6.
constexpr double kFurnaceFloatTol = 1e-5;

Scene enclosure_scene(const Material& object) {
    Scene scene;
    SceneEditor editor(scene);
    editor.add_material(object);
    Material glow;
    glow.kind = BsdfKind::Emission;
    glow.radiance = Rgb(1.f);
    editor.add_material(glow);
    editor.add_sphere(Sphere{Vec3(0.f), 0.5f, 0});
    editor.add_sphere(Sphere{Vec3(0.f), kEnclosureRadius, 1}); // its Sphere light
    // 3 units above the object; an 18 degree field of view sees only the object.
    scene.camera = camera_looking_down(Vec3(0.f, 3.f, 0.f), 18.f);
    editor.finalize();
    return scene;
}

Estimate furnace_render(const Scene& scene, AccelKind accel, bool mis, bool hemisphere,
                        float hfov = 18.f, int spp = 64) {
    Scene s = scene;
    s.camera = camera_looking_down(Vec3(0.f, 3.f, 0.f), hfov);
    RenderSettings set = small_settings(accel, 8, spp);
    set.max_depth = 1000; // roulette ends the paths
    set.mis = mis;
    set.hemisphere = hemisphere;
    return film_estimate(render_film(s, set));
}

Material white(BsdfKind kind) {
    Material m;
    m.kind = kind;
    m.albedo = m.reflectance = m.transmittance = Rgb(1.f);
    m.ior = 1.5f;
    return m;
}

} // namespace

TEST_CASE("furnace: lossless objects in a uniform environment have radiance 1", "[render][stat]") {
    const AccelKind accel = accel_param();
    for (BsdfKind kind :
         {BsdfKind::Diffuse, BsdfKind::Mirror, BsdfKind::Glass, BsdfKind::Refraction}) {
        const Scene scene = enclosure_scene(white(kind));
        for (int mode = 0; mode < 3; ++mode) {
            const bool mis = mode == 0, hemisphere = mode == 2;
            const Estimate e = furnace_render(scene, accel, mis, hemisphere, 18.f, 256);
            INFO(bsdf_kind_name(kind) << " (" << accel_kind_name(accel) << ", mode " << mode
                                      << "): " << e.mean << " +- " << e.std_err);
            CHECK(std::abs(e.mean - 1.0) <= kZBound * e.std_err + kFurnaceFloatTol);
            // Informative: next-event estimation alone (--no-mis) of a diffuse object is the
            // noisiest, ~1% at 256 samples per pixel.
            CHECK(e.std_err < 0.015);
        }
    }
}

TEST_CASE("furnace: rough conductor and rough glass agree across estimators, at most 1",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    Material conductor;
    conductor.kind = BsdfKind::Microfacet;
    conductor.alpha = 0.5f;
    conductor.eta = Rgb(1.f);
    conductor.k = Rgb(1000.f); // F ~ 1: only Smith's shadowing-masking loses energy
    Material glass = white(BsdfKind::Glass);
    glass.roughness = 0.4f;
    REQUIRE_FALSE(glass.is_delta());
    for (const Material& m : {conductor, glass}) {
        const Scene scene = enclosure_scene(m);
        // Without MIS the light reaches the inside of the glass only by next-event estimation
        // from its inner surface: noisier, so more samples (16k paths, still under 0.1 s).
        const Estimate mis = furnace_render(scene, accel, true, false, 18.f, 256);
        const Estimate nee = furnace_render(scene, accel, false, false, 18.f, 256);
        INFO(bsdf_kind_name(m.kind)
             << " (" << accel_kind_name(accel) << "): MIS " << mis.mean << " +- " << mis.std_err
             << ", no MIS " << nee.mean << " +- " << nee.std_err);
        CHECK(std::abs(mis.mean - nee.mean) <=
              kZBound * std::sqrt(mis.std_err * mis.std_err + nee.std_err * nee.std_err));
        CHECK(mis.mean <= 1.0 + kZBound * mis.std_err);
        CHECK(mis.mean > 0.5);
        CHECK(mis.std_err < 0.01);
        if (!m.has_transmission()) {
            // Uniform hemisphere sampling sees the whole reflection lobe of an opaque surface.
            const Estimate h = furnace_render(scene, accel, true, true, 18.f, 256);
            INFO("-H " << h.mean << " +- " << h.std_err);
            CHECK(std::abs(mis.mean - h.mean) <=
                  kZBound * std::sqrt(mis.std_err * mis.std_err + h.std_err * h.std_err));
        }
    }
}

TEST_CASE("furnace: a rough conductor at normal incidence shows its directional albedo",
          "[render][stat]") {
    const AccelKind accel = accel_param();
    Material m;
    m.kind = BsdfKind::Microfacet;
    m.alpha = 0.5f;
    m.eta = Rgb(1.f);
    m.k = Rgb(1000.f);
    // Quadrature of f cos over the hemisphere at wo = +z (the integrand is smooth; cells on
    // the horizon's edge).
    const Vec3 wo(0.f, 0.f, 1.f);
    auto g = [&](const Vec3& wi) -> float {
        return wi.z > 0.f ? luminance(bsdf_f(m, wo, wi)) * wi.z : 0.f;
    };
    const double albedo = test::integrate_sphere(g, 40, 80, 1e-7);
    // A tiny field of view: every pixel sees the object's pole head-on.
    const Estimate e = furnace_render(enclosure_scene(m), accel, true, false, 1e-3f, 256);
    INFO("render " << e.mean << " +- " << e.std_err << ", albedo " << albedo);
    // The quadrature is accurate to ~1e-6; the render's own noise dominates.
    CHECK(std::abs(e.mean - albedo) <= kZBound * e.std_err + 1e-5);
    CHECK(e.std_err < 0.003);
    CHECK(albedo < 0.99); // the loss is there to be seen
}

TEST_CASE("furnace: lossless ellipsoids in a uniform environment have radiance 1",
          "[render][stat]") {
    // A sheared, rotated ellipsoid: white Lambertian and white glass are lossless whatever the
    // shape (the ellipsoid is convex, so every diffuse bounce leaves it; glass is power
    // conserving), so the render is 1 with every estimator.
    const AccelKind accel = accel_param();
    Mat3d L;
    const double v[3][3] = {{0.45, 0.15, -0.05}, {0.05, 0.2, 0.1}, {-0.1, 0.1, 0.35}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            L.m[i][j] = v[i][j];
    for (BsdfKind kind : {BsdfKind::Diffuse, BsdfKind::Glass}) {
        Scene scene = enclosure_scene(white(kind));
        scene.spheres[0] = make_ellipsoid(Vec3(0.f), L, 0);
        SceneEditor(scene).finalize();
        for (int mode = 0; mode < 3; ++mode) {
            const Estimate e = furnace_render(scene, accel, mode == 0, mode == 2, 18.f, 256);
            INFO(bsdf_kind_name(kind) << " ellipsoid (" << accel_kind_name(accel) << ", mode "
                                      << mode << "): " << e.mean << " +- " << e.std_err);
            CHECK(std::abs(e.mean - 1.0) <= kZBound * e.std_err + kFurnaceFloatTol);
            CHECK(e.std_err < 0.015);
        }
    }
}

TEST_CASE("an emissive ellipsoid lights a floor alike for every estimator", "[render][stat]") {
    // Light sampling (sample_li / pdf_li of the ellipsoid), MIS and hemisphere sampling (which
    // only finds the ellipsoid by hitting it) must agree in the mean.
    const AccelKind accel = accel_param();
    Scene scene;
    SceneEditor editor(scene);
    Material floor;
    floor.albedo = Rgb(0.7f);
    editor.add_material(floor);
    Material glow;
    glow.kind = BsdfKind::Emission;
    glow.radiance = Rgb(4.f);
    editor.add_material(glow);
    add_floor(scene, 5.f, 0.f, 0);
    Mat3d L;
    const double v[3][3] = {{0.6, 0.2, 0.0}, {0.1, 0.15, -0.1}, {0.0, 0.3, 0.25}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            L.m[i][j] = v[i][j];
    editor.add_sphere(make_ellipsoid(Vec3(0.3f, 0.8f, -0.2f), L, 1)); // its Sphere light
    scene.camera = camera_looking_down(Vec3(0.f, 3.f, 0.f), 60.f);
    editor.finalize();
    std::vector<Estimate> est;
    for (int mode = 0; mode < 3; ++mode) {
        RenderSettings s = small_settings(accel, 8, 256);
        s.max_depth = 3;
        s.mis = mode == 0;
        s.hemisphere = mode == 2;
        est.push_back(film_estimate(render_film(scene, s)));
        INFO("mode " << mode << ": " << est.back().mean << " +- " << est.back().std_err);
        CHECK(est.back().std_err < 0.03 * est.back().mean);
    }
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            INFO("modes " << a << ", " << b << ": " << est[a].mean << " +- " << est[a].std_err
                          << " vs " << est[b].mean << " +- " << est[b].std_err);
            CHECK(std::abs(est[a].mean - est[b].mean) <=
                  kZBound *
                      std::sqrt(est[a].std_err * est[a].std_err + est[b].std_err * est[b].std_err));
        }
}
