// Huge-page-friendly storage of the builtin BVH's arrays (include/candela/accel/bvh_allocator.h).
#include "candela/accel/bvh_allocator.h"

#include <algorithm>
#include <cstdlib>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace candela {

namespace {
/// Transparent huge page size on x86-64 Linux.
constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;
} // namespace

void* bvh_allocate(std::size_t bytes, std::size_t align) {
    if (bytes >= kHugePageBytes) {
        const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
        void* p = std::aligned_alloc(kHugePageBytes, rounded);
        if (!p) throw std::bad_alloc();
#ifdef __linux__
        madvise(p, rounded, MADV_HUGEPAGE); // a hint: failure only costs speed
#endif
        return p;
    }
    return ::operator new(bytes, std::align_val_t(std::max(align, alignof(std::max_align_t))));
}

void bvh_deallocate(void* p, std::size_t bytes, std::size_t align) noexcept {
    if (bytes >= kHugePageBytes)
        std::free(p);
    else
        ::operator delete(p, std::align_val_t(std::max(align, alignof(std::max_align_t))));
}

} // namespace candela
