#pragma once
// Drives a render: tiles in parallel (TBB), passes of samples, adaptive stopping, progress.
// The image depends only on (scene, settings): every pixel sample draws its numbers from a
// sampler seeded by (seed, pixel, sample index) and is added in index order by one thread, so
// any thread count and tile order give a bit-identical film. The state between passes
// (RenderState) is all there is to a render in progress, so a render stopped after pass k and
// resumed from its state is bit-identical to one that never stopped.
#include "candela/accel/accel.h"
#include "candela/render/adaptive.h"
#include "candela/render/counters.h"
#include "candela/render/film.h"
#include "candela/render/render_state.h"
#include "candela/render/settings.h"
#include "candela/scene/scene.h"

#include <atomic>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

namespace candela {

/// Half-open range of sample indices.
struct SampleBlock {
    int first = 0, last = 0;
    int size() const { return last - first; }
};

/// Rank `rank`'s share of the sample indices [first, last) among `size` ranks: contiguous
/// blocks in rank order whose sizes differ by at most one; together they tile [first, last).
SampleBlock rank_block(int first, int last, int rank, int size);

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
    /// Sums `values` element-wise over all ranks onto the root (collective; the others keep
    /// theirs). Every rank passes as many values.
    virtual void reduce_sums(std::vector<std::uint64_t>& values) const = 0;
    /// reduce_sums() of every counter.
    void reduce(RenderCounters& counters) const;
    /// Copies the root's bytes to every rank (collective); same size on every rank.
    virtual void broadcast(std::vector<std::uint8_t>& bytes) const = 0;

    // What a rank does by its role in the pass loop, so that the loop asks no rank questions.

    /// Runs `decide` on the root, then copies the root's `outcome` vectors (what `decide` wrote
    /// into them), sizes and all, to every rank (collective).
    template <class Decide, class... T>
    void decide_on_root(const Decide& decide, std::vector<T>&... outcome) const {
        if (root()) decide();
        (share(outcome), ...);
    }
    /// The root's `flag` on every rank (collective): a decision made on the root's clock.
    bool root_flag(bool flag) const { return any(root() && flag); }
    /// Runs `report` on the root, which reports for the group (progress, checkpoints).
    template <class Report> void report_on_root(const Report& report) const {
        if (root()) report();
    }
    /// `on_root` on the root, `elsewhere` on the other ranks.
    template <class T> T root_or(T on_root, T elsewhere) const {
        return root() ? std::move(on_root) : std::move(elsewhere);
    }
    /// Where this rank renders its own samples. Alone it renders into the state itself: returns
    /// false and leaves `own_film` and `own_cost` alone. In a group the state becomes the sum
    /// of the ranks' own (gather()): `own_film` and `own_cost` start as the state's on the root
    /// (a resumed render's samples) and as `fresh()`'s on the others; returns true.
    bool own_share(const RenderState& st, const std::function<RenderState()>& fresh, Film& own_film,
                   std::vector<std::uint64_t>& own_cost) const;
    /// Makes the root's state film and costs the sums of every rank's own (collective); the
    /// other ranks' state film becomes the sum too, their costs stay. Nothing alone.
    void gather(const Film& own_film, const std::vector<std::uint64_t>& own_cost,
                RenderState& st) const;
    /// Sums each rank's `busy` seconds onto the root, which prints them and the ratio of the
    /// slowest to the fastest when `report` is set and the group has several ranks (collective).
    void report_balance(double busy, bool report) const;

  private:
    /// Copies the root's `v`, size and all, to every rank (collective; nothing alone).
    template <class T> void share(std::vector<T>& v) const {
        if (size() == 1) return;
        std::uint64_t n = v.size();
        std::vector<std::uint8_t> bytes(sizeof n);
        std::memcpy(bytes.data(), &n, sizeof n);
        broadcast(bytes);
        std::memcpy(&n, bytes.data(), sizeof n);
        std::vector<std::uint8_t> data(std::size_t(n) * sizeof(T));
        if (root() && !data.empty()) std::memcpy(data.data(), v.data(), data.size());
        broadcast(data);
        v.resize(std::size_t(n));
        if (!data.empty()) std::memcpy(v.data(), data.data(), data.size());
    }
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

  private:
    const Scene& scene_;
    const Accel& accel_;
    RenderSettings s_;
};

/// Cost units of `samples` camera samples that made `queries` ray queries in all (closest-hit
/// plus occlusion, camera rays included): a fixed cost per sample that covers its camera ray,
/// plus a larger one for every further query (renderer.cpp gives the weights and how they were
/// measured). A deterministic stand-in for time: the relative sampler's budget and allocation
/// are counted in these units.
std::uint64_t cost_units(std::uint64_t queries, std::uint64_t samples);

/// Tile edge in pixels: small enough to balance load on few cores, large enough that the
/// per-tile overhead (a task, a sampler set-up per pixel) is negligible.
constexpr int kTileSize = 16;

} // namespace candela
