// `candela probe`'s splits of one pixel (diagnostics/probe.h): the pixel is the render's own value,
// each split adds up to it, and the per-light split estimates what each light gives alone.
#include "render_support.h"

#include "candela/diagnostics/probe.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene_editor.h"

#include <catch2/catch.hpp>

using namespace candela;
using namespace candela::test;

namespace {

/// A split's classes add up to the pixel up to float rounding: each sample's radiance is a
/// float sum of at most a few tens of contributions (about 1e-7 relative each), and the
/// classes' per-sample parts are float sums of the same values in another grouping.
constexpr double kSplitSumTol = 1e-5;

RenderSettings probe_settings(int spp) {
    RenderSettings s;
    s.width = 40;
    s.height = 30;
    s.spp = spp;
    s.quiet = true;
    s.seed = 11;
    s.max_depth = 6;
    s.adaptive = AdaptiveKind::None;
    return s;
}

Rgb split_sum(const std::vector<ProbeShare>& split) {
    Rgb sum(0.f);
    for (const ProbeShare& s : split)
        sum += s.mean;
    return sum;
}

void check_sums_to_pixel(const std::vector<ProbeShare>& split, const Rgb& pixel, const char* what) {
    const Rgb sum = split_sum(split);
    for (int c = 0; c < 3; ++c) {
        INFO(what << " channel " << c << ": sum " << sum[c] << ", pixel " << pixel[c]);
        CHECK(std::abs(double(sum[c]) - double(pixel[c])) <=
              kSplitSumTol * std::max(1e-3, double(pixel[c])));
    }
}

/// A floor with a sphere on it, lit by two rectangular lights of different colours (either
/// left out), seen from above.
Scene two_light_scene(bool first, bool second) {
    Scene scene;
    SceneEditor editor(scene);
    Material grey;
    grey.albedo = Rgb(0.6f);
    add_floor(scene, 4.f, 0.f, editor.add_material(grey));
    Material red;
    red.albedo = Rgb(0.7f, 0.2f, 0.2f);
    editor.add_sphere(Sphere{Vec3(0.3f, 0.5f, 0.f), 0.5f, editor.add_material(red)});
    if (first)
        add_rect_light(scene, Vec3(-1.f, 2.f, 0.f), Vec3(1.f, 0.f, 0.f), Vec3(0.f, 0.f, 1.f),
                       Rgb(4.f, 4.f, 3.f));
    if (second)
        add_rect_light(scene, Vec3(1.5f, 1.5f, 0.5f), Vec3(0.5f, 0.f, 0.f), Vec3(0.f, 0.f, 0.5f),
                       Rgb(2.f, 3.f, 8.f));
    scene.camera = camera_looking_down(Vec3(0.f, 3.f, 0.f), 70.f);
    editor.finalize();
    return scene;
}

} // namespace

TEST_CASE("probe: the pixel is the render's, and every split adds up to it", "[probe][render]") {
    const Scene& scene = spheres_scene();
    RenderSettings s = probe_settings(64);
    s.integrator = GENERATE(IntegratorKind::Path, IntegratorKind::Direct);
    s.hemisphere = GENERATE(false, true);
    const int x = 23, y = 17;
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    const ProbeResult r = probe_pixel(scene, *accel, s, x, y, 2);

    // The render of that pixel alone (a region of one pixel) with the same settings.
    RenderSettings one = s;
    one.region = Region{x, y, 1, 1};
    const Film film = render_film(scene, one);
    CHECK(film.mean(0, 0) == r.pixel);
    CHECK(r.samples == 64);
    REQUIRE(luminance(r.pixel) > 0.f);

    check_sums_to_pixel(r.by_order, r.pixel, "by order");
    check_sums_to_pixel(r.by_light, r.pixel, "by light");
    check_sums_to_pixel(r.by_first_material, r.pixel, "by first material");
    check_sums_to_pixel(r.by_first_object, r.pixel, "by first object");
    check_sums_to_pixel(r.by_last_scatter, r.pixel, "by last scatter");
    // The direct integrator stops after one scattering event.
    if (s.integrator == IntegratorKind::Direct)
        for (std::size_t o = 2; o < r.by_order.size(); ++o)
            CHECK(r.by_order[o].mean == Rgb(0.f));
    CHECK(r.top_percent_share > 0.0);
    CHECK(r.top_percent_share <= 1.0);
    REQUIRE(r.heaviest.size() == 2);
    CHECK(luminance(r.heaviest[0].L) >= luminance(r.heaviest[1].L));
    CHECK_FALSE(r.heaviest[0].vertices.empty());
}

TEST_CASE("probe: a pixel that sees the sky, delta and infinite lights still adds up",
          "[probe][render]") {
    Diagnostics diag;
    const Scene scene =
        load_scene(std::string(CANDELA_PROJECT_SCENES) + "/lights.dae", BuildOptions{}, diag);
    RenderSettings s = probe_settings(64);
    s.hemisphere = GENERATE(false, true);
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    for (const auto& [x, y] : {std::pair<int, int>{20, 15}, {15, 18}}) {
        const ProbeResult r = probe_pixel(scene, *accel, s, x, y, 1);
        INFO("pixel " << x << " " << y);
        REQUIRE(luminance(r.pixel) > 0.f);
        check_sums_to_pixel(r.by_order, r.pixel, "by order");
        check_sums_to_pixel(r.by_light, r.pixel, "by light");
        check_sums_to_pixel(r.by_first_material, r.pixel, "by first material");
        check_sums_to_pixel(r.by_last_scatter, r.pixel, "by last scatter");
    }
}

TEST_CASE("probe: the per-light split matches renders with each light alone",
          "[probe][render][stat]") {
    const Scene both = two_light_scene(true, true);
    const Scene only_first = two_light_scene(true, false);
    const Scene only_second = two_light_scene(false, true);
    const RenderSettings s = probe_settings(4096);
    // A pixel on the floor beside the sphere, lit by both lights directly and by the sphere.
    const int x = 24, y = 14;
    auto probe = [&](const Scene& scene) {
        std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
        return probe_pixel(scene, *accel, s, x, y, 0);
    };
    const ProbeResult r = probe(both);
    // Light 0 is the first rect light in every scene that has it; the second is light 1 with
    // both, light 0 alone.
    const ProbeResult a = probe(only_first), b = probe(only_second);
    const ProbeShare& first = r.by_light[0];
    const ProbeShare& second = r.by_light[1];
    for (int c = 0; c < 3; ++c) {
        // Independent estimates (other scenes, other light choices): the difference has the
        // standard error sqrt(se_split^2 + se_alone^2).
        const double bound_a =
            kZBound * std::hypot(double(first.std_error[c]), double(a.std_error[c]));
        const double bound_b =
            kZBound * std::hypot(double(second.std_error[c]), double(b.std_error[c]));
        INFO("channel " << c << ": first " << first.mean[c] << " vs " << a.pixel[c] << " (bound "
                        << bound_a << "), second " << second.mean[c] << " vs " << b.pixel[c]
                        << " (bound " << bound_b << ")");
        REQUIRE(bound_a > 0.0);
        REQUIRE(bound_b > 0.0);
        CHECK(std::abs(double(first.mean[c]) - double(a.pixel[c])) < bound_a);
        CHECK(std::abs(double(second.mean[c]) - double(b.pixel[c])) < bound_b);
        // Informative: each light's share is resolved to a few per cent.
        CHECK(first.std_error[c] < 0.05f * first.mean[c]);
        CHECK(second.std_error[c] < 0.05f * second.mean[c]);
    }
}

TEST_CASE("probe: a pixel outside the frame is refused", "[probe][quick]") {
    const Scene& scene = spheres_scene();
    const RenderSettings s = probe_settings(4);
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    CHECK_THROWS_WITH(probe_pixel(scene, *accel, s, 40, 0, 0),
                      Catch::Contains("pixel (40, 0) is not inside the 40x30 frame"));
}
