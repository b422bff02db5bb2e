// Refining a finished render (render/refine.h): continuing it to a stricter noise threshold or
// a larger -s gives the image a render with the final settings from the start gives.
#include "render_support.h"

#include "candela/render/adaptive.h"
#include "candela/render/refine.h"

#include <catch2/catch.hpp>

using namespace candela;
using namespace candela::test;

namespace {

RenderSettings refine_settings() {
    RenderSettings s;
    s.width = 48;
    s.height = 36;
    s.quiet = true;
    s.seed = 5;
    s.max_depth = 5;
    s.progress = ProgressMode::None;
    return s;
}

/// The relative sampler with a budget of 512 samples per pixel stopping at `threshold`.
RenderSettings threshold_settings(float threshold) {
    RenderSettings s = refine_settings();
    s.adaptive = AdaptiveKind::Relative;
    s.adaptive_batch = 16;
    s.spp = 512;
    s.noise_threshold = threshold;
    return s;
}

/// Renders `before` to the end, then continues its state with `after`.
Film refined(const Scene& scene, const RenderSettings& before, const RenderSettings& after,
             RenderStats& first, RenderStats& second) {
    std::unique_ptr<Accel> accel = make_accel(scene, before.accel);
    Renderer r1(scene, *accel, before);
    RenderState st = r1.start();
    r1.run(st, first);
    REQUIRE(make_pass_policy(before)->finished(st));
    reopen_for_refinement(before, after, st);
    REQUIRE_FALSE(make_pass_policy(after)->finished(st));
    Renderer(scene, *accel, after).run(st, second);
    return std::move(st.film);
}

/// Whether two films hold the same sums in every pixel: the same image bit for bit.
void check_same_film(const Film& a, const Film& b) {
    REQUIRE(a.width() == b.width());
    REQUIRE(a.height() == b.height());
    CHECK(a.raw_sum() == b.raw_sum());
    std::size_t differing = 0;
    for (int y = 0; y < a.height(); ++y)
        for (int x = 0; x < a.width(); ++x)
            differing += a.count(x, y) != b.count(x, y) || !(a.mean(x, y) == b.mean(x, y));
    CHECK(differing == 0);
}

} // namespace

TEST_CASE("refine: noise threshold 0.04 continued to 0.02 is the render to 0.02",
          "[refine][render]") {
    const Scene& scene = spheres_scene();
    const RenderSettings loose = threshold_settings(0.04f), strict = threshold_settings(0.02f);
    RenderStats first, second, direct_stats;
    const Film film = refined(scene, loose, strict, first, second);
    CHECK(first.stop == StopReason::NoiseThreshold);
    CHECK(second.stop == StopReason::NoiseThreshold);
    CHECK(second.passes > 0);
    const Film direct = render_film(scene, strict, &direct_stats);
    CHECK(direct_stats.passes == first.passes + second.passes);
    check_same_film(film, direct);
}

TEST_CASE("refine: -s 32 continued to -s 64 under --adaptive none is -s 64", "[refine][render]") {
    const Scene& scene = spheres_scene();
    RenderSettings s32 = refine_settings();
    s32.adaptive = AdaptiveKind::None;
    s32.spp = 32;
    RenderSettings s64 = s32;
    s64.spp = 64;
    RenderStats first, second;
    const Film film = refined(scene, s32, s64, first, second);
    check_same_film(film, render_film(scene, s64));
}

TEST_CASE("refine: cs184 -s continued at a pass boundary is the larger -s", "[refine][render]") {
    const Scene& scene = spheres_scene();
    RenderSettings s = refine_settings();
    s.adaptive = AdaptiveKind::Cs184;
    s.adaptive_batch = 8;
    s.adaptive_tol = 0.05f;
    s.spp = 32;
    RenderSettings more = s;
    more.spp = 64;
    RenderStats first, second;
    const Film film = refined(scene, s, more, first, second);
    check_same_film(film, render_film(scene, more));
}

TEST_CASE("refine: a larger -s under the relative sampler agrees with the direct render",
          "[refine][render][stat]") {
    // The budget and the per-pixel cap grow with -s, so the allocations differ from a direct
    // render's after the first render's end (refine.h): the images agree in expectation.
    const Scene& scene = spheres_scene();
    RenderSettings s = refine_settings();
    s.adaptive = AdaptiveKind::Relative;
    s.adaptive_batch = 16;
    s.noise_threshold = 0.f;
    s.spp = 32;
    RenderSettings more = s;
    more.spp = 96;
    RenderStats first, second, direct_stats;
    const Estimate a = film_estimate(refined(scene, s, more, first, second));
    const Estimate b = film_estimate(render_film(scene, more, &direct_stats));
    // The two share the first render's samples, so their difference varies less than two
    // independent estimates': the bound of independent ones is conservative.
    INFO("refined " << a.mean << " +- " << a.std_err << ", direct " << b.mean << " +- "
                    << b.std_err);
    REQUIRE(a.std_err > 0.0);
    CHECK(std::abs(a.mean - b.mean) < kZBound * std::hypot(a.std_err, b.std_err));
    // The refinement rendered: the larger budget gave it samples to take.
    CHECK(second.samples > 0);
}

TEST_CASE("refine: a looser setting or a spent budget is refused", "[refine][quick]") {
    RenderSettings s = refine_settings();
    s.adaptive = AdaptiveKind::Relative;
    s.spp = 64;
    s.noise_threshold = 0.02f;
    RenderState st;
    RenderSettings fewer = s;
    fewer.spp = 32;
    CHECK_THROWS_WITH(reopen_for_refinement(s, fewer, st), Catch::Contains("cannot lower -s"));
    RenderSettings looser = s;
    looser.noise_threshold = 0.05f;
    CHECK_THROWS_WITH(reopen_for_refinement(s, looser, st),
                      Catch::Contains("cannot raise the noise threshold"));
}

TEST_CASE("refine: the forecast of a threshold refinement follows the noise model",
          "[refine][quick]") {
    const Scene& scene = spheres_scene();
    const RenderSettings loose = threshold_settings(0.04f), strict = threshold_settings(0.02f);
    std::unique_ptr<Accel> accel = make_accel(scene, loose.accel);
    Renderer r(scene, *accel, loose);
    RenderState st = r.start();
    RenderStats stats;
    r.run(st, stats);
    reopen_for_refinement(loose, strict, st);
    const RefineForecast f = forecast_refinement(strict, st, 10.0);
    // The error falls as 1/sqrt(cost): (noise / 0.02)^2 times the cost so far in all, plus
    // half a pass; in seconds at the measured 10 s for the cost so far.
    REQUIRE(f.noise > 0.0);
    CHECK(f.noise <= 0.04);
    const double ratio = f.noise / 0.02;
    CHECK(f.seconds > 10.0 * (ratio * ratio - 1.0));
    CHECK(f.seconds < 10.0 * (ratio * ratio - 1.0) + 10.0);
    CHECK(f.samples > 0.0);
}

TEST_CASE("refine: a relative render whose budget share reached -s is finished",
          "[refine][quick]") {
    // A version 3 or 4 checkpoint of a finished relative render holds its end only as the share
    // of the budget (budget_spp = -s), not as `stopped`.
    RenderSettings s = refine_settings();
    s.adaptive = AdaptiveKind::Relative;
    s.spp = 64;
    RenderState st;
    st.budget_spp = 64;
    CHECK_FALSE(st.stopped);
    CHECK(make_pass_policy(s)->finished(st));
    st.budget_spp = 63;
    CHECK_FALSE(make_pass_policy(s)->finished(st));
    RenderSettings uniform = s;
    uniform.adaptive = AdaptiveKind::None;
    st.budget_spp = 64;
    CHECK_FALSE(make_pass_policy(uniform)->finished(st));
}

TEST_CASE("refine: a larger -s reopens a relative render whose budget was spent",
          "[refine][quick]") {
    RenderSettings s = refine_settings();
    s.width = 2;
    s.height = 1;
    s.adaptive = AdaptiveKind::Relative;
    s.spp = 32;
    RenderState st;
    st.film = Film(2, 1, AovSet{}, true);
    st.passes = 3;
    st.done = {0, 0};
    st.stopped = true; // the budget of -s 32 was spent
    st.cost = {60, 40};
    st.cost_budget = 100;
    st.budget_spp = 32;
    RenderSettings more = s;
    more.spp = 64;
    reopen_for_refinement(s, more, st);
    // The budget doubles with -s; 100 of its 200 units are spent: half of the new -s.
    CHECK(st.cost_budget == 200);
    CHECK(st.budget_spp == 32);
    CHECK_FALSE(st.stopped);
    CHECK_FALSE(make_pass_policy(more)->finished(st));
}
