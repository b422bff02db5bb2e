// The pass loop: tiles of pixels in parallel, passes of samples, adaptive stopping, one rank or
// many.
#include "candela/render/renderer.h"

#include "candela/render/adaptive.h"
#include "candela/render/distributed.h"
#include "candela/render/integrator.h"
#include "candela/render/progress.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/sampler.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/stopwatch.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace candela {

namespace {

/// Relative sampler: neighbourhood radius of the error and cost estimates (a 5x5 window without
/// its centre: 24 neighbours decide a pixel's budget, its own samples do not).
constexpr int kRelativeSmoothRadius = 2;
/// Relative sampler: separates the hash stream of the allocation's rounding (seeded by the render
/// seed and the pass) from the samplers' streams.
constexpr std::uint64_t kRoundingSalt = 0x524f554e44ULL;
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
/// keeps the variance channel; n counts sample indices used (finite plus dropped). Fills m in
/// place: a map of the same film size keeps its storage from pass to pass.
void fill_lum_stats(const Film& film, LumStatsMap& m) {
    m.width = film.width();
    m.height = film.height();
    const std::size_t P = film.pixel_count();
    m.mean.resize(P);
    m.var.resize(P);
    m.n.resize(P);
    const bool rgb = film.aovs().variance;
    m.mean_rgb.resize(rgb ? 3 * P : 0);
    m.var_rgb.resize(rgb ? 3 * P : 0);
    // Each pixel's statistics from its own sums: rows in parallel, the same values for any split.
    tbb::parallel_for(tbb::blocked_range<int>(0, m.height), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y < r.end(); ++y)
            for (int x = 0; x < m.width; ++x) {
                const std::size_t i = std::size_t(y) * m.width + x;
                std::uint32_t n;
                film.lum_stats(x, y, m.mean[i], m.var[i], n);
                m.n[i] = n + film.dropped(x, y);
                if (!rgb) continue;
                const Rgb mu = film.mean(x, y), vm = film.variance_of_mean(x, y);
                const double count = double(film.count(x, y));
                for (int c = 0; c < 3; ++c) {
                    m.mean_rgb[3 * i + c] = mu[c];
                    m.var_rgb[3 * i + c] = double(vm[c]) * count; // variance of one sample
                }
            }
    });
}

/// Most camera samples the integrator renders in one batch: enough for Embree's stream
/// traversal to form full packets and for the shading loop to run long, few enough that the
/// batch's path state (about 250 bytes a path, with its queued shadow rays) stays in the
/// second-level cache.
constexpr std::size_t kMaxBatch = 2048;

/// One pixel's share of a run's batch.
struct RunPixel {
    int x, y;  ///< film coordinates
    int count; ///< its samples in this pass
};

/// A task of a pass: the pixels at positions [begin, end) of the pass order (pass_order()).
struct PassRun {
    std::uint32_t begin, end;
};

/// The order in which a pass visits the pixels of a w x h film: kTileSize x kTileSize tiles row
/// by row, each tile's pixels row by row. A run of this order is a compact patch of the image,
/// so a batch's camera rays are coherent. Returns the pixel indices (y w + x) in that order.
std::vector<std::uint32_t> pass_order(int w, int h) {
    std::vector<std::uint32_t> order;
    order.reserve(std::size_t(w) * std::size_t(h));
    for (int ty = 0; ty < h; ty += kTileSize)
        for (int tx = 0; tx < w; tx += kTileSize)
            for (int y = ty; y < std::min(h, ty + kTileSize); ++y)
                for (int x = tx; x < std::min(w, tx + kTileSize); ++x)
                    order.push_back(std::uint32_t(std::size_t(y) * std::size_t(w) + x));
    return order;
}

/// Cuts the pass order into runs of about kMaxBatch samples (`count(pixel)` each): no run
/// exceeds kMaxBatch unless one pixel alone does, so the integrator's batches are full however
/// the samples are spread over the pixels (the relative sampler's passes give most pixels few
/// or none). A pixel's samples stay in one run: one thread adds them to the film, in index
/// order. Runs of pixels without samples are left out.
template <class Count>
void cut_runs(const std::vector<std::uint32_t>& order, const Count& count,
              std::vector<PassRun>& runs) {
    runs.clear();
    std::uint32_t begin = 0;
    std::size_t samples = 0;
    for (std::uint32_t pos = 0; pos < order.size(); ++pos) {
        const std::size_t n = std::size_t(count(order[pos]));
        if (n == 0) {
            if (samples == 0) begin = pos + 1; // a run starts at its first pixel with samples
            continue;
        }
        if (samples > 0 && samples + n > kMaxBatch) {
            runs.push_back({begin, pos});
            begin = pos;
            samples = 0;
        }
        samples += n;
    }
    if (samples > 0) runs.push_back({begin, std::uint32_t(order.size())});
}

/// Totals of one render over its passes (summed from the threads' counters).
struct PassCounters {
    std::atomic<std::uint64_t> samples{0}, camera_rays{0}, rays{0}, shadow_rays{0}, dropped{0};
};

/// What a thread keeps from run to run, so that the render loop does not allocate.
struct RunBuffers {
    std::vector<SampleRequest> requests;
    std::vector<SampleResult> results;
    std::vector<RunPixel> pixels;
    BatchWorkspace workspace;
};

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

namespace {

/// The group of one process: nothing to communicate.
class SingleProcess final : public RenderGroup {
  public:
    int rank() const override { return 0; }
    int size() const override { return 1; }
    void reduce_film(Film&) const override {}
    bool any(bool flag) const override { return flag; }
    void reduce_counters(std::vector<std::uint64_t>&) const override {}
    void broadcast(std::vector<std::uint8_t>&) const override {}
};

template <typename T> std::vector<std::uint8_t> to_bytes(const std::vector<T>& v) {
    std::vector<std::uint8_t> b(v.size() * sizeof(T));
    if (!b.empty()) std::memcpy(b.data(), v.data(), b.size());
    return b;
}

template <typename T> void from_bytes(const std::vector<std::uint8_t>& b, std::vector<T>& v) {
    v.resize(b.size() / sizeof(T));
    if (!b.empty()) std::memcpy(v.data(), b.data(), b.size());
}

} // namespace

const RenderGroup& single_process() {
    static const SingleProcess group;
    return group;
}

/// One render's pass loop: what a pass renders (the plan), the pass over the tiles, and the
/// decisions between passes, for one process or for every rank of a group.
///
/// Films and costs: each rank renders its share of every pixel's sample range into its own film
/// (`local`), the root's starting from the film of a resumed render. The state's film and costs
/// are the group's: with one process they are the local ones themselves; in a group the root's
/// are the sums over the ranks, refreshed after every pass that decides something (adaptive
/// sampling, a checkpoint, the end).
namespace {

class PassLoop {
  public:
    PassLoop(const Renderer& r, const Scene& scene, const Accel& accel, const RenderSettings& s,
             RenderState& st, const RenderGroup& group)
        : r_(r), s_(s), st_(st), group_(group), fw_(r.film_width()), fh_(r.film_height()),
          pixels_(std::size_t(fw_) * fh_), integrator_(scene, accel, s),
          order_(pass_order(fw_, fh_)) {
        if (s_.adaptive == AdaptiveKind::Relative && st_.cost.size() != pixels_) {
            if (st_.film.total_samples() + st_.film.total_dropped() > 0)
                throw Error(ErrorKind::Usage,
                            "the relative adaptive sampler cannot continue a render whose "
                            "state has no per-pixel costs");
            st_.cost.assign(pixels_, 0);
        }
        if (group_.size() > 1) {
            // The root's own samples start from the resumed film; the others' from nothing.
            own_film_ = group_.root() ? st_.film : r_.start().film;
            if (relative())
                own_cost_ = group_.root() ? st_.cost : std::vector<std::uint64_t>(pixels_, 0);
            local_film_ = &own_film_;
            local_cost_ = &own_cost_;
        } else {
            local_film_ = &st_.film;
            local_cost_ = &st_.cost;
        }
        if (relative()) start_indices();
    }

    bool relative() const { return s_.adaptive == AdaptiveKind::Relative; }
    /// Relative sampler on a film of one pixel (a 1x1 region): with no neighbours to judge it by,
    /// its error estimate would be 0 and the render would end after the first pass. It takes -s
    /// samples instead, uniformly, and no noise threshold ends it (its own samples would decide
    /// their own count, the stopping rule the neighbour estimate exists to avoid).
    bool lone_pixel() const { return relative() && pixels_ == 1; }
    bool cs184() const { return s_.adaptive == AdaptiveKind::Cs184; }

    /// The sample range of every pixel in the next pass: [first, last) for all pixels not done,
    /// or (relative sampler) the allocation after each pixel's samples so far.
    void plan(int& first, int& last) {
        first = st_.next_sample;
        const int step = r_.pass_size();
        // Without adaptive decisions every rank renders a whole single-process pass of its own;
        // with them a pass is one batch, split among the ranks.
        const int width = s_.adaptive == AdaptiveKind::None ? step * group_.size() : step;
        last = std::min(s_.spp, first + width);
        if (!relative()) return;
        if (lone_pixel()) {
            alloc_.assign(pixels_, std::max(0, std::min(step, s_.spp - int(next_index_[0]))));
            return;
        }
        if (st_.cost_budget == 0) {
            alloc_.assign(pixels_, step); // the first pass is uniform and sets the budget
            return;
        }
        if (group_.root()) {
            // Depends only on the film and the recorded costs: the same for any thread count,
            // rank count and after a resume. Every pass after the first may spend what a uniform
            // pass of `step` samples per pixel costs.
            const std::uint64_t spent = total_cost(st_.cost);
            const double uniform_pass = double(st_.cost_budget) * double(step) / double(s_.spp);
            const double budget =
                std::min(double(st_.cost_budget - std::min(st_.cost_budget, spent)), uniform_pass);
            const LumStatsMap& m = film_stats();
            // Each pixel's share comes from its neighbours' samples, never its own
            // (adaptive.h): its count is then independent of the values it averages.
            alloc_ = allocate_pass(
                m, relative_error_map(m, kRelativeSmoothRadius, WindowCentre::Exclude),
                cost_per_sample_map(m, st_.cost, kRelativeSmoothRadius, WindowCentre::Exclude),
                budget, r_.relative_max_per_pixel(),
                hash_combine(s_.seed, kRoundingSalt, std::uint64_t(st_.passes)));
        }
        if (group_.size() > 1) {
            std::vector<std::uint8_t> bytes = to_bytes(alloc_);
            bytes.resize(pixels_ * sizeof(int));
            group_.broadcast(bytes);
            from_bytes(bytes, alloc_);
        }
    }

    /// The statistics of the (group's) film, computed once per pass: the decision after a pass
    /// and the plan of the next read the same film.
    const LumStatsMap& film_stats() {
        if (!stats_current_) {
            fill_lum_stats(st_.film, stats_);
            stats_current_ = true;
        }
        return stats_;
    }

    /// This rank's sample indices of pixel `pixel` (its index y w + x) in pass [first, last): a
    /// contiguous range, so index k of a pixel always gets the same numbers (relative sampler:
    /// the pixel's allocation after the samples it has); this rank takes its block of it. Empty
    /// for a stopped pixel.
    SampleBlock pixel_block(std::size_t pixel, int first, int last) const {
        if (st_.done[pixel]) return {};
        int k0 = first, k1 = last;
        if (relative()) {
            k0 = int(next_index_[pixel]);
            k1 = k0 + alloc_[pixel];
        }
        return rank_block(k0, k1, group_.rank(), group_.size());
    }

    /// Renders this rank's share of the planned samples of every pixel into the local film.
    void execute(int first, int last, Progress& progress, PassCounters& totals) {
        stats_current_ = false;
        cut_runs(
            order_, [&](std::uint32_t pixel) { return pixel_block(pixel, first, last).size(); },
            runs_);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs_.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              TraceCounters counters;
                              std::uint64_t samples = 0, dropped = 0;
                              RunBuffers& buf = run_buffers_.local();
                              for (std::size_t k = r.begin(); k < r.end(); ++k) {
                                  const std::uint64_t n =
                                      render_run(runs_[k], first, last, buf, counters, dropped);
                                  samples += n;
                                  // Every rank renders about as much: the root's progress stands
                                  // for all.
                                  progress.add(n * std::uint64_t(group_.size()));
                              }
                              totals.camera_rays += counters.camera_rays;
                              totals.rays += counters.rays;
                              totals.shadow_rays += counters.shadow_rays;
                              totals.samples += samples;
                              totals.dropped += dropped;
                          });
    }

    /// Makes the state's film and costs the group's (a no-op for one process).
    void sync() {
        if (group_.size() == 1) return;
        stats_current_ = false;
        st_.film = *local_film_;
        group_.reduce_film(st_.film);
        if (relative()) {
            std::vector<std::uint64_t> cost = *local_cost_;
            group_.reduce_counters(cost);
            if (group_.root()) st_.cost = std::move(cost);
        }
        synced_ = true;
    }

    /// The decisions after pass [first, last): which pixels the CS184 criterion stops, and
    /// whether the relative sampler is done. Made on the root's (group) film and shared.
    void decide(int first, int last) {
        (void)first;
        st_.next_sample = last;
        if (cs184()) {
            if (last < s_.spp && group_.root())
                for (int y = 0; y < fh_; ++y)
                    for (int x = 0; x < fw_; ++x) {
                        const std::size_t pixel = std::size_t(y) * fw_ + x;
                        if (!st_.done[pixel] &&
                            adaptive_pixel_converged(st_.film, x, y, s_.adaptive_tol))
                            st_.done[pixel] = 1;
                    }
            if (group_.size() > 1) group_.broadcast(st_.done);
            // Every pixel has converged: nothing is left to render.
            if (std::all_of(st_.done.begin(), st_.done.end(),
                            [](std::uint8_t d) { return d != 0; }))
                st_.next_sample = s_.spp;
        }
        if (relative()) decide_relative();
    }

    void decide_relative() {
        for (std::size_t i = 0; i < pixels_; ++i)
            next_index_[i] += std::uint32_t(alloc_[i]);
        bool finished = false;
        if (group_.root()) {
            // After the first (uniform) pass the budget is fixed: what spp uniform samples per
            // pixel cost at that pass's mean cost per sample. next_sample is the share of the
            // budget spent so far, in samples per pixel; the render ends when the budget is
            // spent, nothing more can be gained (no allocation), or the estimated relative RMS
            // error of the image reaches the tolerance.
            const std::uint64_t taken = st_.film.total_samples() + st_.film.total_dropped();
            const std::uint64_t spent = total_cost(st_.cost);
            if (st_.cost_budget == 0)
                st_.cost_budget = std::uint64_t(
                    std::llround(double(spent) / double(taken) * double(s_.spp) * double(pixels_)));
            std::uint64_t allocated = 0;
            for (int a : alloc_)
                allocated += std::uint64_t(a);
            const LumStatsMap& m = film_stats();
            const double err =
                estimated_relative_rms(m, relative_error_map(m, 0, WindowCentre::Include));
            const double share = double(spent) / double(st_.cost_budget);
            st_.next_sample = int(std::min(double(s_.spp), std::floor(share * double(s_.spp))));
            finished = spent >= st_.cost_budget || allocated == 0 || err <= s_.adaptive_tol;
            outlook_ = {err, share, spent, taken,
                        err <= s_.adaptive_tol     ? StopReason::NoiseThreshold
                        : spent >= st_.cost_budget ? StopReason::BudgetSpent
                        : allocated == 0           ? StopReason::NothingToGain
                                                   : StopReason::AllSamples};
            if (lone_pixel()) {
                st_.next_sample = int(std::min(next_index_[0], std::uint32_t(s_.spp)));
                finished = next_index_[0] >= std::uint32_t(s_.spp);
                outlook_.stop = StopReason::BudgetSpent;
            }
        }
        if (group_.size() > 1) {
            // Every rank needs the budget (the next plan tests it) and the verdict.
            std::vector<std::uint64_t> shared = {st_.cost_budget, std::uint64_t(st_.next_sample)};
            std::vector<std::uint8_t> bytes = to_bytes(shared);
            group_.broadcast(bytes);
            from_bytes(bytes, shared);
            st_.cost_budget = shared[0];
            st_.next_sample = int(shared[1]);
            finished = group_.any(finished);
        }
        if (finished) st_.next_sample = s_.spp;
    }

    /// Relative sampler, on the root: where the render stood after the last decision.
    struct Outlook {
        double error = -1.0;                      ///< estimated relative RMS error of the image
        double share = 0.0;                       ///< of the cost budget spent
        std::uint64_t spent = 0;                  ///< cost units spent
        std::uint64_t taken = 0;                  ///< samples taken
        StopReason stop = StopReason::AllSamples; ///< what ended the render, if it ended
    };
    const Outlook& outlook() const { return outlook_; }

    /// An estimate of the samples (of the group) still to come. Relative sampler: the error
    /// falls as 1/sqrt(cost), so the threshold is reached at about spent (error/threshold)^2,
    /// or the budget ends the render first. cs184: every pixel that has not converged takes
    /// the rest of its samples (the most it can).
    std::uint64_t samples_left() const {
        const std::uint64_t left_per_pixel = std::uint64_t(std::max(0, s_.spp - st_.next_sample));
        if (lone_pixel()) return std::uint64_t(std::max(0, s_.spp - int(next_index_[0])));
        if (relative()) {
            const Outlook& o = outlook_;
            if (o.spent == 0 || o.taken == 0) return pixels_ * left_per_pixel;
            double end = double(st_.cost_budget);
            if (s_.adaptive_tol > 0.0 && o.error > 0.0)
                end = std::min(end, double(o.spent) * (o.error / s_.adaptive_tol) *
                                        (o.error / s_.adaptive_tol));
            const double cost_left = std::max(0.0, end - double(o.spent));
            return std::uint64_t(cost_left * double(o.taken) / double(o.spent));
        }
        if (cs184())
            return left_per_pixel * std::uint64_t(std::count(st_.done.begin(), st_.done.end(), 0));
        return pixels_ * left_per_pixel;
    }

    /// Whether the state's film is the group's after the last pass.
    bool synced() const { return synced_ || group_.size() == 1; }
    void mark_unsynced() { synced_ = false; }

  private:
    /// Renders one run's samples, pixel by pixel in the pass order and each pixel's in index
    /// order (one pixel's camera rays next to each other), and adds them to the local film and
    /// costs: the film's sums are added in index order whatever the runs. Returns the samples
    /// rendered; adds the non-finite ones dropped to `dropped`.
    std::uint64_t render_run(const PassRun& run, int first, int last, RunBuffers& buf,
                             TraceCounters& counters, std::uint64_t& dropped) {
        const int x0 = s_.region.full() ? 0 : s_.region.x;
        const int y0 = s_.region.full() ? 0 : s_.region.y;
        buf.requests.clear();
        buf.pixels.clear();
        for (std::uint32_t pos = run.begin; pos < run.end; ++pos) {
            const std::uint32_t pixel = order_[pos];
            const SampleBlock b = pixel_block(pixel, first, last);
            if (b.size() == 0) continue;
            const int x = int(pixel % std::uint32_t(fw_)), y = int(pixel / std::uint32_t(fw_));
            for (int k = b.first; k < b.last; ++k)
                buf.requests.push_back(SampleRequest{std::uint32_t(x0 + x), std::uint32_t(y0 + y),
                                                     s_.sample_offset + std::uint64_t(k)});
            buf.pixels.push_back({x, y, b.size()});
        }
        const std::size_t n = buf.requests.size();
        if (buf.results.size() < n) buf.results.resize(n);
        for (std::size_t b = 0; b < n; b += kMaxBatch)
            integrator_.render(buf.requests.data() + b, std::min(kMaxBatch, n - b),
                               buf.results.data() + b, buf.workspace, counters);
        Film& film = *local_film_;
        std::size_t next = 0;
        for (const RunPixel& tp : buf.pixels) {
            const SampleResult* res = buf.results.data() + next;
            next += std::size_t(tp.count);
            dropped += film.add_samples(tp.x, tp.y, tp.count,
                                        [res](int k) -> const FilmSample& { return res[k].fs; });
            if (!relative()) continue;
            std::uint64_t queries = 0;
            for (int k = 0; k < tp.count; ++k)
                queries += res[k].queries;
            (*local_cost_)[std::size_t(tp.y) * fw_ + tp.x] +=
                cost_units(queries, std::uint64_t(tp.count));
        }
        return n;
    }

    /// Relative sampler: each pixel's samples so far (the group's), known to every rank.
    void start_indices() {
        next_index_.assign(pixels_, 0);
        if (group_.root())
            for (int y = 0; y < fh_; ++y)
                for (int x = 0; x < fw_; ++x)
                    next_index_[std::size_t(y) * fw_ + x] =
                        st_.film.count(x, y) + st_.film.dropped(x, y);
        if (group_.size() > 1) {
            std::vector<std::uint8_t> bytes = to_bytes(next_index_);
            group_.broadcast(bytes);
            from_bytes(bytes, next_index_);
        }
    }

    const Renderer& r_;
    const RenderSettings& s_;
    RenderState& st_;
    const RenderGroup& group_;
    const int fw_, fh_;
    const std::size_t pixels_;
    Integrator integrator_;
    const std::vector<std::uint32_t> order_; ///< pass_order() of the film
    std::vector<PassRun> runs_;              ///< the tasks of the current pass
    tbb::enumerable_thread_specific<RunBuffers> run_buffers_;
    Film own_film_;                       ///< in a group: this rank's own samples
    std::vector<std::uint64_t> own_cost_; ///< in a group: the costs of this rank's samples
    Film* local_film_ = nullptr;
    std::vector<std::uint64_t>* local_cost_ = nullptr;
    std::vector<int> alloc_;                ///< relative sampler: samples per pixel this pass
    std::vector<std::uint32_t> next_index_; ///< relative sampler: each pixel's next index
    bool synced_ = false;
    Outlook outlook_;
    LumStatsMap stats_;          ///< film_stats(): the film's statistics ...
    bool stats_current_ = false; ///< ... while no pass has changed it
};

} // namespace

/// What ended a render, once its loop is over.
StopReason Renderer::stop_reason(const RenderStats& stats, const RenderState& st,
                                 StopReason relative_stop) const {
    if (stats.interrupted) return StopReason::Interrupted;
    if (stats.out_of_time) return StopReason::TimeBudget;
    if (s_.adaptive == AdaptiveKind::Relative) return relative_stop;
    if (s_.adaptive == AdaptiveKind::Cs184 &&
        std::all_of(st.done.begin(), st.done.end(), [](std::uint8_t d) { return d != 0; }))
        return StopReason::Converged;
    return StopReason::AllSamples;
}

void Renderer::run(RenderState& st, RenderStats& stats, const std::atomic<bool>* stop,
                   const std::function<void(const RenderState&)>& on_pass,
                   const RenderGroup& group) const {
    const Stopwatch timer;
    std::unique_ptr<tbb::global_control> limit;
    if (s_.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(s_.threads));
    PassLoop loop(*this, scene_, accel_, s_, st, group);
    const std::uint64_t remaining = std::uint64_t(film_width()) * film_height() *
                                    std::uint64_t(std::max(0, s_.spp - st.next_sample));
    // The root reports for the group; quiet silences all but an explicit JSON progress.
    Progress progress(remaining,
                      group.root() ? resolve_progress_mode(s_.progress, s_.quiet || !verbose())
                                   : ProgressMode::None,
                      s_.time_budget);
    PassCounters totals;
    int passes = 0;
    double busy = 0.0; // seconds this rank spent rendering its blocks (load balance)
    while (!st.finished(s_.spp)) {
        if (group.any(stop && stop->load())) {
            stats.interrupted = true;
            break;
        }
        // The time budget is the root's clock, checked between whole passes, after at least one.
        const double elapsed = timer.seconds();
        if (group.any(group.root() && s_.time_budget > 0.0 && passes > 0 &&
                      elapsed >= s_.time_budget)) {
            stats.out_of_time = true;
            break;
        }
        int first = 0, last = 0;
        loop.plan(first, last);
        const Stopwatch pass_clock;
        loop.execute(first, last, progress, totals);
        busy += pass_clock.seconds();
        loop.mark_unsynced();
        ++passes;
        ++st.passes;
        const bool adaptive = s_.adaptive != AdaptiveKind::None;
        // Decisions and checkpoints need the group's film; so does the end of the render.
        if (adaptive || on_pass || last >= s_.spp) loop.sync();
        loop.decide(first, last);
        if (group.root()) progress.retarget(progress.done() + loop.samples_left());
        if (on_pass && group.root()) on_pass(st);
    }
    if (!loop.synced()) loop.sync();
    stats.stop = stop_reason(stats, st, loop.outlook().stop);
    stats.estimated_error = loop.outlook().error;
    stats.budget_spent = loop.outlook().share;
    if (stats.stop != StopReason::Interrupted) progress.complete();
    progress.finish();
    // Counters summed over the ranks onto the root; each rank's busy time in microseconds in a
    // slot of its own.
    constexpr std::size_t kBusySlot = 5;
    std::vector<std::uint64_t> counters = {totals.samples, totals.camera_rays, totals.rays,
                                           totals.shadow_rays, totals.dropped};
    counters.resize(kBusySlot + std::size_t(group.size()), 0);
    counters[kBusySlot + std::size_t(group.rank())] = std::uint64_t(busy * 1e6);
    group.reduce_counters(counters);
    if (group.size() > 1 && group.root() && !s_.quiet && verbose()) {
        std::uint64_t lo = counters[kBusySlot], hi = counters[kBusySlot];
        std::string list;
        for (int r = 0; r < group.size(); ++r) {
            const std::uint64_t us = counters[kBusySlot + std::size_t(r)];
            lo = std::min(lo, us);
            hi = std::max(hi, us);
            char buf[32];
            std::snprintf(buf, sizeof buf, " %.3f", double(us) * 1e-6);
            list += buf;
        }
        std::fprintf(stderr, "candela: render seconds per rank:%s (slowest/fastest %.3f)\n",
                     list.c_str(), lo > 0 ? double(hi) / double(lo) : 1.0);
    }
    stats.seconds = timer.seconds();
    stats.samples = counters[0];
    stats.camera_rays = counters[1];
    stats.rays = counters[2];
    stats.shadow_rays = counters[3];
    stats.dropped = counters[4];
    stats.passes = passes;
}

} // namespace candela
