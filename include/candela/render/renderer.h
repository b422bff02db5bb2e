#pragma once
// Drives a render: tiles in parallel (TBB), passes of samples, adaptive stopping, progress.
// The image depends only on (scene, settings): every pixel sample draws its numbers from a
// sampler seeded by (seed, pixel, sample index) and is added in index order by one thread, so
// any thread count and tile order give a bit-identical film. The state between passes
// (RenderState) is all there is to a render in progress, so a render stopped after pass k and
// resumed from its state is bit-identical to one that never stopped.
#include "candela/accel/accel.h"
#include "candela/render/film.h"
#include "candela/render/settings.h"
#include "candela/scene/scene.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
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

struct RenderStats {
    double seconds = 0.0;
    std::uint64_t samples = 0;     ///< camera samples taken (including dropped ones)
    std::uint64_t camera_rays = 0; ///< closest-hit queries of camera rays
    std::uint64_t rays = 0;        ///< closest-hit queries (camera rays included)
    std::uint64_t shadow_rays = 0; ///< occlusion queries
    std::uint64_t dropped = 0;     ///< non-finite samples dropped
    int passes = 0;                ///< passes run by this call
    bool interrupted = false;      ///< stopped by the stop flag before the target
    bool out_of_time = false;      ///< stopped by the time budget before the target
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
    int next_sample = 0;            ///< the next pass starts at this sample index
    int passes = 0;                 ///< passes finished so far
    std::vector<std::uint8_t> done; ///< per pixel: adaptive sampling stopped it (cs184)
    /// Relative sampler: per pixel, the cost of every sample taken so far, in cost units (a
    /// weighted count of samples and ray queries, see cost_units()). A count, not a time, so it
    /// is the same for any thread count and across a resume. Empty in the other modes.
    std::vector<std::uint64_t> cost;
    /// Relative sampler: the total cost the render may spend, in cost units. Set after the
    /// first pass to spp x pixels x that pass's mean cost per sample (the cost of a uniform
    /// render of spp samples, estimated from the first pass, which is uniform); 0 before.
    std::uint64_t cost_budget = 0;
    bool finished(int spp) const { return next_sample >= spp; }
};

/// The processes that render one image together (MPI ranks), as the render loop sees them.
/// Rank 0, the root, makes the decisions between passes and ends with the image. One process
/// is a group of one (single_process()), where every operation is a no-op.
class RenderGroup {
  public:
    virtual ~RenderGroup() = default;
    virtual int rank() const = 0;
    virtual int size() const = 0;
    bool root() const { return rank() == 0; }
    /// Sums `film` of every rank element-wise onto the root's `film` (collective); on the
    /// other ranks `film` is left unchanged. All films have the same size and channels.
    virtual void reduce_film(Film& film) const = 0;
    /// Logical OR of `flag` over all ranks (collective).
    virtual bool any(bool flag) const = 0;
    /// Sums each counter over all ranks onto the root (collective; others keep their values).
    virtual void reduce_counters(std::vector<std::uint64_t>& counters) const = 0;
    /// Copies the root's bytes to every rank (collective); same size on every rank.
    virtual void broadcast(std::vector<std::uint8_t>& bytes) const = 0;
};

/// The group of one process.
const RenderGroup& single_process();

class Renderer {
  public:
    Renderer(const Scene& scene, const Accel& accel, const RenderSettings& settings);

    /// A fresh state: empty film sized to the region (or full frame), no pass done.
    RenderState start() const;

    /// Runs passes on `state` until the sample target is reached, adaptive sampling has
    /// stopped every pixel, or `stop` (set by another thread or a signal handler) is true at a
    /// pass boundary. `on_pass`, when set, is called after every pass (for checkpoints).
    ///
    /// With a group of several processes (MPI ranks; every rank calls run() with the same
    /// settings and a state from start(), the root's possibly a resumed one) each pass's sample
    /// range of every pixel is split into one contiguous block per rank (rank_block()), the
    /// decisions between passes (adaptive sampling, the time budget, a stop on any rank) are
    /// made on the root's clock and film and shared, and on the root the state ends as the
    /// whole group's: its film, costs and counters are the sums over the ranks, `on_pass` (set
    /// on every rank or on none) is called there with that state. The other ranks' films hold
    /// their own samples. The image does not depend on the number of ranks beyond the order
    /// of the film's floating-point sums.
    void run(RenderState& state, RenderStats& stats, const std::atomic<bool>* stop = nullptr,
             const std::function<void(const RenderState&)>& on_pass = {},
             const RenderGroup& group = single_process()) const;

    /// start() + run(): the whole render.
    Film render(RenderStats& stats, const std::atomic<bool>* stop = nullptr) const;

    int film_width() const { return s_.region.full() ? s_.width : s_.region.w; }
    int film_height() const { return s_.region.full() ? s_.height : s_.region.h; }
    /// Samples per pixel of each pass (with the relative adaptive sampler: the average).
    int pass_size() const;
    /// Largest sample count of one pixel under the relative adaptive sampler: the budget is
    /// spp x pixels on average, and one pixel may take up to this many.
    int relative_max_per_pixel() const;

  private:
    StopReason stop_reason(const RenderStats& stats, const RenderState& st,
                           StopReason relative_stop) const;

    const Scene& scene_;
    const Accel& accel_;
    RenderSettings s_;
};

/// Samples per pixel of each pass of a render with settings `s` (Renderer::pass_size()).
int pass_size(const RenderSettings& s);

/// Cost units of `samples` camera samples that made `queries` ray queries in all (closest-hit
/// plus occlusion, camera rays included): a fixed cost per sample that covers its camera ray,
/// plus a larger one for every further query (renderer.cpp gives the weights and how they were
/// measured). A deterministic stand-in for time: the relative sampler's budget and allocation
/// are counted in these units.
std::uint64_t cost_units(std::uint64_t queries, std::uint64_t samples);

/// Relative sampler: one pixel may take up to this many times the average budget (-s). Large
/// enough for caustics and edges to get the samples they need, small enough that a few
/// fireflies cannot swallow the frame's budget.
constexpr int kRelativeMaxOversampling = 8;

/// Tile edge in pixels: small enough to balance load on few cores, large enough that the
/// per-tile overhead (a task, a sampler set-up per pixel) is negligible.
constexpr int kTileSize = 16;

} // namespace candela
