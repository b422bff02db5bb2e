#include "candela/render/renderer.h"

#include "candela/render/integrator.h"
#include "candela/sampling/sampler.h"
#include "candela/util/log.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <unistd.h>

namespace candela {

namespace {

/// z-value of the CS184 adaptive criterion: a 95% confidence half-width (spec §5.4).
constexpr double kConfidenceZ = 1.96;

/// Prints progress on stderr from its own thread: a bar with ETA on a terminal, a line every
/// few seconds otherwise.
class Progress {
  public:
    Progress(std::uint64_t total, bool enabled) : total_(total), enabled_(enabled) {
        if (!enabled_) return;
        tty_ = ::isatty(2) != 0;
        start_ = std::chrono::steady_clock::now();
        thread_ = std::thread([this] { loop(); });
    }
    ~Progress() { finish(); }
    void add(std::uint64_t n) { done_.fetch_add(n, std::memory_order_relaxed); }
    void finish() {
        if (!enabled_ || !thread_.joinable()) return;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
        }
        cv_.notify_all();
        thread_.join();
        print(true);
    }

  private:
    void loop() {
        std::unique_lock<std::mutex> lock(mutex_);
        auto period = tty_ ? std::chrono::milliseconds(250) : std::chrono::milliseconds(10000);
        while (!cv_.wait_for(lock, period, [this] { return stop_; }))
            print(false);
    }
    void print(bool final) {
        double frac = total_ ? std::min(1.0, double(done_.load()) / double(total_)) : 1.0;
        double el =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        double eta = frac > 0.0 ? el * (1.0 - frac) / frac : 0.0;
        if (tty_) {
            const int width = 40;
            int fill = int(frac * width);
            std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  %6.1fs elapsed  ETA %6.1fs", fill,
                         "========================================", width - fill, "", 100.0 * frac,
                         el, eta);
            if (final) std::fprintf(stderr, "\n");
        } else if (!final) {
            std::fprintf(stderr, "progress: %5.1f%%  %.1fs elapsed  ETA %.1fs\n", 100.0 * frac, el,
                         eta);
        }
        std::fflush(stderr);
    }

    std::uint64_t total_;
    bool enabled_;
    bool tty_ = false;
    std::atomic<std::uint64_t> done_{0};
    std::chrono::steady_clock::time_point start_;
    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
};

} // namespace

Renderer::Renderer(const Scene& scene, const Accel& accel, const RenderSettings& settings)
    : scene_(scene), accel_(accel), s_(settings) {}

int Renderer::pass_size() const {
    // A pass is one adaptive batch, or a slice of the sample budget so that a stop request is
    // honoured, and a checkpoint written, within a fraction of the render.
    if (s_.adaptive != AdaptiveKind::None) return s_.adaptive_batch;
    if (s_.pass_spp > 0) return s_.pass_spp;
    return std::max(1, std::min(s_.spp, 16));
}

RenderState Renderer::start() const {
    RenderState st;
    const bool adaptive = s_.adaptive != AdaptiveKind::None;
    st.film = Film(film_width(), film_height(), s_.aovs, adaptive);
    st.done.assign(std::size_t(film_width()) * film_height(), 0);
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

    const int tiles_x = (fw + kTileSize - 1) / kTileSize;
    const int tiles_y = (fh + kTileSize - 1) / kTileSize;
    const int tile_count = tiles_x * tiles_y;
    const int step = pass_size();
    std::atomic<std::uint64_t> rays{0}, shadow_rays{0}, dropped{0}, samples{0};

    std::unique_ptr<tbb::global_control> limit;
    if (s_.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(s_.threads));

    const std::uint64_t remaining =
        std::uint64_t(fw) * fh * std::uint64_t(std::max(0, s_.spp - st.next_sample));
    Progress progress(remaining, !s_.quiet && verbose());
    int passes = 0;
    while (!st.finished(s_.spp)) {
        if (stop && stop->load()) {
            stats.interrupted = true;
            break;
        }
        const int first = st.next_sample;
        const int last = std::min(s_.spp, first + step);
        std::atomic<int> active{0};
        tbb::parallel_for(
            tbb::blocked_range<int>(0, tile_count), [&](const tbb::blocked_range<int>& r) {
                TraceCounters counters;
                std::uint64_t local_samples = 0, local_dropped = 0;
                Sampler sampler(s_.sampler, s_.seed);
                for (int tile = r.begin(); tile < r.end(); ++tile) {
                    int tx = (tile % tiles_x) * kTileSize, ty = (tile / tiles_x) * kTileSize;
                    int ex = std::min(fw, tx + kTileSize), ey = std::min(fh, ty + kTileSize);
                    std::uint64_t tile_samples = 0;
                    for (int y = ty; y < ey; ++y)
                        for (int x = tx; x < ex; ++x) {
                            std::size_t pi = std::size_t(y) * fw + x;
                            if (done[pi]) continue;
                            const int px = x0 + x, py = y0 + y;
                            for (int k = first; k < last; ++k) {
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
                            tile_samples += std::uint64_t(last - first);
                            if (adaptive && last < s_.spp) {
                                double mean, var;
                                std::uint32_t n;
                                film.lum_stats(x, y, mean, var, n);
                                if (n >= 2) {
                                    double half_width = kConfidenceZ * std::sqrt(var / n);
                                    if (half_width <= s_.adaptive_tol * mean) done[pi] = 1;
                                }
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
        if (adaptive && active.load() == 0) st.next_sample = s_.spp;
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
