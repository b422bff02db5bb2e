#pragma once
// candela's own bounding volume hierarchy: an 8-wide BVH (BVH8) built top-down with binned SAH
// splits (each node splits its children, small ones first, then the largest, until it has
// eight), laid out depth first, and traversed with slab tests of all eight children at once:
// one AVX2 pass on CPUs that have it (selected at run time), two SSE passes otherwise.
// Closest-hit queries visit children near to far; occlusion queries visit them far to near
// and stop at the first hit. Leaves hold at most kBvhMaxLeafPrims primitives stored
// contiguously in structure-of-arrays form, so four Moller-Trumbore tests run in one SSE pass.
#include "candela/accel/accel.h"
#include "candela/accel/bvh_allocator.h"

#include <cstdint>
#include <vector>

namespace candela {

struct Sphere;

/// Leaves hold at most this many primitives: one SSE register of triangles.
constexpr int kBvhMaxLeafPrims = 4;
/// Children per inner node.
constexpr int kBvhWidth = 8;

/// An inner node of the 8-wide BVH: four 64-byte cache lines. bounds[a][0][k] and
/// bounds[a][1][k] are the low and high bound of child k along axis a (structure of arrays, so
/// one AVX load fetches a plane of all eight children). child[k] is either the index of an
/// inner node, or kBvhLeafBit | (first primitive << 3) | (count - 1) for a leaf. Unused slots
/// have an empty box (lo = +inf, hi = -inf) that no ray enters.
struct alignas(64) Bvh8Node {
    float bounds[3][2][kBvhWidth];
    std::uint32_t child[kBvhWidth];
    std::uint32_t pad[kBvhWidth];
};
static_assert(sizeof(Bvh8Node) == 256, "BVH8 nodes are meant to be four cache lines");

/// Marks a leaf in Bvh8Node::child.
constexpr std::uint32_t kBvhLeafBit = 0x80000000u;

/// Instruction set of the traversal: Auto picks AVX2 when the CPU supports it, else SSE2.
enum class BvhIsa { Auto, Sse2, Avx2 };

/// True when this CPU (and OS) can run the AVX2 traversal.
bool bvh_cpu_has_avx2();

class BvhAccel final : public Accel {
  public:
    /// Builds over `scene` (which must outlive the accelerator) with `build_threads` TBB
    /// threads (0 = all available, 1 = serial). The tree does not depend on the thread count.
    /// `isa` forces a traversal instruction set; Avx2 on a CPU without it throws Error.
    BvhAccel(const Scene& scene, TriangleTest test, int build_threads, BvhIsa isa = BvhIsa::Auto);
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override;
    /// The batch interface: one traversal kernel call per ray, no virtual call between them.
    void intersect_batch(BatchRayHit* rays, std::size_t n, BatchCoherence coherence) const override;
    void occluded_batch(BatchRay* rays, std::size_t n) const override;
    Bounds3 bounds() const override;
    const char* name() const override { return "builtin"; }
    /// Nodes + leaf primitive data + the reference-decoding table, in bytes.
    std::size_t memory_bytes() const override;

    std::size_t node_count() const { return nodes_.size(); } ///< inner nodes
    std::size_t leaf_count() const { return leaf_count_; }
    int depth() const { return depth_; } ///< levels of inner nodes plus the leaf level
    double build_seconds() const { return build_seconds_; }
    BvhIsa isa() const { return isa_; } ///< the traversal in use: Sse2 or Avx2
    const BvhVector<Bvh8Node>& nodes() const { return nodes_; }
    std::uint32_t root() const { return root_; } ///< node index, or a leaf reference
    /// Scene-wide reference (triangles of mesh 0, mesh 1, ..., then spheres) of primitive k of
    /// the leaf with child reference `leaf`; k < (leaf & 7) + 1.
    std::uint32_t leaf_prim_ref(std::uint32_t leaf, std::uint32_t k) const;

    /// Closest-hit result of a traversal kernel: t, barycentrics and the scene-wide primitive
    /// reference (triangles of mesh 0, mesh 1, ..., then spheres).
    struct TraceHit {
        float t, u, v;
        std::uint32_t ref;
    };
    /// What a traversal kernel reads.
    struct TraceData {
        const Bvh8Node* nodes;
        const float* leaves;
        std::uint32_t root;
        std::uint32_t sphere_first_ref;
        const Sphere* spheres; ///< the scene's spheres (ellipsoid tests read their maps)
    };
    /// A traversal kernel: true when a hit with t in (ray.tmin, ray.tmax] exists; the closest
    /// one is written to the TraceHit unless the kernel is an any-hit kernel.
    using TraceFn = bool (*)(const TraceData&, const Ray&, TraceHit&);

  private:
    /// Sets isa_, closest_ and any_: the kernels of `isa` (Auto: the best this CPU runs) for
    /// test_ and the kinds of sphere the scene has (bvh_query.cpp). Throws Error (Usage) for
    /// Avx2 on a CPU without it.
    void select_kernels(BvhIsa isa);
    Hit decode(const TraceHit& h) const;

    const Scene& scene_;
    TriangleTest test_;
    BvhIsa isa_ = BvhIsa::Sse2;
    TraceFn closest_ = nullptr;
    TraceFn any_ = nullptr;
    BvhVector<Bvh8Node> nodes_;
    /// Leaf data: the leaf with c primitives starting at primitive index i occupies the 10 c
    /// floats at 10 i, nine coordinate rows of c floats then the c refs (uint32 bits). With
    /// Moller-Trumbore the rows are p0, e1 = p1 - p0, e2 = p2 - p0 (the same float subtractions
    /// the scalar test does, precomputed); with the watertight test p0, p1, p2. Spheres store
    /// the centre in the first row and the radius in the fourth (an ellipsoid's map is read
    /// from its Sphere record by the kernels that test ellipsoids). Four spare floats at the end
    /// let SIMD loads read past the last leaf.
    BvhVector<float> leaf_data_;
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
