#pragma once
// candela's own bounding volume hierarchy: a 4-wide BVH (BVH4) built top-down with binned SAH
// splits (each node repeatedly splits its largest child until it has four), traversed with
// SSE2 slab tests of the four children at once in near-to-far order, with leaves of at most
// kBvhMaxLeafPrims primitives whose vertices are stored contiguously in structure-of-arrays
// form so that four Moller-Trumbore tests run in one SIMD pass.
#include "candela/accel/accel.h"

#include <cstdint>
#include <vector>

namespace candela {

/// Leaves hold at most this many primitives: one SSE register of triangles.
constexpr int kBvhMaxLeafPrims = 4;

/// An inner node of the 4-wide BVH, one 128-byte pair of cache lines. bounds[a][0][k] and
/// bounds[a][1][k] are the low and high bound of child k along axis a (structure of arrays, so
/// one SSE load fetches a plane of all four children). child[k] is either the index of an inner
/// node, or kBvhLeafBit | (first primitive << 3) | (count - 1) for a leaf. Unused slots have
/// an empty box (lo = +inf, hi = -inf) that no ray enters.
struct alignas(64) Bvh4Node {
    float bounds[3][2][4];
    std::uint32_t child[4];
    std::uint32_t pad[4];
};
static_assert(sizeof(Bvh4Node) == 128, "BVH4 nodes are meant to be 128 bytes");

/// Marks a leaf in Bvh4Node::child.
constexpr std::uint32_t kBvhLeafBit = 0x80000000u;

class BvhAccel final : public Accel {
  public:
    /// Builds over `scene` (which must outlive the accelerator) with `build_threads` TBB
    /// threads (0 = all available, 1 = serial). The tree does not depend on the thread count.
    BvhAccel(const Scene& scene, TriangleTest test, int build_threads);
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3 bounds() const override;
    const char* name() const override { return "builtin"; }
    /// Nodes + leaf primitive data + the reference-decoding table, in bytes.
    std::size_t memory_bytes() const override;

    std::size_t node_count() const { return nodes_.size(); } ///< inner nodes
    std::size_t leaf_count() const { return leaf_count_; }
    int depth() const { return depth_; } ///< levels of inner nodes plus the leaf level
    double build_seconds() const { return build_seconds_; }

  private:
    template <TriangleTest kTest, bool kSpheres, bool kAnyHit>
    bool trace(const Ray& ray, Hit& hit) const;
    Hit decode(std::uint32_t ref, float t, float u, float v) const;

    const Scene& scene_;
    TriangleTest test_;
    std::vector<Bvh4Node> nodes_;
    /// Leaf data: the leaf with c primitives starting at primitive index i occupies the 10 c
    /// floats at 10 i: p0.x[c] p0.y[c] p0.z[c] p1.x[c] ... p2.z[c] ref[c] (refs stored as
    /// uint32 bits). Spheres store the centre in p0 and the radius in p1.x. Four spare floats
    /// at the end let SIMD loads read past the last leaf.
    std::vector<float> leaf_data_;
    /// mesh_first_ref_[g] = ref of mesh g's first triangle; the last entry is the first sphere.
    std::vector<std::uint32_t> mesh_first_ref_;
    std::uint32_t sphere_first_ref_ = 0;
    std::uint32_t root_ = 0; ///< node index, or a leaf reference when the scene is tiny
    std::uint32_t prim_count_ = 0;
    Bounds3 bounds_;
    std::size_t leaf_count_ = 0;
    int depth_ = 0;
    double build_seconds_ = 0.0;
};

} // namespace candela
