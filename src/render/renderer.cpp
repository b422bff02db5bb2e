// The pass loop: tiles of pixels in parallel, passes of samples, adaptive stopping, one rank or
// many.
#include "candela/render/renderer.h"

#include "candela/render/adaptive.h"
#include "candela/render/integrator.h"
#include "candela/render/progress.h"
#include "candela/sampling/sampler.h"
#include "candela/util/check.h"
#include "candela/util/log.h"
#include "candela/util/stopwatch.h"

#include <fmt/format.h>
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

/// What a thread keeps from run to run, so that the render loop does not allocate.
struct RunBuffers {
    std::vector<SampleRequest> requests;
    std::vector<SampleResult> results;
    std::vector<RunPixel> pixels;
    BatchWorkspace workspace;
};

} // namespace

std::uint64_t cost_units(std::uint64_t queries, std::uint64_t samples) {
    // Every sample traces its camera ray, so queries >= samples.
    return kSampleCost * samples + kQueryCost * (queries - std::min(queries, samples));
}

Renderer::Renderer(const Scene& scene, const Accel& accel, const RenderSettings& settings)
    : scene_(scene), accel_(accel), s_(settings) {}

RenderState Renderer::start() const {
    return make_pass_policy(s_)->start(film_width(), film_height(), s_.aovs);
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
    void reduce_sums(std::vector<std::uint64_t>&) const override {}
    void broadcast(std::vector<std::uint8_t>&) const override {}
};

} // namespace

const RenderGroup& single_process() {
    static const SingleProcess group;
    return group;
}

void RenderGroup::reduce(RenderCounters& counters) const {
    std::vector<std::uint64_t> values;
    for (std::uint64_t RenderCounters::*f : kRenderCounterFields)
        values.push_back(counters.*f);
    reduce_sums(values);
    std::size_t i = 0;
    for (std::uint64_t RenderCounters::*f : kRenderCounterFields)
        counters.*f = values[i++];
}

SampleBlock rank_block(int first, int last, int rank, int size) {
    CANDELA_CHECK(size >= 1 && rank >= 0 && rank < size && last >= first,
                  "rank_block: invalid rank, size or range");
    const long long n = last - first;
    SampleBlock b;
    b.first = first + int(n * rank / size);
    b.last = first + int(n * (rank + 1) / size);
    return b;
}

bool RenderGroup::own_share(const RenderState& st, const std::function<RenderState()>& fresh,
                            Film& own_film, std::vector<std::uint64_t>& own_cost) const {
    if (size() == 1) return false;
    // The root's own samples start from the resumed film; the others' from nothing.
    own_film = root() ? st.film : fresh().film;
    if (!st.cost.empty())
        own_cost = root() ? st.cost : std::vector<std::uint64_t>(st.cost.size(), 0);
    return true;
}

void RenderGroup::gather(const Film& own_film, const std::vector<std::uint64_t>& own_cost,
                         RenderState& st) const {
    if (size() == 1) return;
    st.film = own_film;
    reduce_film(st.film);
    if (own_cost.empty()) return;
    std::vector<std::uint64_t> cost = own_cost;
    reduce_sums(cost);
    if (root()) st.cost = std::move(cost);
}

void RenderGroup::report_balance(double busy, bool report) const {
    std::vector<std::uint64_t> busy_us(std::size_t(size()), 0); // one element per rank
    busy_us[std::size_t(rank())] = std::uint64_t(busy * 1e6);
    reduce_sums(busy_us);
    if (size() == 1 || !root() || !report) return;
    const auto [lo, hi] = std::minmax_element(busy_us.begin(), busy_us.end());
    std::string list;
    for (std::uint64_t us : busy_us)
        list += fmt::format(" {:.3f}", double(us) * 1e-6);
    fmt::print(stderr, "candela: render seconds per rank:{} (slowest/fastest {:.3f})\n", list,
               *lo > 0 ? double(*hi) / double(*lo) : 1.0);
}

namespace {

/// One render's pass loop: the pass over the tiles, the films and costs, and the group's share
/// of the work, for one process or for every rank of a group. What each pass renders and what
/// follows from it is the pass policy's (render/adaptive.h), asked on the root.
///
/// Films and costs: each rank renders its share of every pixel's sample range into its own film
/// (`local`), the root's starting from the film of a resumed render. The state's film and costs
/// are the group's: with one process they are the local ones themselves; in a group the root's
/// are the sums over the ranks, refreshed after every pass that the policy decides from the
/// film, for a checkpoint, and at the end.
class PassLoop {
  public:
    PassLoop(const Renderer& r, const Scene& scene, const Accel& accel, const RenderSettings& s,
             RenderState& st, const RenderGroup& group)
        : r_(r), s_(s), st_(st), group_(group), fw_(r.film_width()), fh_(r.film_height()),
          integrator_(scene, accel, s), order_(pass_order(fw_, fh_)),
          policy_(make_pass_policy(s, group.size())) {
        policy_->prepare(st_);
        const bool own = group_.own_share(
            st_, [this] { return r_.start(); }, own_film_, own_cost_);
        local_film_ = own ? &own_film_ : &st_.film;
        local_cost_ = own ? &own_cost_ : &st_.cost;
    }

    const PassPolicy& policy() const { return *policy_; }

    /// The next pass's samples of every pixel: the root's policy plans them, every rank learns.
    void plan() {
        std::vector<int> range;
        group_.decide_on_root(
            [&] {
                policy_->plan(st_, plan_);
                range = {plan_.first, plan_.size};
            },
            range, plan_.start, plan_.count);
        plan_.first = range[0];
        plan_.size = range[1];
    }

    /// The decisions after the pass: made by the root's policy on the group's film (when it reads
    /// it: sync() first), the state's outcome then shared, so every rank sees the same end.
    void decide() {
        std::vector<std::uint64_t> outcome;
        group_.decide_on_root(
            [&] {
                policy_->decide(st_, plan_);
                outcome = {std::uint64_t(st_.next_sample), std::uint64_t(st_.budget_spp),
                           std::uint64_t(st_.stopped), st_.cost_budget};
            },
            outcome);
        st_.next_sample = int(outcome[0]);
        st_.budget_spp = int(outcome[1]);
        st_.stopped = outcome[2] != 0;
        st_.cost_budget = outcome[3];
    }

    /// This rank's block of the planned samples of `pixel` (its index y w + x): a contiguous
    /// range, so index k of a pixel always gets the same numbers, split among the ranks. Empty
    /// for a pixel the plan gives none.
    SampleBlock pixel_block(std::size_t pixel) const {
        const int k0 = plan_.first_of(pixel);
        return rank_block(k0, k0 + plan_.count_of(pixel), group_.rank(), group_.size());
    }

    /// Renders this rank's share of the planned samples of every pixel into the local film.
    void execute(Progress& progress) {
        cut_runs(
            order_, [&](std::uint32_t pixel) { return pixel_block(pixel).size(); }, runs_);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs_.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              RenderCounters& counters = counters_.local();
                              RunBuffers& buf = run_buffers_.local();
                              for (std::size_t k = r.begin(); k < r.end(); ++k) {
                                  const std::uint64_t n = render_run(runs_[k], buf, counters);
                                  // Every rank renders about as much: the root's progress stands
                                  // for all.
                                  progress.add(n * std::uint64_t(group_.size()));
                              }
                          });
    }

    /// This rank's counters of every pass so far (the threads' summed).
    RenderCounters counters() const {
        RenderCounters sum;
        for (const RenderCounters& c : counters_)
            sum += c;
        return sum;
    }

    /// Makes the state's film and costs the group's (a no-op for one process).
    void sync() {
        group_.gather(*local_film_, *local_cost_, st_);
        synced_ = true;
    }

    /// Whether the state's film is the group's after the last pass (always when the local film
    /// is the state's own).
    bool synced() const { return synced_ || local_film_ == &st_.film; }
    void mark_unsynced() { synced_ = false; }

  private:
    /// Renders one run's samples, pixel by pixel in the pass order and each pixel's in index
    /// order (one pixel's camera rays next to each other), and adds them to the local film and
    /// costs: the film's sums are added in index order whatever the runs. Returns the samples
    /// rendered; counts them, their ray queries and the non-finite ones dropped in `counters`.
    std::uint64_t render_run(const PassRun& run, RunBuffers& buf, RenderCounters& counters) {
        const int x0 = s_.region.full() ? 0 : s_.region.x;
        const int y0 = s_.region.full() ? 0 : s_.region.y;
        buf.requests.clear();
        buf.pixels.clear();
        for (std::uint32_t pos = run.begin; pos < run.end; ++pos) {
            const std::uint32_t pixel = order_[pos];
            const SampleBlock b = pixel_block(pixel);
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
            counters.dropped += film.add_samples(
                tp.x, tp.y, tp.count, [res](int k) -> const FilmSample& { return res[k].fs; });
            if (local_cost_->empty()) continue; // costs are the relative sampler's
            std::uint64_t queries = 0;
            for (int k = 0; k < tp.count; ++k)
                queries += res[k].queries;
            (*local_cost_)[std::size_t(tp.y) * fw_ + tp.x] +=
                cost_units(queries, std::uint64_t(tp.count));
        }
        counters.samples += n;
        return n;
    }

    const Renderer& r_;
    const RenderSettings& s_;
    RenderState& st_;
    const RenderGroup& group_;
    const int fw_, fh_;
    Integrator integrator_;
    const std::vector<std::uint32_t> order_; ///< pass_order() of the film
    std::unique_ptr<PassPolicy> policy_;
    PassPlan plan_;             ///< the current pass
    std::vector<PassRun> runs_; ///< the tasks of the current pass
    tbb::enumerable_thread_specific<RunBuffers> run_buffers_;
    tbb::enumerable_thread_specific<RenderCounters> counters_;
    Film own_film_;                       ///< in a group: this rank's own samples
    std::vector<std::uint64_t> own_cost_; ///< in a group: the costs of this rank's samples
    Film* local_film_ = nullptr;
    std::vector<std::uint64_t>* local_cost_ = nullptr;
    bool synced_ = false;
};

/// Whether the stop flag or (on the root's clock, between whole passes, after at least one) the
/// time budget ends the render before the next pass; the same answer on every rank.
bool stop_requested(const RenderGroup& group, const std::atomic<bool>* stop,
                    const RenderSettings& s, const Stopwatch& timer, int passes,
                    RenderStats& stats) {
    if (group.any(stop && stop->load())) {
        stats.interrupted = true;
        return true;
    }
    const double elapsed = timer.seconds();
    if (group.root_flag(s.time_budget > 0.0 && passes > 0 && elapsed >= s.time_budget)) {
        stats.out_of_time = true;
        return true;
    }
    return false;
}

/// The counters of a finished run summed over the group onto the root (`stats`), and each rank's
/// busy time (seconds rendering its blocks), which the root reports when verbose.
void gather_counters(const RenderGroup& group, const PassLoop& loop, double busy, bool report,
                     RenderStats& stats) {
    RenderCounters totals = loop.counters();
    group.reduce(totals);
    static_cast<RenderCounters&>(stats) = totals;
    group.report_balance(busy, report);
}

} // namespace

void Renderer::run(RenderState& st, RenderStats& stats, const std::atomic<bool>* stop,
                   const std::function<void(const RenderState&)>& on_pass,
                   const RenderGroup& group) const {
    const Stopwatch timer;
    std::unique_ptr<tbb::global_control> limit;
    if (s_.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(s_.threads));
    PassLoop loop(*this, scene_, accel_, s_, st, group);
    // The root reports for the group; quiet silences all but an explicit JSON progress.
    Progress progress(loop.policy().samples_left(st),
                      group.root_or(resolve_progress_mode(s_.progress, s_.quiet || !verbose()),
                                    ProgressMode::None),
                      s_.time_budget);
    int passes = 0;
    double busy = 0.0; // seconds this rank spent rendering its blocks (load balance)
    while (!loop.policy().finished(st) && !stop_requested(group, stop, s_, timer, passes, stats)) {
        loop.plan();
        const Stopwatch pass_clock;
        loop.execute(progress);
        busy += pass_clock.seconds();
        loop.mark_unsynced();
        ++passes;
        ++st.passes;
        // Decisions and checkpoints need the group's film; so does the end (after the loop).
        if (loop.policy().reads_film() || on_pass) loop.sync();
        loop.decide();
        group.report_on_root([&] {
            progress.retarget(progress.done() + loop.policy().samples_left(st));
            if (on_pass) on_pass(st);
        });
    }
    if (!loop.synced()) loop.sync();
    stats.stop = stats.interrupted   ? StopReason::Interrupted
                 : stats.out_of_time ? StopReason::TimeBudget
                                     : loop.policy().stop_reason(st);
    stats.estimated_error = loop.policy().estimated_error();
    stats.budget_spent = loop.policy().budget_spent();
    if (stats.stop != StopReason::Interrupted) progress.complete();
    progress.finish();
    gather_counters(group, loop, busy, !s_.quiet && verbose(), stats);
    stats.seconds = timer.seconds();
    stats.passes = passes;
}

} // namespace candela
