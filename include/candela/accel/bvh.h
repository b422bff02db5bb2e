#pragma once
// candela's own bounding volume hierarchy: binned SAH build, flattened 32-byte nodes with
// adjacent children, leaves of at most kBvhMaxLeafPrims primitives, iterative ordered traversal.
#include "candela/accel/accel.h"

#include <cstdint>
#include <vector>

namespace candela {

/// Leaves hold at most this many primitives (a leaf's SAH cost grows linearly with its size,
/// and four triangles fit in a few cache lines of the prepared array).
constexpr int kBvhMaxLeafPrims = 4;

/// A flattened node. Inner nodes (count == 0) have their two children at `offset` and
/// `offset + 1`; `axis` is the split axis used to visit the nearer child first. Leaves have
/// `count` primitives at prims[offset .. offset + count).
struct BvhNode {
    float box[6] = {0.f, 0.f, 0.f, 0.f, 0.f, 0.f}; ///< lo.x lo.y lo.z hi.x hi.y hi.z
    std::uint32_t offset = 0;
    std::uint16_t count = 0;
    std::uint8_t axis = 0;
    std::uint8_t pad = 0;
};
static_assert(sizeof(BvhNode) == 32, "BVH nodes are meant to be 32 bytes");

/// A primitive prepared for traversal, in leaf order. Triangles keep their three vertices
/// exactly as the mesh stores them (so hits are bit-identical to the brute-force oracle);
/// spheres store the centre in p0 and the radius in p1.x. `ref` packs (geom, prim) as an index
/// into the scene-wide primitive numbering: all mesh triangles in mesh order, then spheres.
struct BvhPrim {
    Vec3 p0, p1, p2;
    std::uint32_t ref = 0;
};
static_assert(sizeof(BvhPrim) == 40, "prepared primitives are meant to be 40 bytes");

class BvhAccel final : public Accel {
  public:
    /// Builds over `scene` (which must outlive the accelerator) with `build_threads` TBB
    /// threads (0 = all available, 1 = serial).
    BvhAccel(const Scene& scene, TriangleTest test, int build_threads);
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3 bounds() const override;
    const char* name() const override { return "builtin"; }
    /// Nodes + prepared primitives + the reference-decoding table, in bytes.
    std::size_t memory_bytes() const override;

    std::size_t node_count() const { return nodes_.size(); }
    std::size_t leaf_count() const { return leaf_count_; }
    int depth() const { return depth_; }
    double build_seconds() const { return build_seconds_; }

  private:
    template <TriangleTest kTest, bool kSpheres, bool kAnyHit>
    bool trace(const Ray& ray, Hit& hit) const;
    Hit decode(std::uint32_t ref, float t, float u, float v) const;
    void relinearize();

    const Scene& scene_;
    TriangleTest test_;
    std::vector<BvhNode> nodes_;
    std::vector<BvhPrim> prims_;
    /// mesh_first_ref_[g] = ref of mesh g's first triangle; the last entry is the first sphere.
    std::vector<std::uint32_t> mesh_first_ref_;
    std::uint32_t sphere_first_ref_ = 0;
    std::size_t leaf_count_ = 0;
    int depth_ = 0;
    double build_seconds_ = 0.0;
};

} // namespace candela
