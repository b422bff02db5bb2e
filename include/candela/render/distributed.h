#pragma once
// Distributed rendering over MPI (`mpirun -np N candela render ...`). Every rank loads the scene
// and builds its own accelerator; the render loop is the single-process one (Renderer::run with
// this context as its RenderGroup): each pass's sample range of every pixel is split into N
// contiguous blocks, rank r rendering block r. Film sums are reduced onto rank 0, which alone
// writes files. With adaptive sampling the sums are reduced after every pass, rank 0 makes the
// decisions on the global film and broadcasts them, so every rank renders the same pixels and
// the sample-count image is the one a single process makes. The result therefore does not
// depend on N beyond floating-point summation order (docs/distributed.md states the bound).
//
// Without CANDELA_WITH_MPI, or when the process was not started by an MPI launcher, the context
// is a one-rank world.
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
class DistributedContext final : public RenderGroup {
  public:
    DistributedContext();
    ~DistributedContext() override;
    DistributedContext(const DistributedContext&) = delete;
    DistributedContext& operator=(const DistributedContext&) = delete;

    int rank() const override { return rank_; }
    int size() const override { return size_; }

    /// The collective operations of RenderGroup over MPI_COMM_WORLD (local no-ops with one
    /// rank).
    void reduce_film(Film& film) const override;
    bool any(bool flag) const override;
    void reduce_sums(std::vector<std::uint64_t>& values) const override;
    void broadcast(std::vector<std::uint8_t>& bytes) const override;

    /// Ends every process of the job with `status` (MPI_Abort). Only for a failure on one
    /// rank in the middle of the render, where the others would wait forever in a collective
    /// operation; with one rank it returns and the caller reports the error normally.
    void abort_job(int status) const;

  private:
    int rank_ = 0, size_ = 1;
    bool mpi_ = false; ///< MPI was initialised by this context
};

} // namespace candela
