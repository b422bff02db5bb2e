#pragma once
// A render between two passes (RenderState), what one run of the pass loop did (RenderStats) and
// why it stopped (StopReason). Plain data below both the pass loop (renderer.h) and the pass
// policies (adaptive.h), which read and write it.
#include "candela/render/counters.h"
#include "candela/render/film.h"
#include "candela/util/enum_table.h"

#include <cstdint>
#include <vector>

namespace candela {

/// Why a render stopped.
enum class StopReason {
    Interrupted,    ///< the stop flag (a signal)
    TimeBudget,     ///< --time-budget ran out
    AllSamples,     ///< --adaptive none: every pixel has its -s samples; cs184: every pixel that
                    ///< did not converge has them
    Converged,      ///< cs184: every pixel met its tolerance
    NoiseThreshold, ///< relative: the estimated relative RMS error reached the threshold
    BudgetSpent,    ///< relative: the cost budget is spent (a lone pixel: its -s samples)
    NothingToGain,  ///< relative: the allocation gave no pixel another sample
};

/// Machine names of the reasons (the `stop` field of `--progress json`'s done event).
inline constexpr EnumTable<StopReason, 7> kStopReasons = {{
    {StopReason::Interrupted, "interrupted", ""},
    {StopReason::TimeBudget, "time_budget", ""},
    {StopReason::AllSamples, "all_samples", ""},
    {StopReason::Converged, "converged", ""},
    {StopReason::NoiseThreshold, "noise_threshold", ""},
    {StopReason::BudgetSpent, "budget_spent", ""},
    {StopReason::NothingToGain, "nothing_to_gain", ""},
}};

/// What one run() did: its counters (summed over the group's ranks on the root), time, passes
/// and why it stopped.
struct RenderStats : RenderCounters {
    double seconds = 0.0;
    int passes = 0;           ///< passes run by this call
    bool interrupted = false; ///< stopped by the stop flag before the target
    bool out_of_time = false; ///< stopped by the time budget before the target
    StopReason stop = StopReason::AllSamples;
    /// Relative sampler, on the root: the estimated relative RMS error of the image after the
    /// last pass (-1 when no pass decided) and the share of the cost budget spent.
    double estimated_error = -1.0;
    double budget_spent = 0.0;
    double rays_per_second() const {
        return seconds > 0.0 ? double(rays + shadow_rays) / seconds : 0.0;
    }
};

/// A render between two passes.
struct RenderState {
    Film film;
    /// Uniform and cs184 sampling: the next pass starts at this sample index (every pixel has
    /// the samples before it, but the ones cs184 stopped). The relative sampler leaves it at 0:
    /// each pixel continues from its own count.
    int next_sample = 0;
    int passes = 0;                 ///< passes finished so far
    std::vector<std::uint8_t> done; ///< per pixel: adaptive sampling stopped it (cs184)
    /// The sampler ended the render before -s: cs184 stopped every pixel, or the relative
    /// sampler's stop rule (noise threshold, budget, nothing to gain) held.
    bool stopped = false;
    /// Relative sampler: per pixel, the cost of every sample taken so far, in cost units (a
    /// weighted count of samples and ray queries, see cost_units()). A count, not a time, so it
    /// is the same for any thread count and across a resume. Empty in the other modes.
    std::vector<std::uint64_t> cost;
    /// Relative sampler: the total cost the render may spend, in cost units. Set after the
    /// first pass to spp x pixels x that pass's mean cost per sample (the cost of a uniform
    /// render of spp samples, estimated from the first pass, which is uniform); 0 before.
    std::uint64_t cost_budget = 0;
    /// Relative sampler: the share of the cost budget spent so far, in samples per pixel of the
    /// uniform render it stands for: floor(spent / cost_budget x spp), at most spp (a 1x1 film:
    /// its samples). For progress and reports; the render ends by `stopped`.
    int budget_spp = 0;
    bool finished(int spp) const { return stopped || next_sample >= spp; }
};

} // namespace candela
