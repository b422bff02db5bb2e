#include "candela/render/refine.h"

#include "candela/render/adaptive.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

namespace {

std::uint64_t spent_cost(const RenderState& st) {
    std::uint64_t sum = 0;
    for (std::uint64_t c : st.cost)
        sum += c;
    return sum;
}

/// The relative sampler's share of its budget when `spent` of `budget` cost units are spent,
/// in samples per pixel of -s `spp`, as RelativePolicy::decide counts it (RenderState::budget_spp).
int budget_share_spp(std::uint64_t spent, std::uint64_t budget, int spp) {
    const double share = double(spent) / double(budget);
    return int(std::min(double(spp), std::floor(share * double(spp))));
}

std::uint64_t samples_taken(const RenderState& st) {
    return st.film.total_samples() + st.film.total_dropped();
}

/// The relative sampler's estimate of the image's relative RMS error, as Renderer::run computes
/// it after a pass.
double estimated_noise(const Film& film) {
    LumStatsMap m;
    fill_lum_stats(film, m);
    return estimated_relative_rms(m, relative_error_map(m, 0, WindowCentre::Include));
}

} // namespace

void reopen_for_refinement(const RenderSettings& before, const RenderSettings& after,
                           RenderState& st) {
    if (after.spp < before.spp)
        throw Error(ErrorKind::Usage, "a refinement cannot lower -s (" +
                                          std::to_string(before.spp) + " to " +
                                          std::to_string(after.spp) + ")");
    // 0 is no threshold: the strictest.
    const bool stricter_or_same =
        after.noise_threshold == 0.f || after.noise_threshold <= before.noise_threshold;
    if (after.adaptive == AdaptiveKind::Relative && !stricter_or_same)
        throw Error(ErrorKind::Usage, "a refinement cannot raise the noise threshold");
    const bool finished = render_finished(before, st);
    if (!finished && after.spp == before.spp && after.noise_threshold == before.noise_threshold)
        return;
    const int w = st.film.width(), h = st.film.height();
    const std::size_t pixels = st.film.pixel_count();
    switch (after.adaptive) {
    case AdaptiveKind::None:
        // Sample k of a pixel is the same in any pass: the render goes on at next_sample.
        return;
    case AdaptiveKind::Cs184:
        // A direct render with the larger -s tests every running pixel at the old -s, a pass
        // boundary for it; the finished render did not (its last pass ended it).
        if (!finished || after.spp == before.spp) return;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                std::uint8_t& done = st.done[std::size_t(y) * w + x];
                if (!done && adaptive_pixel_converged(st.film, x, y, after.adaptive_tol)) done = 1;
            }
        // Every pixel has converged: the sampler ends the render (Cs184Policy::decide).
        if (std::all_of(st.done.begin(), st.done.end(), [](std::uint8_t d) { return d != 0; }))
            st.stopped = true;
        return;
    case AdaptiveKind::Relative:
        break;
    }
    if (pixels == 1) {
        // A lone pixel takes -s samples uniformly (RelativePolicy: no neighbours to judge it by).
        const std::uint64_t taken = samples_taken(st);
        st.budget_spp = int(std::min<std::uint64_t>(taken, std::uint64_t(after.spp)));
        st.stopped = taken >= std::uint64_t(after.spp);
        return;
    }
    if (st.cost_budget == 0) return; // no pass has set the budget: the render starts afresh
    // The budget is -s uniform samples at the first pass's cost per sample: it scales with -s.
    if (after.spp != before.spp)
        st.cost_budget = std::uint64_t(
            std::llround(double(st.cost_budget) * double(after.spp) / double(before.spp)));
    // Progress counts the share of the budget spent, in samples per pixel of the new -s; a
    // render whose budget is spent stays finished. Any other stop (the threshold, nothing to
    // gain) is decided again after the next pass, under the new settings.
    const std::uint64_t spent = spent_cost(st);
    st.budget_spp = budget_share_spp(spent, st.cost_budget, after.spp);
    st.stopped = spent >= st.cost_budget;
}

bool render_finished(const RenderSettings& s, const RenderState& st) {
    // A relative render of a version 3 or 4 checkpoint says it ended only by its share of the
    // budget (PassPolicy::prepare).
    return st.finished(s.spp) || (s.adaptive == AdaptiveKind::Relative && st.budget_spp >= s.spp);
}

RefineForecast forecast_refinement(const RenderSettings& s, const RenderState& st,
                                   double seconds_so_far) {
    RefineForecast f;
    if (render_finished(s, st)) return f;
    const std::uint64_t taken = samples_taken(st);
    const std::size_t pixels = st.film.pixel_count();
    const double seconds_per_sample = taken > 0 ? seconds_so_far / double(taken) : 0.0;
    const double left_per_pixel = double(s.spp - st.next_sample);
    if (s.adaptive == AdaptiveKind::None) {
        f.samples = left_per_pixel * double(pixels);
    } else if (s.adaptive == AdaptiveKind::Cs184) {
        f.samples = left_per_pixel * double(std::count(st.done.begin(), st.done.end(), 0));
    } else if (pixels == 1 || st.cost_budget == 0) {
        f.samples = double(s.spp) - double(taken);
    } else {
        const double spent = double(spent_cost(st));
        f.noise = estimated_noise(st.film);
        double end = double(st.cost_budget);
        if (s.noise_threshold > 0.f && f.noise > double(s.noise_threshold)) {
            const double ratio = f.noise / double(s.noise_threshold);
            // Half a pass past the threshold on average: a pass spends at most the cost of
            // pass_spp() uniform samples per pixel, and the test comes after it.
            const double pass_cost = double(st.cost_budget) * double(pass_spp(s)) / double(s.spp);
            end = std::min(end, spent * ratio * ratio + 0.5 * pass_cost);
        }
        const double cost_left = std::max(0.0, end - spent);
        f.samples = spent > 0.0 ? cost_left * double(taken) / spent : 0.0;
        f.seconds = spent > 0.0 ? cost_left * seconds_so_far / spent : 0.0;
        return f;
    }
    f.seconds = f.samples * seconds_per_sample;
    return f;
}

} // namespace candela
