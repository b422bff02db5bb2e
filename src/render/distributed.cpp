// The MPI context of a distributed render: ranks, reductions and each rank's share of a pass.
#include "candela/render/distributed.h"

#include "candela/render/adaptive.h"

#include "candela/util/check.h"
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

void DistributedContext::reduce_sums(std::vector<std::uint64_t>& values) const {
#ifdef CANDELA_WITH_MPI
    if (size_ > 1) reduce_sum(values, root());
#else
    (void)values;
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

} // namespace candela
