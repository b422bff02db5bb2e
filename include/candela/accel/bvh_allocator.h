#pragma once
// Storage of the builtin BVH's arrays (nodes, leaf data, build records): huge-page-friendly
// allocation and a std::vector allocator over it that leaves trivial elements unwritten.
#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace candela {

/// Raw storage of the BVH arrays: blocks of at least 2 MiB are 2 MiB-aligned and advised as
/// transparent-huge-page candidates (Linux), since incoherent traversal touches the arrays at
/// random and would otherwise miss the TLB on most node fetches. Returns memory aligned to at
/// least `align`; throws std::bad_alloc.
void* bvh_allocate(std::size_t bytes, std::size_t align);
/// Releases what bvh_allocate(bytes, align) returned.
void bvh_deallocate(void* p, std::size_t bytes, std::size_t align) noexcept;

/// std::vector allocator over bvh_allocate.
template <class T> struct BvhAllocator {
    using value_type = T;
    BvhAllocator() = default;
    template <class U> BvhAllocator(const BvhAllocator<U>&) {}
    T* allocate(std::size_t n) { return static_cast<T*>(bvh_allocate(n * sizeof(T), alignof(T))); }
    void deallocate(T* p, std::size_t n) noexcept { bvh_deallocate(p, n * sizeof(T), alignof(T)); }
    /// Default-initialises: resize() leaves trivial elements (floats, SIMD boxes) unwritten,
    /// because the builder writes every element once and a zeroing pass would touch tens of
    /// megabytes for nothing. Construction with arguments forwards them as usual.
    template <class U> void construct(U* p) { ::new (static_cast<void*>(p)) U; }
    template <class U, class... Args> void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <class U> bool operator==(const BvhAllocator<U>&) const { return true; }
    template <class U> bool operator!=(const BvhAllocator<U>&) const { return false; }
};
template <class T> using BvhVector = std::vector<T, BvhAllocator<T>>;

} // namespace candela
