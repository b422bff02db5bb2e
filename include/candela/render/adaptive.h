#pragma once
// Adaptive sampling decisions, separate from the renderer so they can be tested on synthetic
// statistics.
//
// cs184: spec §5.4, a pixel stops when its own 95% confidence half-width on luminance falls
// below tol times its mean.
//
// relative: a global budget (the cost of spp x pixels uniform samples) is spent in passes. The
// first pass gives every pixel the same batch; each later pass hands its share of the budget to the
// pixels in proportion to how far they are below their optimal sample count. The per-pixel error
// estimate is the relative variance of one sample, var / (mu^2 + floor), of each pixel, averaged
// over its (2r+1)^2 neighbourhood WITHOUT the pixel itself: the floor keeps dark pixels from
// being starved (their relative error is not taken as infinite), and leaving the pixel out makes
// its share independent of the values of its own samples. A count chosen from the samples it
// then averages is a stopping rule, which biases the mean (a pixel whose first samples happen to
// agree gets fewer, so its early luck weighs more); chosen from the neighbours' samples, which
// are independent of the pixel's, it is not. The cost per sample is smoothed over the same
// window without the pixel, since a path's cost correlates with the light it carries. What still
// pools every pixel is global: the scale of the allocation and the end of the render, which
// one pixel moves by O(1/pixels). Minimising sum_p e_p / n_p subject to sum_p n_p = N gives n_p
// proportional to sqrt(e_p). Samples do not all cost the same, though: a camera ray into the black
// background is one cheap query, a path through a closed box takes about ten times as long. With
// c_p the cost of one sample of pixel p, minimising sum_p e_p / n_p subject to sum_p c_p n_p = C
// gives n_p = C sqrt(e_p / c_p) / sum_q sqrt(e_q c_q), and the budget is counted in cost units. The
// render stops when the estimated relative RMS error of the image is below tol or the budget is
// spent.
//
// The three samplers (uniform, cs184, relative) are pass policies (PassPolicy below): what each
// pass renders and what follows from it, and every other question whose answer depends on the
// sampler (the state a render starts from, reopening a finished one, what is left, which
// settings it reads, how it explains itself). The render loop (renderer.cpp) keeps the tiles,
// the films and the processes of a group; it asks the policy once per pass.
#include "candela/render/render_state.h"
#include "candela/render/settings.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace candela {

/// Per-pixel luminance statistics of a film, row-major.
struct LumStatsMap {
    int width = 0, height = 0;
    std::vector<double> mean;     ///< sample mean of luminance
    std::vector<double> var;      ///< sample variance of luminance (n-1 denominator)
    std::vector<std::uint32_t> n; ///< samples taken (finite or dropped: indices used)
    /// Optional per-channel statistics (3 per pixel: R, G, B), when the film keeps sums of
    /// squares. With them the relative error is that of each channel, averaged, which is what
    /// relMSE measures: a coloured surface's dark channels are relatively noisier than its
    /// luminance.
    std::vector<double> mean_rgb, var_rgb;
};

/// The CS184 criterion (spec §5.4): true when 1.96 sigma / sqrt(n) <= tol * mu. Needs n >= 2.
bool cs184_converged(double mean, double var, std::uint32_t n, double tol);

class Film;
/// cs184_converged() on pixel (x, y) of a film with lum_stats.
bool adaptive_pixel_converged(const Film& film, int x, int y, double tol);

/// The luminance statistics of every pixel of a film with lum_stats, plus per-channel ones when
/// it keeps the variance channel; n counts sample indices used (finite plus dropped). Fills `m`
/// in place: a map of the same film size keeps its storage from pass to pass.
void fill_lum_stats(const Film& film, LumStatsMap& m);

/// Whether a pixel's own value takes part in its neighbourhood mean. The relative sampler's
/// allocation excludes it (see above); its estimate of the image's error includes it.
enum class WindowCentre { Include, Exclude };

/// Relative variance of one sample per pixel (dimensionless), var / (mu^2 + floor) with the dark
/// floor of adaptive.cpp, of luminance or averaged over R, G, B when the map has per-channel
/// statistics; each pixel's value is then averaged over the pixels of its (2 radius + 1)^2
/// neighbourhood that have at least two samples (window_mean()).
std::vector<double> relative_error_map(const LumStatsMap& stats, int radius, WindowCentre centre);

/// Mean of the values of the valid pixels in each pixel's (2 radius + 1)^2 neighbourhood,
/// clipped at the frame, with or without the pixel itself. Where the neighbourhood has no valid
/// pixel: with WindowCentre::Include 0; with Exclude the mean of every other valid pixel of the
/// image (0 when there is none), so that the value still does not depend on the pixel's own.
/// Row-major, w x h.
std::vector<double> window_mean(const std::vector<double>& values,
                                const std::vector<std::uint8_t>& valid, int w, int h, int radius,
                                WindowCentre centre);

/// Estimated relative RMS error of the image's pixel means: sqrt(mean_p e_p / n_p).
double estimated_relative_rms(const LumStatsMap& stats, const std::vector<double>& error_map);

/// Cost of one sample per pixel (cost units per sample), smoothed over the same
/// (2 radius + 1)^2 neighbourhood as relative_error_map(), with or without the pixel itself: the
/// window's total cost divided by its total samples. `cost` holds each pixel's total cost so far
/// (RenderState::cost). Pixels whose window has no sample get the image's mean cost per sample.
/// Throws Error(Internal) when the sizes disagree or no sample has any cost.
std::vector<double> cost_per_sample_map(const LumStatsMap& stats,
                                        const std::vector<std::uint64_t>& cost, int radius,
                                        WindowCentre centre);

/// Samples per pixel for the next pass of the relative sampler, with every sample costing the
/// same: allocate_pass() with unit costs and a budget of `budget` samples.
std::vector<int> allocate_pass(const LumStatsMap& stats, const std::vector<double>& error_map,
                               std::uint64_t budget, int max_per_pixel,
                               std::uint64_t rounding_seed);

/// Samples per pixel for the next pass of the relative sampler, cost-aware. `cost_map` is the
/// cost of one sample of each pixel (cost units, > 0); `budget` is the pass's budget in cost
/// units. The optimal allocation of all the cost spent once this pass is done (the cost of the
/// samples already taken, sum_p c_p n_p, plus `budget`) is n*_p proportional to
/// sqrt(e_p / c_p), capped at max_per_pixel; the pass gives each pixel samples in proportion to
/// its deficit n*_p - n_p, scaled so that their cost, sum_p c_p a_p, is `budget` (or less when
/// the deficits are smaller). Each count is rounded on its own, down or up with the probability
/// of its fractional part, by a uniform hashed from (rounding_seed, pixel): the expected count is
/// the real-valued share and the rounding of one pixel never depends on another's error. (A
/// remainder carried from pixel to pixel, which would keep the total exact, would make a pixel's
/// count depend on its neighbour's share, whose window holds the pixel itself.) The cost handed
/// out is the budget in expectation, within a few samples' cost in practice. Deterministic: it
/// depends only on the inputs. Returns one count per pixel.
std::vector<int> allocate_pass(const LumStatsMap& stats, const std::vector<double>& error_map,
                               const std::vector<double>& cost_map, double budget,
                               int max_per_pixel, std::uint64_t rounding_seed);

/// Relative sampler: one pixel may take up to this many times the average budget (-s). Large
/// enough for caustics and edges to get the samples they need, small enough that a few
/// fireflies cannot swallow the frame's budget.
constexpr int kRelativeMaxOversampling = 8;

/// Largest sample count of one pixel under the relative adaptive sampler with budget `spp`: the
/// budget is spp x pixels on average, and one pixel may take up to kRelativeMaxOversampling
/// times that (at most kMaxSpp).
int relative_max_per_pixel(int spp);

/// The samples of one pass: pixel p takes the sample indices [first_of(p), first_of(p) +
/// count_of(p)), which a group of processes splits among its ranks.
struct PassPlan {
    int first = 0; ///< every pixel's first index, unless `start` gives each its own
    int size = 0;  ///< every pixel's count, unless `count` gives each its own
    std::vector<std::uint32_t> start; ///< per pixel (relative): its samples so far
    std::vector<int> count;           ///< per pixel (cs184, relative): its samples this pass
    int first_of(std::size_t p) const { return start.empty() ? first : int(start[p]); }
    int count_of(std::size_t p) const { return count.empty() ? size : count[p]; }
};

/// How a render spends its samples, pass by pass: every pixel the same (--adaptive none), each
/// pixel until the CS184 criterion stops it, or a cost budget spread by the relative error
/// (make_pass_policy()). The render loop asks it for a plan before every pass and lets it decide
/// after; in a group of processes only the root does, on the group's film, and the loop shares
/// the plan and the state's decisions with the other ranks. A policy knows nothing of tiles,
/// threads or ranks; it is called a few times a pass, never per sample. Everything else that
/// depends on the sampler is asked of it too: the layout of a fresh state, reopening a finished
/// render for a refinement (render/refine.h), whether a render is over and what is left of it,
/// which settings it reads, and the words the render command explains it with.
class PassPolicy {
  public:
    virtual ~PassPolicy() = default;

    // The state.

    /// A fresh state for a w x h film with the channels `aovs`: luminance statistics when the
    /// policy reads the film, a stop flag per pixel, and (relative) a cost per pixel.
    virtual RenderState start(int w, int h, const AovSet& aovs) const;
    /// Readies a state to start or resume from (its per-pixel costs, what it has sampled).
    /// Throws Error(Usage) when the state cannot be continued under this policy.
    virtual void prepare(RenderState& st) = 0;
    /// Whether the render of `st` has ended: its samples taken or the sampler stopped it
    /// (RenderState::stopped).
    virtual bool finished(const RenderState& st) const {
        return st.stopped || st.next_sample >= s_.spp;
    }
    /// Readies `st`, the state of a render with settings `before` (`finished` under them, or
    /// interrupted), to continue under this policy's settings, which differ from `before` by a
    /// larger -s or a lower noise threshold (reopen_for_refinement() checks them): the state a
    /// render with these settings from the start would have at that point, as far as the
    /// sampler allows (render/refine.h says how far).
    virtual void reopen(const RenderSettings& before, bool finished, RenderState& st) const = 0;

    // The passes.

    /// Whether plan() and decide() read the film (the loop then gives the root the group's film
    /// before every decision).
    virtual bool reads_film() const = 0;
    /// The next pass, from the state after the last one.
    virtual void plan(const RenderState& st, PassPlan& plan) = 0;
    /// After the pass `plan`, whose samples the state's film now holds: where the next pass
    /// starts, which pixels stop, the budget, and whether the render is over (st.stopped).
    virtual void decide(RenderState& st, const PassPlan& plan) = 0;
    /// An estimate of the samples still to come: the progress target, and a refinement's
    /// forecast (after prepare()).
    virtual std::uint64_t samples_left(const RenderState& st) const = 0;
    /// What ended a render that was not stopped by a request or the time budget.
    virtual StopReason stop_reason(const RenderState& st) const = 0;
    /// Relative sampler, after the last decision (or prepare() of a state that has a budget):
    /// the estimated relative RMS error of the image (-1 when there is none) and the share of
    /// the cost budget spent.
    virtual double estimated_error() const { return -1.0; }
    virtual double budget_spent() const { return 0.0; }

    // The settings: which ones the policy reads (the others do nothing under it) and the
    // bounds they set.

    /// -a's BATCH (RenderSettings::adaptive_batch).
    virtual bool reads_batch() const { return true; }
    /// -a's TOLERANCE as the per-pixel criterion (RenderSettings::adaptive_tol).
    virtual bool reads_tolerance() const { return false; }
    /// --noise-threshold, or -a's TOLERANCE in its place (RenderSettings::noise_threshold).
    virtual bool reads_noise_threshold() const { return false; }
    /// --pass-spp (RenderSettings::pass_spp).
    virtual bool reads_pass_spp() const { return false; }
    /// Whether pixels may end with different sample counts (a sample-rate image and a map of
    /// where the samples went then say something).
    virtual bool spreads_samples() const { return true; }
    /// Most samples one pixel can take: -s, or more under the relative sampler.
    virtual int most_per_pixel() const { return s_.spp; }

    // The words: what the render command prints about the sampler.

    /// What -s means under this sampler, for the line before the render: a count, a cap or a
    /// budget.
    virtual std::string sampling_text() const = 0;
    /// How a render that spreads its samples bounds them, for the summary ("" when it does not
    /// spread them).
    virtual std::string summary_text() const { return ""; }
    /// How far the render of `st` got, in the words of sampling_text().
    virtual std::string reached_text(const RenderState& st) const;
    /// How far the render of `st` got, as a fraction of the whole.
    virtual double reached(const RenderState& st) const;
    /// Why a render with these statistics stopped on a film of `pixels` pixels.
    virtual std::string stop_text(const RenderStats& stats, std::size_t pixels) const;
    /// Why a finished render leaves a refinement nothing to do.
    virtual std::string finished_text() const {
        return "every pixel has its samples or has converged";
    }

  protected:
    explicit PassPolicy(const RenderSettings& s) : s_(s) {}
    const RenderSettings& s_;
};

/// The policy of `s.adaptive`, which keeps a reference to `s`. `ranks`: the processes rendering
/// together; without decisions between passes (--adaptive none) each of them renders a whole
/// pass of its own.
std::unique_ptr<PassPolicy> make_pass_policy(const RenderSettings& s, int ranks = 1);

/// Settings that select each sampler with its own parameters, for code that chooses the sampler
/// itself (benches, diagnostics, tools) rather than from the command line.
void use_uniform_sampler(RenderSettings& s);
void use_cs184_sampler(RenderSettings& s, int batch, float tolerance);
void use_relative_sampler(RenderSettings& s, int batch, float noise_threshold);

} // namespace candela
