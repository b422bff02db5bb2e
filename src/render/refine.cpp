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
        throw Error(ErrorKind::Usage, "error: a refinement cannot lower -s (" +
                                          std::to_string(before.spp) + " to " +
                                          std::to_string(after.spp) + ")");
    // 0 is no threshold: the strictest.
    const bool stricter_or_same =
        after.adaptive_tol == 0.f || after.adaptive_tol <= before.adaptive_tol;
    if (after.adaptive == AdaptiveKind::Relative && !stricter_or_same)
        throw Error(ErrorKind::Usage, "error: a refinement cannot raise the noise threshold");
    const bool finished = st.finished(before.spp);
    if (!finished && after.spp == before.spp && after.adaptive_tol == before.adaptive_tol) return;
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
        if (std::all_of(st.done.begin(), st.done.end(), [](std::uint8_t d) { return d != 0; }))
            st.next_sample = after.spp;
        return;
    case AdaptiveKind::Relative:
        break;
    }
    if (pixels == 1) {
        // A lone pixel takes -s samples uniformly (Renderer: no neighbours to judge it by).
        st.next_sample = int(std::min<std::uint64_t>(samples_taken(st), std::uint64_t(after.spp)));
        return;
    }
    if (st.cost_budget == 0) return; // no pass has set the budget: the render starts afresh
    // The budget is -s uniform samples at the first pass's cost per sample: it scales with -s.
    if (after.spp != before.spp)
        st.cost_budget = std::uint64_t(
            std::llround(double(st.cost_budget) * double(after.spp) / double(before.spp)));
    // Progress counts the share of the budget spent, in samples per pixel of the new -s; a
    // render whose budget is spent stays finished.
    const std::uint64_t spent = spent_cost(st);
    if (spent >= st.cost_budget) {
        st.next_sample = after.spp;
        return;
    }
    const double share = double(spent) / double(st.cost_budget);
    st.next_sample = std::min(after.spp - 1, int(std::floor(share * double(after.spp))));
}

RefineForecast forecast_refinement(const RenderSettings& s, const RenderState& st,
                                   double seconds_so_far) {
    RefineForecast f;
    if (st.finished(s.spp)) return f;
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
        if (s.adaptive_tol > 0.f && f.noise > double(s.adaptive_tol)) {
            const double ratio = f.noise / double(s.adaptive_tol);
            // Half a pass past the threshold on average: a pass spends at most the cost of
            // pass_size() uniform samples per pixel, and the test comes after it.
            const double pass_cost = double(st.cost_budget) * double(pass_size(s)) / double(s.spp);
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
