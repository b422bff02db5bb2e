#include "candela/render/distributed.h"

#include "candela/render/adaptive.h"

#include "candela/util/error.h"
#include "candela/util/log.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>

#ifdef CANDELA_WITH_MPI
#include <mpi.h>
#endif

namespace candela {

namespace {

#ifdef CANDELA_WITH_MPI
/// Elements per MPI call: MPI counts are `int`, and a bounded message also bounds the
/// temporary buffers of the MPI library.
constexpr std::size_t kMaxMessageElements = std::size_t(1) << 26;

template <typename T> MPI_Datatype mpi_type() {
    if constexpr (std::is_same_v<T, double>)
        return MPI_DOUBLE;
    else if constexpr (std::is_same_v<T, float>)
        return MPI_FLOAT;
    else if constexpr (std::is_same_v<T, std::uint32_t>)
        return MPI_UINT32_T;
    else if constexpr (std::is_same_v<T, std::uint64_t>)
        return MPI_UINT64_T;
    else
        static_assert(sizeof(T) == 0, "no MPI type for this element type");
}

/// Element-wise sum (or minimum) of `v` over all ranks onto rank 0, in place on rank 0.
template <typename T> void reduce_sum(std::vector<T>& v, bool root, MPI_Op op = MPI_SUM) {
    for (std::size_t off = 0; off < v.size(); off += kMaxMessageElements) {
        int n = int(std::min(kMaxMessageElements, v.size() - off));
        if (root)
            MPI_Reduce(MPI_IN_PLACE, v.data() + off, n, mpi_type<T>(), op, 0, MPI_COMM_WORLD);
        else
            MPI_Reduce(v.data() + off, nullptr, n, mpi_type<T>(), op, 0, MPI_COMM_WORLD);
    }
}
#endif

} // namespace

bool distributed_built_in() {
#ifdef CANDELA_WITH_MPI
    return true;
#else
    return false;
#endif
}

bool launched_by_mpi() {
    // Open MPI's mpirun, PMIx-based launchers (Slurm srun, prterun), MPICH's Hydra.
    for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
        if (std::getenv(var)) return true;
    return false;
}

DistributedContext::DistributedContext() {
#ifdef CANDELA_WITH_MPI
    if (!launched_by_mpi()) return;
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) throw Error(ErrorKind::Internal, "MPI is already initialised");
    int provided = 0;
    if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        throw Error(ErrorKind::Internal, "MPI_Init_thread failed");
    mpi_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (provided < MPI_THREAD_FUNNELED) {
        MPI_Finalize();
        mpi_ = false;
        throw Error(ErrorKind::Internal, "the MPI library does not support threads "
                                         "(MPI_THREAD_FUNNELED)");
    }
#endif
}

DistributedContext::~DistributedContext() {
#ifdef CANDELA_WITH_MPI
    if (mpi_) MPI_Finalize();
#endif
}

void DistributedContext::reduce_film(Film& film) const {
#ifdef CANDELA_WITH_MPI
    if (size_ == 1) return;
    const bool is_root = root();
    film.for_each_sum([&](auto& v, Film::Combine c) {
        reduce_sum(v, is_root, c == Film::Combine::Min ? MPI_MIN : MPI_SUM);
    });
#else
    (void)film;
#endif
}

bool DistributedContext::any(bool flag) const {
#ifdef CANDELA_WITH_MPI
    if (size_ == 1) return flag;
    int in = flag ? 1 : 0, out = 0;
    MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
    return out != 0;
#else
    return flag;
#endif
}

void DistributedContext::reduce_counters(std::vector<std::uint64_t>& counters) const {
#ifdef CANDELA_WITH_MPI
    if (size_ > 1) reduce_sum(counters, root());
#else
    (void)counters;
#endif
}

void DistributedContext::broadcast(std::vector<std::uint8_t>& bytes) const {
#ifdef CANDELA_WITH_MPI
    if (size_ == 1) return;
    for (std::size_t off = 0; off < bytes.size(); off += kMaxMessageElements) {
        int n = int(std::min(kMaxMessageElements, bytes.size() - off));
        MPI_Bcast(bytes.data() + off, n, MPI_BYTE, 0, MPI_COMM_WORLD);
    }
#else
    (void)bytes;
#endif
}

void DistributedContext::abort_job(int status) const {
#ifdef CANDELA_WITH_MPI
    if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, status);
#else
    (void)status;
#endif
}

SampleBlock rank_block(int first, int last, int rank, int size) {
    if (size < 1 || rank < 0 || rank >= size || last < first)
        throw Error(ErrorKind::Internal, "rank_block: invalid rank, size or range");
    const long long n = last - first;
    SampleBlock b;
    b.first = first + int(n * rank / size);
    b.last = first + int(n * (rank + 1) / size);
    return b;
}

void run_distributed(const DistributedContext& ctx, const Scene& scene, const Accel& accel,
                     const RenderSettings& s, RenderState& state, RenderStats& stats,
                     const std::atomic<bool>* stop,
                     const std::function<void(const RenderState&)>& on_pass) {
    Renderer global(scene, accel, s);
    if (ctx.size() == 1) {
        global.run(state, stats, stop, on_pass);
        return;
    }
    auto t0 = std::chrono::steady_clock::now();
    if (s.adaptive == AdaptiveKind::Relative)
        throw Error(ErrorKind::Usage, "candela: error: --adaptive relative is not supported "
                                      "under MPI yet (use cs184, or render parts with "
                                      "--sample-offset and candela merge)");
    const bool adaptive = s.adaptive != AdaptiveKind::None;
    // With adaptive sampling a pass is one batch, as in one process: the decisions between
    // batches shape the image. Otherwise pass boundaries do not change the sums, and every rank
    // gets a whole single-process pass of its own per global pass.
    const int pass_len = adaptive ? global.pass_size() : global.pass_size() * ctx.size();
    const int fw = global.film_width(), fh = global.film_height();

    // This rank's own samples (rank 0 also holds a resumed render's film).
    Film local = ctx.root() ? std::move(state.film) : global.start().film;
    Film reduced;
    bool have_reduced = false;
    std::uint64_t samples = 0, rays = 0, shadow_rays = 0, dropped = 0;
    double busy = 0.0; // seconds this rank spent rendering its blocks (load-balance report)
    int passes = 0;
    while (!state.finished(s.spp)) {
        if (ctx.any(stop && stop->load())) {
            stats.interrupted = true;
            break;
        }
        // The time budget is rank 0's clock, so that every rank stops after the same pass.
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (ctx.any(ctx.root() && s.time_budget > 0.0 && elapsed >= s.time_budget)) {
            stats.out_of_time = true;
            break;
        }
        const int first = state.next_sample;
        const int last = std::min(s.spp, first + pass_len);
        const SampleBlock block = rank_block(first, last, ctx.rank(), ctx.size());
        if (block.size() > 0) {
            // One pass of the single-process renderer over this rank's block: its sample
            // indices are sample_offset + [block.first, block.last), and with spp equal to the
            // block it makes no adaptive decision of its own (that is global, below).
            RenderSettings ls = s;
            ls.sample_offset = s.sample_offset + std::uint64_t(block.first);
            ls.spp = block.size();
            ls.pass_spp = block.size();
            ls.adaptive_batch = block.size();
            ls.quiet = true;
            ls.time_budget = 0.0;
            Renderer part(scene, accel, ls);
            RenderState sub;
            sub.film = std::move(local);
            sub.done = state.done;
            RenderStats ps;
            part.run(sub, ps);
            busy += ps.seconds;
            local = std::move(sub.film);
            samples += ps.samples;
            rays += ps.rays;
            shadow_rays += ps.shadow_rays;
            dropped += ps.dropped;
        }
        state.next_sample = last;
        ++state.passes;
        ++passes;

        const bool sync = adaptive || on_pass || state.finished(s.spp);
        if (!sync) continue;
        reduced = local;
        ctx.reduce_film(reduced);
        have_reduced = true;
        if (adaptive && last < s.spp) {
            // Rank 0 decides on the global film; every rank then skips the same pixels.
            if (ctx.root())
                for (int y = 0; y < fh; ++y)
                    for (int x = 0; x < fw; ++x) {
                        std::size_t pi = std::size_t(y) * fw + x;
                        if (!state.done[pi] &&
                            adaptive_pixel_converged(reduced, x, y, s.adaptive_tol))
                            state.done[pi] = 1;
                    }
            ctx.broadcast(state.done);
            if (std::all_of(state.done.begin(), state.done.end(),
                            [](std::uint8_t d) { return d != 0; }))
                state.next_sample = s.spp;
        }
        if (on_pass && ctx.root()) {
            RenderState global_state;
            global_state.film = reduced;
            global_state.next_sample = state.next_sample;
            global_state.passes = state.passes;
            global_state.done = state.done;
            on_pass(global_state);
        }
    }
    // A render stopped early has not synchronised its last passes yet.
    if (!have_reduced || stats.interrupted || stats.out_of_time) {
        reduced = local;
        ctx.reduce_film(reduced);
    }
    state.film = ctx.root() ? std::move(reduced) : std::move(local);

    // Counters summed over ranks, then each rank's busy time in microseconds in its own slot.
    std::vector<std::uint64_t> counters = {samples, rays, shadow_rays, dropped};
    counters.resize(4 + std::size_t(ctx.size()), 0);
    counters[4 + std::size_t(ctx.rank())] = std::uint64_t(busy * 1e6);
    ctx.reduce_counters(counters);
    if (ctx.root() && !s.quiet && verbose()) {
        std::uint64_t lo = counters[4], hi = counters[4];
        std::string list;
        for (int r = 0; r < ctx.size(); ++r) {
            const std::uint64_t us = counters[4 + std::size_t(r)];
            lo = std::min(lo, us);
            hi = std::max(hi, us);
            char buf[32];
            std::snprintf(buf, sizeof buf, " %.3f", double(us) * 1e-6);
            list += buf;
        }
        std::fprintf(stderr, "candela: render seconds per rank:%s (slowest/fastest %.3f)\n",
                     list.c_str(), lo > 0 ? double(hi) / double(lo) : 1.0);
    }
    stats.samples = counters[0];
    stats.rays = counters[1];
    stats.shadow_rays = counters[2];
    stats.dropped = counters[3];
    stats.passes = passes;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

} // namespace candela
