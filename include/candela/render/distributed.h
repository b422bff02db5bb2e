#pragma once
// Distributed rendering over MPI (`mpirun -np N candela render ...`). Every rank loads the scene
// and builds its own accelerator; each pass of sample indices [first, last) is split into N
// contiguous blocks, rank r rendering block r for *every* pixel. Film sums are reduced onto
// rank 0, which alone writes files. With adaptive sampling the sums are reduced after every
// pass, rank 0 makes the convergence decision on the global film and broadcasts it, so every
// rank skips the same pixels and the sample-count image is the one a single process makes.
// The result therefore does not depend on N beyond floating-point summation order
// (docs/distributed.md states the bound).
//
// Without CANDELA_WITH_MPI, or when the process was not started by an MPI launcher, the context
// is a one-rank world and run_distributed() is exactly Renderer::run().
#include "candela/render/renderer.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

namespace candela {

/// True when this binary was built with MPI (-DCANDELA_WITH_MPI=ON).
bool distributed_built_in();

/// True when the environment shows an MPI launcher started this process (mpirun, srun...).
bool launched_by_mpi();

/// The processes of one render. Initialises MPI (thread level FUNNELED: only the main thread
/// communicates, the TBB workers never do) when built in and launched by an MPI launcher, and
/// finalises it on destruction. At most one context may exist per process.
class DistributedContext {
  public:
    DistributedContext();
    ~DistributedContext();
    DistributedContext(const DistributedContext&) = delete;
    DistributedContext& operator=(const DistributedContext&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    bool root() const { return rank_ == 0; }

    /// Sums `film` of every rank element-wise onto rank 0's `film` (collective). On other
    /// ranks `film` is left unchanged. All films must have the same size and channels.
    void reduce_film(Film& film) const;
    /// Logical OR of `flag` over all ranks (collective); `flag` itself with one rank.
    bool any(bool flag) const;
    /// Sums each counter over all ranks onto rank 0 (collective; others keep their values).
    void reduce_counters(std::vector<std::uint64_t>& counters) const;
    /// Copies rank 0's bytes to every rank (collective); `bytes` must have the same size on
    /// every rank.
    void broadcast(std::vector<std::uint8_t>& bytes) const;

    /// Ends every process of the job with `status` (MPI_Abort). Only for a failure on one
    /// rank in the middle of the render, where the others would wait forever in a collective
    /// operation; with one rank it returns and the caller reports the error normally.
    void abort_job(int status) const;

  private:
    int rank_ = 0, size_ = 1;
    bool mpi_ = false; ///< MPI was initialised by this context
};

/// Half-open range of sample indices.
struct SampleBlock {
    int first = 0, last = 0;
    int size() const { return last - first; }
};

/// Rank `rank`'s share of the sample indices [first, last) among `size` ranks: contiguous
/// blocks in rank order whose sizes differ by at most one; together they tile [first, last).
SampleBlock rank_block(int first, int last, int rank, int size);

/// Renders `state` to completion (or until `stop` is set on any rank at a pass boundary)
/// with the passes split over the ranks of `ctx`. Same contract as Renderer::run(); with one
/// rank it *is* Renderer::run(). With several ranks:
///  - on ranks other than 0 the film in `state` is reset first (a resumed film lives on rank 0);
///  - on rank 0 `state.film` ends as the global film and `on_pass` (called only on rank 0)
///    sees the global state; the film of other ranks holds only their own samples;
///  - adaptive sampling: `cs184` and `none` only (throws Error(Usage) for `relative`, whose
///    per-pixel sample ranges depend on the film between passes); the time budget is rank 0's
///    clock, and a stop ends the render on every rank;
///  - `on_pass` must be set on every rank or on none (it decides when films are reduced);
///  - `stats` on rank 0 holds the sums over ranks of samples, rays and drops, and rank 0's wall
///    time; `stats.interrupted` is the same on every rank.
void run_distributed(const DistributedContext& ctx, const Scene& scene, const Accel& accel,
                     const RenderSettings& settings, RenderState& state, RenderStats& stats,
                     const std::atomic<bool>* stop = nullptr,
                     const std::function<void(const RenderState&)>& on_pass = {});

} // namespace candela
