// Adaptive sampling decisions (error maps, per-pixel allocation) on statistics, apart from the
// renderer.
#include "candela/render/adaptive.h"

#include "candela/render/film.h"
#include "candela/sampling/rng.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace candela {

namespace {

/// z-value of the CS184 criterion: a 95% confidence half-width (spec §5.4).
constexpr double kConfidenceZ = 1.96;
/// Added to mu^2 in the relative error: the same constant as in the relMSE metric of
/// `candela converge` (converge.h), so the sampler minimises the error that is measured, and a
/// black or very dark pixel has a finite (not infinite) relative error.
constexpr double kDarkFloor = 0.01;

/// Pixels one task of the per-pixel loops below takes at least: a few microseconds of work,
/// so that a small image is not split into tasks that cost more to schedule than to run.
constexpr std::size_t kPixelGrain = 4096;

/// Runs body(begin, end) over [0, count) in parallel chunks. Every loop that uses it writes
/// each index's result from that index's inputs alone, so the results do not depend on the
/// split or the thread count; sums over pixels stay serial, in index order, for the same reason.
template <class Body> void for_pixels(std::size_t count, const Body& body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kPixelGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// for_pixels() over the rows of a w-wide image: body(y_begin, y_end).
template <class Body> void for_rows(int w, int h, const Body& body) {
    const std::size_t rows_per_task =
        std::max<std::size_t>(1, kPixelGrain / std::max<std::size_t>(1, std::size_t(w)));
    tbb::parallel_for(tbb::blocked_range<int>(0, h, rows_per_task),
                      [&](const tbb::blocked_range<int>& r) { body(r.begin(), r.end()); });
}

/// Sums of v over every pixel's (2 radius + 1)^2 window clipped at the frame, with or without
/// the pixel itself, into out (w x h, row-major). Rows first, then columns, each sum taken from
/// the values themselves: a running sum would subtract the value leaving the window, and with
/// the centre excluded its rounding would carry the pixel's own value into its window. `row`
/// and `row_others` are scratch of w x h values. For integer T the sums are exact.
template <class T>
void window_sums(const T* v, int w, int h, int radius, WindowCentre centre, T* out,
                 std::vector<T>& row, std::vector<T>& row_others) {
    const std::size_t P = std::size_t(w) * h;
    const bool exclude = centre == WindowCentre::Exclude;
    row.resize(P);
    if (exclude) row_others.resize(P);
    for_rows(w, h, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const T* in = v + std::size_t(y) * w;
            T* all = row.data() + std::size_t(y) * w;
            T* others = exclude ? row_others.data() + std::size_t(y) * w : nullptr;
            for (int x = 0; x < w; ++x) {
                T left = T(0), right = T(0);
                for (int xx = std::max(0, x - radius); xx < x; ++xx)
                    left += in[xx];
                for (int xx = x + 1; xx <= std::min(w - 1, x + radius); ++xx)
                    right += in[xx];
                all[x] = left + in[x] + right;
                if (exclude) others[x] = left + right;
            }
        }
    });
    for_rows(w, h, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
            const T* own_row = (exclude ? row_others.data() : row.data()) + std::size_t(y) * w;
            T* o = out + std::size_t(y) * w;
            for (int x = 0; x < w; ++x) {
                T sum = T(0);
                for (int yy = y0; yy <= y1; ++yy)
                    sum += yy == y ? own_row[x] : row[std::size_t(yy) * w + x];
                o[x] = sum;
            }
        }
    });
}

} // namespace

bool cs184_converged(double mean, double var, std::uint32_t n, double tol) {
    if (n < 2) return false;
    const double half_width = kConfidenceZ * std::sqrt(std::max(0.0, var) / double(n));
    return half_width <= tol * mean;
}

bool adaptive_pixel_converged(const Film& film, int x, int y, double tol) {
    double mean, var;
    std::uint32_t n;
    film.lum_stats(x, y, mean, var, n);
    return cs184_converged(mean, var, n, tol);
}

std::vector<double> relative_error_map(const LumStatsMap& st, int radius, WindowCentre centre) {
    const int w = st.width, h = st.height;
    const std::size_t P = std::size_t(w) * h;
    CANDELA_CHECK(st.mean.size() == P && st.var.size() == P && st.n.size() == P,
                  "relative_error_map: statistics do not match the size");
    const bool rgb = st.mean_rgb.size() == 3 * P && st.var_rgb.size() == 3 * P;
    const int channels = rgb ? 3 : 1;
    // Each pixel's own relative variance first, then its average over the window. Averaging
    // the ratio (not the variance and the mean separately) keeps the estimate of a pixel next
    // to the bright light or the black background its own: a window mean pulled up by the light
    // would make its neighbours look noiseless, one pulled down by the background would make
    // them look noisy.
    std::vector<double> own(P, 0.0);
    std::vector<std::uint8_t> valid(P, 0);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            if (st.n[i] < 2) continue;
            double sum = 0.0;
            for (int c = 0; c < channels; ++c) {
                const double m = rgb ? st.mean_rgb[3 * i + c] : st.mean[i];
                const double v = std::max(0.0, rgb ? st.var_rgb[3 * i + c] : st.var[i]);
                sum += v / (m * m + kDarkFloor);
            }
            own[i] = sum / channels;
            valid[i] = 1;
        }
    });
    // A window of the pixel alone is its own value (0 where it has none): what window_mean()
    // gives, without its passes over the image.
    if (radius == 0 && centre == WindowCentre::Include) return own;
    return window_mean(own, valid, w, h, radius, centre);
}

std::vector<double> window_mean(const std::vector<double>& v,
                                const std::vector<std::uint8_t>& valid, int w, int h, int radius,
                                WindowCentre centre) {
    const std::size_t P = std::size_t(w) * h;
    CANDELA_CHECK(v.size() == P && valid.size() == P, "window_mean: values do not match the size");
    const bool exclude = centre == WindowCentre::Exclude;
    double all_sum = 0.0;
    std::size_t all_cnt = 0;
    for (std::size_t i = 0; i < P; ++i)
        if (valid[i]) {
            all_sum += v[i];
            ++all_cnt;
        }
    // The valid values (0 elsewhere, which adds nothing) and their counts, summed per window.
    std::vector<double> masked(P), sum(P), row, row_others;
    std::vector<std::uint32_t> ones(P), count(P), count_row, count_row_others;
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            masked[i] = valid[i] ? v[i] : 0.0;
            ones[i] = valid[i] ? 1u : 0u;
        }
    });
    window_sums(masked.data(), w, h, radius, centre, sum.data(), row, row_others);
    window_sums(ones.data(), w, h, radius, centre, count.data(), count_row, count_row_others);
    std::vector<double> out(P, 0.0);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            if (count[i] > 0) {
                out[i] = sum[i] / count[i];
            } else if (exclude) {
                // Every other valid pixel of the image, still without this one.
                const std::size_t others = all_cnt - (valid[i] ? 1 : 0);
                if (others > 0) out[i] = (all_sum - (valid[i] ? v[i] : 0.0)) / double(others);
            }
        }
    });
    return out;
}

double estimated_relative_rms(const LumStatsMap& st, const std::vector<double>& e) {
    const std::size_t P = e.size();
    if (P == 0) return 0.0;
    double sum = 0.0;
    for (std::size_t i = 0; i < P; ++i)
        if (st.n[i] > 0) sum += e[i] / double(st.n[i]);
    return std::sqrt(sum / double(P));
}

std::vector<double> cost_per_sample_map(const LumStatsMap& st,
                                        const std::vector<std::uint64_t>& cost, int radius,
                                        WindowCentre centre) {
    const int w = st.width, h = st.height;
    const std::size_t P = std::size_t(w) * h;
    CANDELA_CHECK(st.n.size() == P && cost.size() == P,
                  "cost_per_sample_map: costs do not match the size");
    double all_cost = 0.0, all_n = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        all_cost += double(cost[i]);
        all_n += double(st.n[i]);
    }
    CANDELA_CHECK(all_cost > 0.0 && all_n > 0.0, "cost_per_sample_map: no sample has been costed");
    const double mean_cost = all_cost / all_n;
    // Integer window sums: exact, so the same in any order.
    std::vector<std::uint64_t> samples(P), sc(P), sn(P), row, row_others;
    for (std::size_t i = 0; i < P; ++i)
        samples[i] = st.n[i];
    window_sums(cost.data(), w, h, radius, centre, sc.data(), row, row_others);
    window_sums(samples.data(), w, h, radius, centre, sn.data(), row, row_others);
    std::vector<double> c(P, mean_cost);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            if (sn[i] > 0 && sc[i] > 0) c[i] = double(sc[i]) / double(sn[i]);
    });
    return c;
}

std::vector<int> allocate_pass(const LumStatsMap& st, const std::vector<double>& e,
                               std::uint64_t budget, int max_per_pixel,
                               std::uint64_t rounding_seed) {
    return allocate_pass(st, e, std::vector<double>(e.size(), 1.0), double(budget), max_per_pixel,
                         rounding_seed);
}

std::vector<int> allocate_pass(const LumStatsMap& st, const std::vector<double>& e,
                               const std::vector<double>& cost, double budget, int max_per_pixel,
                               std::uint64_t rounding_seed) {
    const std::size_t P = e.size();
    CANDELA_CHECK(st.n.size() == P && cost.size() == P, "allocate_pass: maps do not match in size");
    std::vector<int> alloc(P, 0);
    if (P == 0 || !(budget > 0.0)) return alloc;
    for (std::size_t i = 0; i < P; ++i)
        CANDELA_CHECK(cost[i] > 0.0 && std::isfinite(cost[i]),
                      "allocate_pass: a sample cost is not positive");
    // n*_p = lambda sqrt(e_p / c_p) with lambda set by sum_p c_p n*_p = cost spent after the pass.
    // The per-pixel terms are computed in parallel, their sums serially in pixel order.
    std::vector<double> term(P);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            term[i] = std::sqrt(e[i] * cost[i]);
    });
    double spent = 0.0, sum_sqrt_ec = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        spent += cost[i] * double(st.n[i]);
        sum_sqrt_ec += term[i];
    }
    if (!(sum_sqrt_ec > 0.0)) return alloc; // nothing has any variance: nothing to gain
    const double lambda = (spent + budget) / sum_sqrt_ec;
    std::vector<double>& deficit = term; // reused: one value per pixel again
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            double target = std::min(double(max_per_pixel), lambda * std::sqrt(e[i] / cost[i]));
            deficit[i] = std::max(0.0, target - double(st.n[i]));
        }
    });
    double deficit_cost = 0.0;
    for (std::size_t i = 0; i < P; ++i)
        deficit_cost += deficit[i] * cost[i];
    if (!(deficit_cost > 0.0)) return alloc;
    const double scale = std::min(1.0, budget / deficit_cost);
    // Unbiased rounding of each pixel on its own (see adaptive.h): floor(share + u), u uniform.
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double u = double(hash_combine(rounding_seed, i) >> 11) * 0x1p-53;
            int k = int(std::floor(deficit[i] * scale + u));
            k = std::min(k, std::max(0, max_per_pixel - int(st.n[i])));
            alloc[i] = std::max(0, k);
        }
    });
    return alloc;
}

int pass_spp(const RenderSettings& s) {
    // A pass is one adaptive batch, or a slice of the sample budget so that a stop request is
    // honoured, and a checkpoint written, within a fraction of the render.
    if (s.adaptive != AdaptiveKind::None) return std::min(s.spp, s.adaptive_batch);
    if (s.pass_spp > 0) return s.pass_spp;
    return std::max(1, std::min(s.spp, kAutoPassSpp));
}

int relative_max_per_pixel(int spp) {
    return int(std::min<long long>((long long)spp * kRelativeMaxOversampling, kMaxSpp));
}

namespace {

/// Relative sampler: neighbourhood radius of the error and cost estimates (a 5x5 window without
/// its centre: 24 neighbours decide a pixel's budget, its own samples do not).
constexpr int kRelativeSmoothRadius = 2;
/// Relative sampler: separates the hash stream of the allocation's rounding (seeded by the render
/// seed and the pass) from the samplers' streams.
constexpr std::uint64_t kRoundingSalt = 0x524f554e44ULL;

} // namespace

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
    // Each pixel's statistics from its own sums: the same values for any split.
    for_rows(m.width, m.height, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y)
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

namespace {

std::uint64_t total_cost(const std::vector<std::uint64_t>& cost) {
    std::uint64_t sum = 0;
    for (std::uint64_t c : cost)
        sum += c;
    return sum;
}

/// --adaptive none: passes of pass_spp() samples in every pixel until -s. Nothing between passes
/// reads the film, so each rank of a group renders a whole pass of its own.
class UniformPolicy final : public PassPolicy {
  public:
    UniformPolicy(const RenderSettings& s, int ranks) : s_(s), ranks_(ranks) {}
    void prepare(RenderState&) override {}
    bool reads_film() const override { return false; }
    void plan(const RenderState& st, PassPlan& plan) override {
        plan = PassPlan{};
        plan.first = st.next_sample;
        plan.size = std::min(s_.spp, st.next_sample + pass_spp(s_) * ranks_) - st.next_sample;
    }
    void decide(RenderState& st, const PassPlan& plan) override {
        st.next_sample = plan.first + plan.size;
    }
    std::uint64_t samples_left(const RenderState& st) const override {
        return st.film.pixel_count() * std::uint64_t(std::max(0, s_.spp - st.next_sample));
    }
    StopReason stop_reason(const RenderState&) const override { return StopReason::AllSamples; }

  private:
    const RenderSettings& s_;
    const int ranks_;
};

bool all_done(const RenderState& st) {
    return std::all_of(st.done.begin(), st.done.end(), [](std::uint8_t d) { return d != 0; });
}

/// cs184 (spec §5.4): batches of -a BATCH samples; after each, a pixel whose confidence
/// half-width meets the tolerance stops (RenderState::done) until none is left or -s is reached.
class Cs184Policy final : public PassPolicy {
  public:
    explicit Cs184Policy(const RenderSettings& s) : s_(s) {}
    void prepare(RenderState&) override {}
    bool reads_film() const override { return true; }
    void plan(const RenderState& st, PassPlan& plan) override {
        plan.first = st.next_sample;
        plan.size = std::min(s_.spp, st.next_sample + pass_spp(s_)) - st.next_sample;
        plan.start.clear();
        plan.count.resize(st.done.size());
        for (std::size_t p = 0; p < st.done.size(); ++p)
            plan.count[p] = st.done[p] ? 0 : plan.size;
    }
    void decide(RenderState& st, const PassPlan& plan) override {
        st.next_sample = plan.first + plan.size;
        if (st.next_sample < s_.spp)
            for (int y = 0; y < st.film.height(); ++y)
                for (int x = 0; x < st.film.width(); ++x) {
                    const std::size_t p = std::size_t(y) * st.film.width() + x;
                    if (!st.done[p] && adaptive_pixel_converged(st.film, x, y, s_.adaptive_tol))
                        st.done[p] = 1;
                }
        // Every pixel has converged: nothing is left to render.
        if (all_done(st)) st.stopped = true;
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

  private:
    const RenderSettings& s_;
};

/// The relative sampler (this header's derivation): a uniform first pass sets the cost budget;
/// every later pass spends at most a uniform pass's share of it where the neighbours' relative
/// error per unit of cost is largest, until the noise threshold, the budget or nothing to gain
/// ends the render.
class RelativePolicy final : public PassPolicy {
  public:
    explicit RelativePolicy(const RenderSettings& s) : s_(s) {}
    void prepare(RenderState& st) override;
    bool reads_film() const override { return true; }
    void plan(const RenderState& st, PassPlan& plan) override;
    void decide(RenderState& st, const PassPlan& plan) override;
    std::uint64_t samples_left(const RenderState& st) const override;
    StopReason stop_reason(const RenderState&) const override { return outlook_.stop; }
    double estimated_error() const override { return outlook_.error; }
    double budget_spent() const override { return outlook_.share; }

  private:
    /// A film of one pixel (a 1x1 region): with no neighbours to judge it by, its error
    /// estimate would be 0 and the render would end after the first pass. It takes -s samples
    /// instead, uniformly, and no noise threshold ends it (its own samples would decide their
    /// own count, the stopping rule the neighbour estimate exists to avoid).
    bool lone_pixel() const { return next_index_.size() == 1; }
    /// The statistics of the state's film, computed once per pass: the decision after a pass
    /// and the plan of the next read the same film.
    const LumStatsMap& film_stats(const RenderState& st);
    /// The allocation of a pass after the first, from the film and the recorded costs: the same
    /// for any thread count, rank count and after a resume.
    std::vector<int> allocate(const RenderState& st);

    /// Where the render stood after the last decision.
    struct Outlook {
        double error = -1.0;                      ///< estimated relative RMS error of the image
        double share = 0.0;                       ///< of the cost budget spent
        std::uint64_t spent = 0;                  ///< cost units spent
        std::uint64_t taken = 0;                  ///< samples taken
        StopReason stop = StopReason::AllSamples; ///< what ended the render, if it ended
    };

    const RenderSettings& s_;
    std::vector<std::uint32_t> next_index_; ///< each pixel's samples so far (its next index)
    Outlook outlook_;
    LumStatsMap stats_;     ///< film_stats() ...
    int stats_passes_ = -1; ///< ... of the film after this many passes
};

void RelativePolicy::prepare(RenderState& st) {
    const std::size_t pixels = st.film.pixel_count();
    if (st.cost.size() != pixels) {
        if (st.film.total_samples() + st.film.total_dropped() > 0)
            throw Error(ErrorKind::Usage,
                        "the relative adaptive sampler cannot continue a render whose "
                        "state has no per-pixel costs");
        st.cost.assign(pixels, 0);
    }
    // The whole budget spent is the end (what a checkpoint of version 4 or older says so).
    if (st.budget_spp >= s_.spp) st.stopped = true;
    next_index_.assign(pixels, 0);
    for (int y = 0; y < st.film.height(); ++y)
        for (int x = 0; x < st.film.width(); ++x)
            next_index_[std::size_t(y) * st.film.width() + x] =
                st.film.count(x, y) + st.film.dropped(x, y);
}

const LumStatsMap& RelativePolicy::film_stats(const RenderState& st) {
    if (stats_passes_ != st.passes) {
        fill_lum_stats(st.film, stats_);
        stats_passes_ = st.passes;
    }
    return stats_;
}

std::vector<int> RelativePolicy::allocate(const RenderState& st) {
    // Every pass after the first may spend what a uniform pass of pass_spp() samples per pixel
    // costs.
    const std::uint64_t spent = total_cost(st.cost);
    const double uniform_pass = double(st.cost_budget) * double(pass_spp(s_)) / double(s_.spp);
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
    const int step = pass_spp(s_);
    plan.first = plan.size = 0;
    plan.start = next_index_;
    if (lone_pixel())
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
    const std::uint64_t taken = st.film.total_samples() + st.film.total_dropped();
    const std::uint64_t spent = total_cost(st.cost);
    if (st.cost_budget == 0)
        st.cost_budget = std::uint64_t(std::llround(double(spent) / double(taken) * double(s_.spp) *
                                                    double(next_index_.size())));
    std::uint64_t allocated = 0;
    for (int a : plan.count)
        allocated += std::uint64_t(a);
    const LumStatsMap& m = film_stats(st);
    const double err = estimated_relative_rms(m, relative_error_map(m, 0, WindowCentre::Include));
    const double share = double(spent) / double(st.cost_budget);
    st.budget_spp = int(std::min(double(s_.spp), std::floor(share * double(s_.spp))));
    bool finished = spent >= st.cost_budget || allocated == 0 || err <= s_.noise_threshold;
    outlook_ = {err, share, spent, taken,
                err <= s_.noise_threshold ? StopReason::NoiseThreshold
                : spent >= st.cost_budget ? StopReason::BudgetSpent
                : allocated == 0          ? StopReason::NothingToGain
                                          : StopReason::AllSamples};
    if (lone_pixel()) {
        st.budget_spp = int(std::min(next_index_[0], std::uint32_t(s_.spp)));
        finished = next_index_[0] >= std::uint32_t(s_.spp);
        outlook_.stop = StopReason::BudgetSpent;
    }
    if (finished) st.stopped = true;
}

/// The error falls as 1/sqrt(cost), so the threshold is reached at about spent (error /
/// threshold)^2, or the budget ends the render first.
std::uint64_t RelativePolicy::samples_left(const RenderState& st) const {
    const std::uint64_t pixels = next_index_.size();
    if (lone_pixel()) return std::uint64_t(std::max(0, s_.spp - int(next_index_[0])));
    const Outlook& o = outlook_;
    if (o.spent == 0 || o.taken == 0)
        return pixels * std::uint64_t(std::max(0, s_.spp - st.budget_spp));
    double end = double(st.cost_budget);
    if (s_.noise_threshold > 0.0 && o.error > 0.0)
        end = std::min(end, double(o.spent) * (o.error / s_.noise_threshold) *
                                (o.error / s_.noise_threshold));
    const double cost_left = std::max(0.0, end - double(o.spent));
    return std::uint64_t(cost_left * double(o.taken) / double(o.spent));
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

} // namespace candela
