#pragma once
// What the builder and the traversal kernels of the builtin BVH agree on: the leaf data
// layout, the packing of leaf references and the deepest tree the builder can produce (which
// sizes the traversal stack). Internal to src/accel.
#include "candela/accel/bvh.h"

#include <cstddef>
#include <cstdint>

namespace candela::bvh_detail {

/// Floats per primitive in the leaf data: 9 coordinates and the reference.
constexpr std::size_t kLeafFloats = 10;

/// Leaf references (Bvh8Node::child) pack the first primitive in 28 bits, below kBvhLeafBit
/// and above the three bits of the primitive count.
constexpr int kPrimIndexBits = 28;
/// The builder refuses scenes with this many primitives or more.
constexpr std::uint32_t kMaxPrims = 1u << kPrimIndexBits;

/// Past this many binary split levels the build switches to index-median splits, which halve
/// the range.
constexpr int kSahMaxDepth = 64;

/// Most inner nodes on a path from the root, the root included. Every inner node's range is at
/// least one binary split level below its parent's, so an inner node at level L has a range
/// of depth at least L - 1 with more than kBvhMaxLeafPrims primitives. From depth
/// kSahMaxDepth on every split halves the range, and fewer than 2^kPrimIndexBits primitives
/// are halved to at most kBvhMaxLeafPrims in fewer than kPrimIndexBits levels, so L stays
/// below kSahMaxDepth + kPrimIndexBits. The builder checks it (Error Internal otherwise).
constexpr int kBvhMaxDepth = kSahMaxDepth + kPrimIndexBits;

} // namespace candela::bvh_detail
