// The pass policies (adaptive.h): uniform, cs184 and relative sampling, each answering every
// question whose answer depends on the sampler, and the factory that picks one.
#include "candela/render/adaptive.h"

#include "candela/render/film.h"
#include "candela/sampling/rng.h"
#include "candela/util/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace candela {

namespace {

/// Relative sampler: neighbourhood radius of the error and cost estimates (a 5x5 window without
/// its centre: 24 neighbours decide a pixel's budget, its own samples do not).
constexpr int kRelativeSmoothRadius = 2;
/// Relative sampler: separates the hash stream of the allocation's rounding (seeded by the render
/// seed and the pass) from the samplers' streams.
constexpr std::uint64_t kRoundingSalt = 0x524f554e44ULL;

std::uint64_t total_cost(const std::vector<std::uint64_t>& cost) {
    std::uint64_t sum = 0;
    for (std::uint64_t c : cost)
        sum += c;
    return sum;
}

/// Samples a pixel has used in a state: finite and dropped.
std::uint64_t samples_taken(const RenderState& st) {
    return st.film.total_samples() + st.film.total_dropped();
}

/// Samples per pixel of an adaptive pass: one batch (-a BATCH), at most -s.
int batch_spp(const RenderSettings& s) {
    return std::min(s.spp, s.adaptive_batch);
}

} // namespace

RenderState PassPolicy::start(int w, int h, const AovSet& aovs) const {
    RenderState st;
    st.film = Film(w, h, aovs, reads_film());
    st.done.assign(std::size_t(w) * std::size_t(h), 0);
    return st;
}

std::string PassPolicy::reached_text(const RenderState& st) const {
    return fmt::format("{} of {} samples/pixel", st.next_sample, s_.spp);
}

double PassPolicy::reached(const RenderState& st) const {
    return double(st.next_sample) / double(std::max(1, s_.spp));
}

std::string PassPolicy::stop_text(const RenderStats& stats, std::size_t) const {
    switch (stats.stop) {
    case StopReason::Interrupted:
        return "interrupted";
    case StopReason::TimeBudget:
        return fmt::format("time budget ({:g}s) reached", s_.time_budget);
    case StopReason::AllSamples:
        return fmt::format("all {} samples/pixel taken", s_.spp);
    case StopReason::Converged:
        return "every pixel met the -a tolerance";
    case StopReason::NoiseThreshold:
    case StopReason::BudgetSpent:
    case StopReason::NothingToGain:
        break; // the relative sampler's, which says them itself
    }
    return "";
}

namespace {

/// --adaptive none: passes of --pass-spp (or min(-s, kAutoPassSpp)) samples in every pixel until
/// -s. Nothing between passes reads the film, so each rank of a group renders a whole pass of its
/// own.
class UniformPolicy final : public PassPolicy {
  public:
    UniformPolicy(const RenderSettings& s, int ranks) : PassPolicy(s), ranks_(ranks) {}
    void prepare(RenderState&) override {}
    /// Sample k of a pixel is the same in any pass: the render goes on at next_sample.
    void reopen(const RenderSettings&, bool, RenderState&) const override {}
    bool reads_film() const override { return false; }
    void plan(const RenderState& st, PassPlan& plan) override {
        plan = PassPlan{};
        plan.first = st.next_sample;
        plan.size = std::min(s_.spp, st.next_sample + pass_spp() * ranks_) - st.next_sample;
    }
    void decide(RenderState& st, const PassPlan& plan) override {
        st.next_sample = plan.first + plan.size;
    }
    std::uint64_t samples_left(const RenderState& st) const override {
        return st.film.pixel_count() * std::uint64_t(std::max(0, s_.spp - st.next_sample));
    }
    StopReason stop_reason(const RenderState&) const override { return StopReason::AllSamples; }
    bool reads_batch() const override { return false; }
    bool reads_pass_spp() const override { return true; }
    bool spreads_samples() const override { return false; }
    std::string sampling_text() const override { return fmt::format("{} samples/pixel", s_.spp); }

  private:
    /// A slice of the samples, so that a stop request is honoured, and a checkpoint written,
    /// within a fraction of the render.
    int pass_spp() const {
        if (s_.pass_spp > 0) return s_.pass_spp;
        return std::max(1, std::min(s_.spp, kAutoPassSpp));
    }
    const int ranks_;
};

bool all_done(const RenderState& st) {
    return std::all_of(st.done.begin(), st.done.end(), [](std::uint8_t d) { return d != 0; });
}

/// cs184 (spec §5.4): batches of -a BATCH samples; after each, a pixel whose confidence
/// half-width meets the tolerance stops (RenderState::done) until none is left or -s is reached.
class Cs184Policy final : public PassPolicy {
  public:
    explicit Cs184Policy(const RenderSettings& s) : PassPolicy(s) {}
    void prepare(RenderState&) override {}
    /// A direct render with the larger -s tests every running pixel at the old -s, a pass
    /// boundary for it; the finished render did not (its last pass ended it).
    void reopen(const RenderSettings& before, bool finished, RenderState& st) const override {
        if (finished && s_.spp != before.spp) stop_converged(st);
    }
    bool reads_film() const override { return true; }
    void plan(const RenderState& st, PassPlan& plan) override {
        plan.first = st.next_sample;
        plan.size = std::min(s_.spp, st.next_sample + batch_spp(s_)) - st.next_sample;
        plan.start.clear();
        plan.count.resize(st.done.size());
        for (std::size_t p = 0; p < st.done.size(); ++p)
            plan.count[p] = st.done[p] ? 0 : plan.size;
    }
    void decide(RenderState& st, const PassPlan& plan) override {
        st.next_sample = plan.first + plan.size;
        if (st.next_sample < s_.spp)
            stop_converged(st);
        else if (all_done(st))
            st.stopped = true;
    }
    /// Every pixel that has not converged takes the rest of its samples (the most it can).
    std::uint64_t samples_left(const RenderState& st) const override {
        if (st.stopped) return 0;
        return std::uint64_t(std::max(0, s_.spp - st.next_sample)) *
               std::uint64_t(std::count(st.done.begin(), st.done.end(), 0));
    }
    StopReason stop_reason(const RenderState& st) const override {
        return all_done(st) ? StopReason::Converged : StopReason::AllSamples;
    }
    bool reads_tolerance() const override { return true; }
    std::string sampling_text() const override {
        return fmt::format("up to {} samples/pixel (cs184 adaptive)", s_.spp);
    }
    std::string summary_text() const override { return fmt::format("cs184: at most {}", s_.spp); }
    std::string reached_text(const RenderState& st) const override {
        return fmt::format("{} of up to {} samples/pixel", st.next_sample, s_.spp);
    }
    std::string stop_text(const RenderStats& stats, std::size_t pixels) const override {
        if (stats.stop == StopReason::AllSamples)
            return fmt::format("pixels short of the -a tolerance: {} samples/pixel taken", s_.spp);
        return PassPolicy::stop_text(stats, pixels);
    }

  private:
    /// Stops every running pixel that meets the tolerance, and the render when none is left.
    void stop_converged(RenderState& st) const {
        for (int y = 0; y < st.film.height(); ++y)
            for (int x = 0; x < st.film.width(); ++x) {
                const std::size_t p = std::size_t(y) * st.film.width() + x;
                if (!st.done[p] && adaptive_pixel_converged(st.film, x, y, s_.adaptive_tol))
                    st.done[p] = 1;
            }
        if (all_done(st)) st.stopped = true;
    }
};

/// A film of one pixel (a 1x1 region): with no neighbours to judge it by, its error estimate
/// would be 0 and the relative sampler would end the render after the first pass. It takes -s
/// samples instead, uniformly, and no noise threshold ends it (its own samples would decide
/// their own count, the stopping rule the neighbour estimate exists to avoid).
bool lone_pixel(const RenderState& st) {
    return st.film.pixel_count() == 1;
}

/// The relative sampler (this header's derivation): a uniform first pass sets the cost budget;
/// every later pass spends at most a uniform pass's share of it where the neighbours' relative
/// error per unit of cost is largest, until the noise threshold, the budget or nothing to gain
/// ends the render.
class RelativePolicy final : public PassPolicy {
  public:
    explicit RelativePolicy(const RenderSettings& s) : PassPolicy(s) {}
    RenderState start(int w, int h, const AovSet& aovs) const override {
        RenderState st = PassPolicy::start(w, h, aovs);
        st.cost.assign(st.film.pixel_count(), 0);
        return st;
    }
    void prepare(RenderState& st) override;
    /// A version 3 or 4 checkpoint says a render ended only by its share of the budget.
    bool finished(const RenderState& st) const override {
        return PassPolicy::finished(st) || st.budget_spp >= s_.spp;
    }
    void reopen(const RenderSettings& before, bool finished, RenderState& st) const override;
    bool reads_film() const override { return true; }
    void plan(const RenderState& st, PassPlan& plan) override;
    void decide(RenderState& st, const PassPlan& plan) override;
    std::uint64_t samples_left(const RenderState& st) const override;
    StopReason stop_reason(const RenderState&) const override { return outlook_.stop; }
    double estimated_error() const override { return outlook_.error; }
    double budget_spent() const override { return outlook_.share; }
    bool reads_noise_threshold() const override { return true; }
    int most_per_pixel() const override { return relative_max_per_pixel(s_.spp); }
    std::string sampling_text() const override;
    std::string summary_text() const override {
        return fmt::format("relative: noise threshold {:g}, budget the cost of {} samples/pixel",
                           double(s_.noise_threshold), s_.spp);
    }
    std::string reached_text(const RenderState& st) const override;
    double reached(const RenderState& st) const override;
    std::string stop_text(const RenderStats& stats, std::size_t pixels) const override;
    std::string finished_text() const override {
        return fmt::format("the render has spent the budget of -s {}; give a larger -s", s_.spp);
    }

  private:
    /// The statistics of the state's film, computed once per pass: the decision after a pass
    /// and the plan of the next read the same film.
    const LumStatsMap& film_stats(const RenderState& st);
    /// The allocation of a pass after the first, from the film and the recorded costs: the same
    /// for any thread count, rank count and after a resume.
    std::vector<int> allocate(const RenderState& st);
    /// The share of the budget `budget` that `spent` cost units are, in samples per pixel of -s
    /// (RenderState::budget_spp).
    int budget_share_spp(std::uint64_t spent, std::uint64_t budget) const {
        const double share = double(spent) / double(budget);
        return int(std::min(double(s_.spp), std::floor(share * double(s_.spp))));
    }
    /// A lone pixel's end: its -s samples, of which it has `taken`. Sets its share of the budget
    /// and returns whether it is finished.
    bool lone_pixel_end(RenderState& st, std::uint64_t taken) const {
        st.budget_spp = int(std::min(taken, std::uint64_t(s_.spp)));
        return taken >= std::uint64_t(s_.spp);
    }
    /// Reads where the render of `st` stands (its error, cost and samples) into the outlook.
    void look(const RenderState& st);

    /// Where the render stood after the last decision.
    struct Outlook {
        double error = -1.0;                      ///< estimated relative RMS error of the image
        double share = 0.0;                       ///< of the cost budget spent
        std::uint64_t spent = 0;                  ///< cost units spent
        std::uint64_t taken = 0;                  ///< samples taken
        StopReason stop = StopReason::AllSamples; ///< what ended the render, if it ended
    };

    std::vector<std::uint32_t> next_index_; ///< each pixel's samples so far (its next index)
    Outlook outlook_;
    LumStatsMap stats_;     ///< film_stats() ...
    int stats_passes_ = -1; ///< ... of the film after this many passes
};

void RelativePolicy::prepare(RenderState& st) {
    const std::size_t pixels = st.film.pixel_count();
    if (st.cost.size() != pixels) {
        if (samples_taken(st) > 0)
            throw Error(ErrorKind::Usage,
                        "the relative adaptive sampler cannot continue a render whose "
                        "state has no per-pixel costs");
        st.cost.assign(pixels, 0);
    }
    if (finished(st)) st.stopped = true;
    next_index_.assign(pixels, 0);
    for (int y = 0; y < st.film.height(); ++y)
        for (int x = 0; x < st.film.width(); ++x)
            next_index_[std::size_t(y) * st.film.width() + x] =
                st.film.count(x, y) + st.film.dropped(x, y);
    // A resumed render with a budget: its error and cost so far, for the forecast.
    if (st.cost_budget > 0 && !lone_pixel(st)) look(st);
}

/// Finished or not, the budget and the stop are counted again under the new settings.
void RelativePolicy::reopen(const RenderSettings& before, bool, RenderState& st) const {
    if (lone_pixel(st)) {
        st.stopped = lone_pixel_end(st, samples_taken(st));
        return;
    }
    if (st.cost_budget == 0) return; // no pass has set the budget: the render starts afresh
    // The budget is -s uniform samples at the first pass's cost per sample: it scales with -s.
    if (s_.spp != before.spp)
        st.cost_budget = std::uint64_t(
            std::llround(double(st.cost_budget) * double(s_.spp) / double(before.spp)));
    // Progress counts the share of the budget spent, in samples per pixel of the new -s; a
    // render whose budget is spent stays finished. Any other stop (the threshold, nothing to
    // gain) is decided again after the next pass, under the new settings.
    const std::uint64_t spent = total_cost(st.cost);
    st.budget_spp = budget_share_spp(spent, st.cost_budget);
    st.stopped = spent >= st.cost_budget;
}

const LumStatsMap& RelativePolicy::film_stats(const RenderState& st) {
    if (stats_passes_ != st.passes) {
        fill_lum_stats(st.film, stats_);
        stats_passes_ = st.passes;
    }
    return stats_;
}

void RelativePolicy::look(const RenderState& st) {
    const LumStatsMap& m = film_stats(st);
    outlook_.error = estimated_relative_rms(m, relative_error_map(m, 0, WindowCentre::Include));
    outlook_.spent = total_cost(st.cost);
    outlook_.taken = samples_taken(st);
    outlook_.share = double(outlook_.spent) / double(st.cost_budget);
}

std::vector<int> RelativePolicy::allocate(const RenderState& st) {
    // Every pass after the first may spend what a uniform pass of one batch per pixel costs.
    const std::uint64_t spent = total_cost(st.cost);
    const double uniform_pass = double(st.cost_budget) * double(batch_spp(s_)) / double(s_.spp);
    const double budget =
        std::min(double(st.cost_budget - std::min(st.cost_budget, spent)), uniform_pass);
    const LumStatsMap& m = film_stats(st);
    // Each pixel's share comes from its neighbours' samples, never its own (above): its count
    // is then independent of the values it averages.
    return allocate_pass(
        m, relative_error_map(m, kRelativeSmoothRadius, WindowCentre::Exclude),
        cost_per_sample_map(m, st.cost, kRelativeSmoothRadius, WindowCentre::Exclude), budget,
        relative_max_per_pixel(s_.spp),
        hash_combine(s_.seed, kRoundingSalt, std::uint64_t(st.passes)));
}

void RelativePolicy::plan(const RenderState& st, PassPlan& plan) {
    const int step = batch_spp(s_);
    plan.first = plan.size = 0;
    plan.start = next_index_;
    if (lone_pixel(st))
        plan.count.assign(1, std::max(0, std::min(step, s_.spp - int(next_index_[0]))));
    else if (st.cost_budget == 0)
        plan.count.assign(next_index_.size(), step); // the first pass is uniform, sets the budget
    else
        plan.count = allocate(st);
}

void RelativePolicy::decide(RenderState& st, const PassPlan& plan) {
    for (std::size_t i = 0; i < next_index_.size(); ++i)
        next_index_[i] += std::uint32_t(plan.count[i]);
    // After the first (uniform) pass the budget is fixed: what spp uniform samples per pixel
    // cost at that pass's mean cost per sample. The render ends when the budget is spent,
    // nothing more can be gained (no allocation), or the estimated relative RMS error of the
    // image reaches the threshold.
    if (st.cost_budget == 0)
        st.cost_budget =
            std::uint64_t(std::llround(double(total_cost(st.cost)) / double(samples_taken(st)) *
                                       double(s_.spp) * double(next_index_.size())));
    look(st);
    std::uint64_t allocated = 0;
    for (int a : plan.count)
        allocated += std::uint64_t(a);
    const double err = outlook_.error;
    const bool spent = outlook_.spent >= st.cost_budget;
    st.budget_spp = budget_share_spp(outlook_.spent, st.cost_budget);
    bool finished = spent || allocated == 0 || err <= s_.noise_threshold;
    outlook_.stop = err <= s_.noise_threshold ? StopReason::NoiseThreshold
                    : spent                   ? StopReason::BudgetSpent
                    : allocated == 0          ? StopReason::NothingToGain
                                              : StopReason::AllSamples;
    if (lone_pixel(st)) {
        finished = lone_pixel_end(st, next_index_[0]);
        outlook_.stop = StopReason::BudgetSpent;
    }
    if (finished) st.stopped = true;
}

/// The error falls as 1/sqrt(cost) (sqrt(mean_p e_p / n_p) with every n_p scaled alike), so the
/// threshold is reached after about spent (error / threshold)^2 cost units, or the budget ends
/// the render first. The test comes after a pass, which spends at most the cost of one batch of
/// uniform samples per pixel: the render stops at the first pass boundary past the threshold,
/// half a pass later on average.
std::uint64_t RelativePolicy::samples_left(const RenderState& st) const {
    if (st.stopped) return 0;
    if (lone_pixel(st)) return std::uint64_t(std::max(0, s_.spp - int(next_index_[0])));
    const Outlook& o = outlook_;
    if (o.spent == 0 || o.taken == 0)
        return next_index_.size() * std::uint64_t(std::max(0, s_.spp - st.budget_spp));
    double end = double(st.cost_budget);
    if (s_.noise_threshold > 0.f && o.error > double(s_.noise_threshold)) {
        const double ratio = o.error / double(s_.noise_threshold);
        const double pass_cost = double(st.cost_budget) * double(batch_spp(s_)) / double(s_.spp);
        end = std::min(end, double(o.spent) * ratio * ratio + 0.5 * pass_cost);
    }
    const double cost_left = std::max(0.0, end - double(o.spent));
    return std::uint64_t(cost_left * double(o.taken) / double(o.spent));
}

std::string RelativePolicy::sampling_text() const {
    if (s_.noise_threshold > 0.f)
        return fmt::format("budget {} samples/pixel (adaptive, stops at noise threshold {:g})",
                           s_.spp, double(s_.noise_threshold));
    return fmt::format("budget {} samples/pixel (adaptive)", s_.spp);
}

double RelativePolicy::reached(const RenderState& st) const {
    if (st.cost_budget == 0) return 0.0;
    return double(total_cost(st.cost)) / double(st.cost_budget);
}

std::string RelativePolicy::reached_text(const RenderState& st) const {
    const double mean = st.film.pixel_count() == 0
                            ? 0.0
                            : double(samples_taken(st)) / double(st.film.pixel_count());
    return fmt::format("{:.0f} % of the budget of {} samples/pixel (mean {:.2f} samples/pixel)",
                       100.0 * reached(st), s_.spp, mean);
}

std::string RelativePolicy::stop_text(const RenderStats& stats, std::size_t pixels) const {
    const double share = 100.0 * stats.budget_spent;
    switch (stats.stop) {
    case StopReason::TimeBudget:
        return fmt::format("time budget ({:g}s) reached at {:.0f} % of the budget", s_.time_budget,
                           share);
    case StopReason::NoiseThreshold:
        return fmt::format("noise threshold {:g} reached (estimated {:.4g}) at {:.0f} % of the "
                           "budget",
                           double(s_.noise_threshold), stats.estimated_error, share);
    case StopReason::BudgetSpent:
        if (pixels == 1)
            return fmt::format("budget spent: {} samples in the one pixel, uniformly (no "
                               "neighbours to estimate its error from)",
                               s_.spp);
        return fmt::format("budget spent (estimated noise {:.4g})", stats.estimated_error);
    case StopReason::NothingToGain:
        return fmt::format("no pixel needed more samples (estimated noise {:.4g}) at {:.0f} % of "
                           "the budget",
                           stats.estimated_error, share);
    case StopReason::Interrupted:
    case StopReason::AllSamples:
    case StopReason::Converged:
        break;
    }
    return PassPolicy::stop_text(stats, pixels);
}

} // namespace

std::unique_ptr<PassPolicy> make_pass_policy(const RenderSettings& s, int ranks) {
    switch (s.adaptive) {
    case AdaptiveKind::Cs184:
        return std::make_unique<Cs184Policy>(s);
    case AdaptiveKind::Relative:
        return std::make_unique<RelativePolicy>(s);
    case AdaptiveKind::None:
        break;
    }
    return std::make_unique<UniformPolicy>(s, ranks);
}

void use_uniform_sampler(RenderSettings& s) {
    s.adaptive = AdaptiveKind::None;
}

void use_cs184_sampler(RenderSettings& s, int batch, float tolerance) {
    s.adaptive = AdaptiveKind::Cs184;
    s.adaptive_batch = batch;
    s.adaptive_tol = tolerance;
}

void use_relative_sampler(RenderSettings& s, int batch, float noise_threshold) {
    s.adaptive = AdaptiveKind::Relative;
    s.adaptive_batch = batch;
    s.noise_threshold = noise_threshold;
}

} // namespace candela
