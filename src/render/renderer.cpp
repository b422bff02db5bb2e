#include "candela/render/renderer.h"

#include "candela/render/adaptive.h"
#include "candela/render/integrator.h"
#include "candela/render/progress.h"
#include "candela/sampling/sampler.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <unistd.h>

namespace candela {

namespace {

/// Relative sampler: one pixel may take up to this many times the average budget (-s). Large
/// enough for caustics and edges to get the samples they need, small enough that a few
/// fireflies cannot swallow the frame's budget.
constexpr int kRelativeMaxOversampling = 8;
/// Relative sampler: neighbourhood radius of the smoothed error estimate (a 5x5 window), so
/// that a pixel's own samples weigh 1/25 in the decision about its budget.
constexpr int kRelativeSmoothRadius = 2;
/// Relative sampler: tile edge in pixels. Its per-pass work per pixel varies by up to
/// kRelativeMaxOversampling x, so tiles are smaller than kTileSize for load balance.
constexpr int kRelativeTileSize = 4;
/// Cost units of one camera sample, its camera ray included: seeding the sampler, the camera
/// ray and adding to the film. A sample whose camera ray misses everything or ends on an
/// emitter costs this alone.
constexpr std::uint64_t kSampleCost = 2;
/// Cost units of every ray query after the camera ray (bounce rays and shadow rays, each with
/// the shading, BSDF and light sampling around it). With kSampleCost, calibrated on CBbunny and
/// CBspheres_lambertian at 64x48 by timing each pixel's samples on one thread and fitting
/// ns/sample = a + b (queries - 1) over all pixels: a = 370, b = 890 ns, so b/a = 2.4; 5/2 is
/// the nearest small-integer ratio (docs/convergence.md). Integers keep the costs exact sums.
constexpr std::uint64_t kQueryCost = 5;

/// Luminance statistics of every pixel of a film with lum_stats, plus per-channel ones when it
/// keeps the variance channel; n counts sample indices used (finite plus dropped).
LumStatsMap lum_stats_map(const Film& film) {
    LumStatsMap m;
    m.width = film.width();
    m.height = film.height();
    const std::size_t P = film.pixel_count();
    m.mean.resize(P);
    m.var.resize(P);
    m.n.resize(P);
    for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x) {
            std::size_t i = std::size_t(y) * m.width + x;
            std::uint32_t n;
            film.lum_stats(x, y, m.mean[i], m.var[i], n);
            m.n[i] = n + film.dropped(x, y);
        }
    if (film.aovs().variance) {
        m.mean_rgb.resize(3 * P);
        m.var_rgb.resize(3 * P);
        for (int y = 0; y < m.height; ++y)
            for (int x = 0; x < m.width; ++x) {
                std::size_t i = std::size_t(y) * m.width + x;
                Rgb mu = film.mean(x, y), vm = film.variance_of_mean(x, y);
                const double n = double(film.count(x, y));
                for (int c = 0; c < 3; ++c) {
                    m.mean_rgb[3 * i + c] = mu[c];
                    m.var_rgb[3 * i + c] = double(vm[c]) * n; // variance of one sample
                }
            }
    }
    return m;
}

std::uint64_t total_cost(const std::vector<std::uint64_t>& cost) {
    std::uint64_t sum = 0;
    for (std::uint64_t c : cost)
        sum += c;
    return sum;
}

} // namespace

std::uint64_t cost_units(std::uint64_t queries, std::uint64_t samples) {
    // Every sample traces its camera ray, so queries >= samples.
    return kSampleCost * samples + kQueryCost * (queries - std::min(queries, samples));
}

Renderer::Renderer(const Scene& scene, const Accel& accel, const RenderSettings& settings)
    : scene_(scene), accel_(accel), s_(settings) {}

int Renderer::pass_size() const {
    // A pass is one adaptive batch, or a slice of the sample budget so that a stop request is
    // honoured, and a checkpoint written, within a fraction of the render.
    if (s_.adaptive != AdaptiveKind::None) return std::min(s_.spp, s_.adaptive_batch);
    if (s_.pass_spp > 0) return s_.pass_spp;
    return std::max(1, std::min(s_.spp, 16));
}

int Renderer::relative_max_per_pixel() const {
    return int(std::min<long long>((long long)s_.spp * kRelativeMaxOversampling, 1 << 24));
}

RenderState Renderer::start() const {
    RenderState st;
    const bool adaptive = s_.adaptive != AdaptiveKind::None;
    st.film = Film(film_width(), film_height(), s_.aovs, adaptive);
    st.done.assign(std::size_t(film_width()) * film_height(), 0);
    if (s_.adaptive == AdaptiveKind::Relative)
        st.cost.assign(std::size_t(film_width()) * film_height(), 0);
    return st;
}

Film Renderer::render(RenderStats& stats, const std::atomic<bool>* stop) const {
    RenderState st = start();
    run(st, stats, stop);
    return std::move(st.film);
}

void Renderer::run(RenderState& st, RenderStats& stats, const std::atomic<bool>* stop,
                   const std::function<void(const RenderState&)>& on_pass) const {
    auto t0 = std::chrono::steady_clock::now();
    const int fw = film_width(), fh = film_height();
    const int x0 = s_.region.full() ? 0 : s_.region.x;
    const int y0 = s_.region.full() ? 0 : s_.region.y;
    const bool adaptive = s_.adaptive != AdaptiveKind::None;
    Film& film = st.film;
    std::vector<std::uint8_t>& done = st.done;
    Integrator integrator(scene_, accel_, s_);

    // The relative sampler concentrates samples in few pixels: smaller tiles keep the load
    // balanced. Tiling never changes the image (each pixel's samples are its own).
    const int tile_edge = s_.adaptive == AdaptiveKind::Relative ? kRelativeTileSize : kTileSize;
    const int tiles_x = (fw + tile_edge - 1) / tile_edge;
    const int tiles_y = (fh + tile_edge - 1) / tile_edge;
    const int tile_count = tiles_x * tiles_y;
    const int step = pass_size();
    std::atomic<std::uint64_t> rays{0}, shadow_rays{0}, dropped{0}, samples{0};

    std::unique_ptr<tbb::global_control> limit;
    if (s_.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(s_.threads));

    const std::uint64_t remaining =
        std::uint64_t(fw) * fh * std::uint64_t(std::max(0, s_.spp - st.next_sample));
    Progress progress(remaining, resolve_progress_mode(s_.progress, s_.quiet || !verbose()));
    const bool relative = s_.adaptive == AdaptiveKind::Relative;
    const std::uint64_t pixel_count = std::uint64_t(fw) * fh;
    std::vector<int> alloc; // relative sampler: samples of each pixel in this pass
    if (relative && st.cost.size() != pixel_count) {
        if (film.total_samples() + film.total_dropped() > 0)
            throw Error(ErrorKind::Usage, "error: the relative adaptive sampler cannot continue "
                                          "a render whose state has no per-pixel costs");
        st.cost.assign(pixel_count, 0);
    }
    std::vector<std::uint64_t>& cost = st.cost;
    int passes = 0;
    while (!st.finished(s_.spp)) {
        if (stop && stop->load()) {
            stats.interrupted = true;
            break;
        }
        // The time budget is checked between whole passes, after at least one.
        if (s_.time_budget > 0.0 && passes > 0 &&
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >=
                s_.time_budget) {
            stats.out_of_time = true;
            break;
        }
        const int first = st.next_sample;
        const int last = std::min(s_.spp, first + step);
        if (relative) {
            // The allocation depends only on the film and the recorded costs, so it is the same
            // for any thread count and after a resume. The budget is in cost units (renderer.h);
            // every pass after the first may spend what a uniform pass of `step` samples per
            // pixel costs.
            const std::uint64_t taken = film.total_samples() + film.total_dropped();
            if (taken == 0 || st.cost_budget == 0) {
                alloc.assign(pixel_count, step);
            } else {
                const std::uint64_t spent = total_cost(cost);
                const double uniform_pass = double(st.cost_budget) * double(step) / double(s_.spp);
                const double budget = std::min(
                    double(st.cost_budget - std::min(st.cost_budget, spent)), uniform_pass);
                LumStatsMap m = lum_stats_map(film);
                alloc = allocate_pass(m, relative_error_map(m, kRelativeSmoothRadius),
                                      cost_per_sample_map(m, cost, kRelativeSmoothRadius), budget,
                                      relative_max_per_pixel());
            }
        }
        std::atomic<int> active{0};
        tbb::parallel_for(
            tbb::blocked_range<int>(0, tile_count), [&](const tbb::blocked_range<int>& r) {
                TraceCounters counters;
                std::uint64_t local_samples = 0, local_dropped = 0;
                Sampler sampler(s_.sampler, s_.seed);
                for (int tile = r.begin(); tile < r.end(); ++tile) {
                    int tx = (tile % tiles_x) * tile_edge, ty = (tile / tiles_x) * tile_edge;
                    int ex = std::min(fw, tx + tile_edge), ey = std::min(fh, ty + tile_edge);
                    std::uint64_t tile_samples = 0;
                    for (int y = ty; y < ey; ++y)
                        for (int x = tx; x < ex; ++x) {
                            std::size_t pi = std::size_t(y) * fw + x;
                            if (done[pi]) continue;
                            const int px = x0 + x, py = y0 + y;
                            // Sample indices of this pixel in this pass: a contiguous range, so
                            // index k of a pixel always gets the same numbers.
                            int k0 = first, k1 = last;
                            if (relative) {
                                k0 = int(film.count(x, y) + film.dropped(x, y));
                                k1 = k0 + alloc[pi];
                            }
                            const std::uint64_t queries0 = counters.rays + counters.shadow_rays;
                            for (int k = k0; k < k1; ++k) {
                                sampler.start(std::uint32_t(px), std::uint32_t(py),
                                              s_.sample_offset + std::uint64_t(k));
                                Vec2 u = sampler.get_2d();
                                FilmSample fs = integrator.estimate(
                                    float(px) + u.x, float(py) + u.y, sampler, counters);
                                if (is_finite(fs.L))
                                    film.add(x, y, fs);
                                else {
                                    film.add_dropped(x, y);
                                    ++local_dropped;
                                }
                            }
                            tile_samples += std::uint64_t(k1 - k0);
                            if (relative)
                                cost[pi] +=
                                    cost_units(counters.rays + counters.shadow_rays - queries0,
                                               std::uint64_t(k1 - k0));
                            if (s_.adaptive == AdaptiveKind::Cs184 && last < s_.spp) {
                                double mean, var;
                                std::uint32_t n;
                                film.lum_stats(x, y, mean, var, n);
                                if (cs184_converged(mean, var, n, s_.adaptive_tol)) done[pi] = 1;
                            }
                            if (!done[pi]) active.fetch_add(1, std::memory_order_relaxed);
                        }
                    local_samples += tile_samples;
                    progress.add(tile_samples);
                }
                rays += counters.rays;
                shadow_rays += counters.shadow_rays;
                samples += local_samples;
                dropped += local_dropped;
            });
        ++passes;
        ++st.passes;
        st.next_sample = last;
        // Every pixel has converged: nothing is left to render.
        if (adaptive && !relative && active.load() == 0) st.next_sample = s_.spp;
        if (relative) {
            // After the first (uniform) pass the budget is fixed: what spp uniform samples per
            // pixel cost at that pass's mean cost per sample. next_sample is the share of the
            // budget spent so far, in samples per pixel; the render ends when the budget is
            // spent, nothing more can be gained (no allocation), or the estimated relative RMS
            // error of the image reaches the tolerance.
            const std::uint64_t taken = film.total_samples() + film.total_dropped();
            const std::uint64_t spent = total_cost(cost);
            if (st.cost_budget == 0)
                st.cost_budget = std::uint64_t(std::llround(double(spent) / double(taken) *
                                                            double(s_.spp) * double(pixel_count)));
            std::uint64_t allocated = 0;
            for (int a : alloc)
                allocated += std::uint64_t(a);
            LumStatsMap m = lum_stats_map(film);
            const double err = estimated_relative_rms(m, relative_error_map(m, 0));
            const double share = double(spent) / double(st.cost_budget);
            st.next_sample = int(std::min(double(s_.spp), std::floor(share * double(s_.spp))));
            if (spent >= st.cost_budget || allocated == 0 || err <= s_.adaptive_tol)
                st.next_sample = s_.spp;
        }
        if (on_pass) on_pass(st);
    }
    progress.finish();
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    stats.samples = samples;
    stats.rays = rays;
    stats.shadow_rays = shadow_rays;
    stats.dropped = dropped;
    stats.passes = passes;
}

} // namespace candela
