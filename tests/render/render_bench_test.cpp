// bench --render: the ray counts it reports are the render's own, its raw-Embree rates are
// measured on rays of the three kinds, and its ceiling is the counts at those rates.
#include "candela/accel/accel.h"
#include "candela/diagnostics/render_bench.h"
#include "candela/render/renderer.h"
#include "candela/scene/procedural.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <memory>

using namespace candela;

namespace {

RenderBenchOptions small_bench() {
    RenderBenchOptions o;
    o.settings.width = 24;
    o.settings.height = 18;
    o.settings.spp = 4;
    o.settings.max_depth = 5;
    o.settings.sampler = SamplerKind::Sobol;
    o.threads = {1};
    o.record_rays = 1000;
    o.render_rounds = 1;
    o.raw_seconds = 0.03;
    o.raw_rounds = 1;
    return o;
}

/// The same render outside the bench, on one thread: the bench row must report its exact ray
/// counts (the image is a pure function of scene and settings, and so is every path's ray
/// count).
RenderStats check_counts_are_the_renders(const RenderBenchRow& row, const Scene& scene,
                                         RenderSettings s) {
    s.threads = 1;
    s.quiet = true;
    s.progress = ProgressMode::None;
    const std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    RenderStats st;
    Renderer(scene, *accel, s).render(st);
    CHECK(row.camera_rays == st.camera_rays);
    CHECK(row.bounce_rays == st.rays - st.camera_rays);
    CHECK(row.shadow_rays == st.shadow_rays);
    return st;
}

} // namespace

TEST_CASE("box:KIND:N puts the content in a lit open box", "[render_bench]") {
    const Scene plain = make_procedural_scene("sphere:2000");
    const Scene boxed = make_procedural_scene("box:sphere:2000");
    // The sphere, the five walls (10 triangles) and the two-triangle ceiling light.
    CHECK(boxed.meshes.size() == plain.meshes.size() + 2);
    CHECK(boxed.triangle_count() == plain.triangle_count() + 10 + 2);
    REQUIRE(boxed.lights.size() == 1);
    CHECK(boxed.lights[0].kind == LightKind::Area);
    CHECK(plain.lights[0].kind == LightKind::Point);
}

TEST_CASE("bench --render counts the render's own rays and measures a ceiling for them",
          "[render_bench]") {
    const Scene scene = make_procedural_scene("box:sphere:2000");
    const RenderBenchOptions opt = small_bench();
    const RenderBenchReport rep = run_render_bench(scene, opt);
    REQUIRE(rep.rows.size() == 1);
    const RenderBenchRow& row = rep.rows[0];

    check_counts_are_the_renders(row, scene, opt.settings);
    CHECK(row.camera_rays == std::uint64_t(24 * 18 * 4));
    // A closed-at-the-back box around a sphere: paths bounce and light is sampled at each hit.
    CHECK(row.bounce_rays > 0);
    CHECK(row.shadow_rays > 0);

    // Rays of every kind were recorded (up to the cap) and timed.
    CHECK(rep.recorded_camera == opt.record_rays);
    CHECK(rep.recorded_bounce > 0);
    CHECK(rep.recorded_bounce <= opt.record_rays);
    CHECK(rep.recorded_shadow > 0);
    CHECK(rep.recorded_shadow <= opt.record_rays);
    CHECK(row.raw_camera > 0.0);
    CHECK(row.raw_bounce > 0.0);
    CHECK(row.raw_shadow > 0.0);
    const double expected = double(row.camera_rays) / (row.raw_camera * 1e6) +
                            double(row.bounce_rays) / (row.raw_bounce * 1e6) +
                            double(row.shadow_rays) / (row.raw_shadow * 1e6);
    CHECK(row.ceiling_seconds == Approx(expected).epsilon(1e-12));
    CHECK(row.render_seconds > 0.0);
    CHECK(row.fraction() == Approx(row.ceiling_seconds / row.render_seconds).epsilon(1e-12));
    CHECK(row.render_cpu_seconds > 0.0);
    CHECK(row.ceiling_cpu_seconds > 0.0);

    const nlohmann::json json = nlohmann::json::parse(rep.to_json());
    REQUIRE(json.at("rows").size() == rep.rows.size());
    const nlohmann::json& jrow = json.at("rows")[0];
    CHECK(jrow.at("camera_rays") == row.camera_rays);
    CHECK(jrow.at("fraction_of_ceiling").get<double>() == Approx(row.fraction()));
    CHECK(jrow.at("raw_mrays_per_s").at("bounce").get<double>() == Approx(row.raw_bounce));
}

TEST_CASE("bench --render measures the default configuration on its own rays as well",
          "[render_bench]") {
    const Scene scene = make_procedural_scene("box:sphere:2000");
    RenderBenchOptions opt = small_bench();
    opt.settings.spp = 8;
    RenderSettings d = opt.settings;
    d.adaptive = AdaptiveKind::Relative;
    d.adaptive_batch = 2; // several passes, so that the relative sampler reallocates
    d.noise_threshold = 0.f;
    opt.default_settings = d;
    const RenderBenchReport rep = run_render_bench(scene, opt);
    REQUIRE(rep.rows.size() == 2);
    CHECK(rep.rows[0].config == "uniform");
    const RenderBenchRow& row = rep.rows[1];
    CHECK(row.config == "default");

    // Its counts are those of the same render outside the bench, which differ from uniform's.
    const RenderStats st = check_counts_are_the_renders(row, scene, d);
    CHECK(st.passes > 1);
    CHECK(row.camera_rays != rep.rows[0].camera_rays);
    CHECK(row.raw_camera > 0.0);
    CHECK(row.raw_bounce > 0.0);
    CHECK(row.raw_shadow > 0.0);
    CHECK(row.fraction() > 0.0);

    const nlohmann::json json = nlohmann::json::parse(rep.to_json());
    REQUIRE(json.at("rows").size() == 2);
    CHECK(json.at("rows")[1].at("config") == "default");
    CHECK(rep.to_text().find("default ") != std::string::npos);
}

TEST_CASE("bench --render refuses a backend other than embree", "[render_bench]") {
    const Scene scene = make_procedural_scene("box:sphere:500");
    RenderBenchOptions opt = small_bench();
    opt.settings.accel.kind = AccelKind::Builtin;
    CHECK_THROWS_AS(run_render_bench(scene, opt), Error);
}

TEST_CASE("bench figures are medians with their range over the repeats", "[render_bench][quick]") {
    const Spread odd = Spread::of({3.0, 1.0, 2.0});
    CHECK(odd.median == 2.0);
    CHECK(odd.min == 1.0);
    CHECK(odd.max == 3.0);
    CHECK(odd.repeats == 3);
    CHECK(odd.text(2) == "2.00 (1.00-3.00)");
    CHECK(Spread::of({4.0, 1.0, 2.0, 3.0}).median == 2.5);
    CHECK(Spread::of({1.5}).text(1) == "1.5 (1 round)");
    CHECK_FALSE(Spread::of({}).measured());
    CHECK(Spread::of({}).text(3) == "n/a");
}

TEST_CASE("bench warns when the machine is loaded beyond its cores", "[render_bench][quick]") {
    CHECK(load_warning(1.9, 2).empty());
    CHECK(load_warning(2.0, 2).empty());
    CHECK_THAT(load_warning(5.31, 2), Catch::Contains("one-minute load average is 5.31 on 2 "
                                                      "cores"));
}

TEST_CASE("bench --render repeats each figure and says n/a for what it did not measure",
          "[render_bench]") {
    const Scene scene = make_procedural_scene("box:sphere:500");
    RenderBenchOptions opt = small_bench();
    opt.render_rounds = 3;
    opt.raw_rounds = 2;
    const RenderBenchReport rep = run_render_bench(scene, opt);
    REQUIRE(rep.rows.size() == 1);
    const RenderBenchRow& row = rep.rows[0];
    CHECK(row.render.repeats == 3);
    CHECK(row.render.min <= row.render_seconds);
    CHECK(row.render_seconds <= row.render.max);
    CHECK(row.render_seconds == row.render.median);
    CHECK(row.raw_bounce_spread.repeats == 2);
    CHECK(row.raw_bounce == row.raw_bounce_spread.median);
    const std::string text = rep.to_text();
    CHECK_THAT(text, Catch::Contains("spread over the repeats, median (min-max)"));
    CHECK_THAT(text, !Catch::Contains("n/a"));
    const nlohmann::json j = nlohmann::json::parse(rep.to_json());
    CHECK(j.at("rows")[0].at("render_rounds") == 3);
    CHECK(j.at("rows")[0].at("render_seconds_range").size() == 2);

    // A kind of ray the render did not trace has no raw rate, no ceiling and no share of it.
    RenderBenchReport none = rep;
    RenderBenchRow& r = none.rows[0];
    r.shadow_rays = 0;
    r.raw_shadow = 0.0;
    r.raw_shadow_spread = Spread{};
    r.ceiling_seconds = 0.0;
    r.ceiling_cpu_seconds = 0.0;
    const std::string missing = none.to_text();
    INFO(missing);
    CHECK_THAT(missing, Catch::Contains("n/a"));
    CHECK_THAT(missing, Catch::Contains("shadow n/a"));
    CHECK_THAT(missing, !Catch::Contains(" 0.0%"));
    const nlohmann::json jn = nlohmann::json::parse(none.to_json());
    CHECK(jn.at("rows")[0].at("raw_mrays_per_s").at("shadow").is_null());
    CHECK(jn.at("rows")[0].at("fraction_of_ceiling").is_null());
}
