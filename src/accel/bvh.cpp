#include "candela/accel/bvh.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>

namespace candela {

namespace {

// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007):
// 16 centroid bins per axis. Wald reports 16-32 bins within a few percent of the full sweep
// SAH; 16 keeps the per-node bin arrays in L1 and the build memory-bound rather than
// compute-bound.
constexpr int kBins = 16;
/// SAH costs of one node visit and one primitive test, in the same unit. Equal costs (rather
/// than pbrt's 1/8 traversal) favour fuller leaves, which keeps the node count (memory) down;
/// a ray-box test and a Moller-Trumbore test cost about the same here.
constexpr float kTraversalCost = 4.f;
constexpr float kIntersectCost = 1.f;
/// Past this depth the build switches to object-median splits, which halve the range, so the
/// total depth stays below kSahMaxDepth + 32 < kStackSize for any primitive count < 2^32.
constexpr int kSahMaxDepth = 64;
constexpr int kStackSize = 128;
/// Ranges smaller than this are built serially (a TBB task costs about as much as binning a
/// few thousand primitives).
constexpr std::uint32_t kParallelMinPrims = 4096;
/// pbrt-v4's conservative slab test: scaling the far distance by 1 + 2 gamma(3) covers the
/// rounding of (bound - o) * inv_d, so no box is missed by a ray that hits its content.
constexpr float kSlabFarScale = 1.f + 2.f * float_gamma(3);
/// Sphere boxes are padded by this relative amount of |c| + r: the float root-finder may place
/// a grazing hit a few ulps outside the exact box.
constexpr float kSphereBoxPad = float_gamma(8);

/// Build-time record of one primitive. The build partitions an array of these in place, so
/// every pass reads memory sequentially.
struct BuildPrim {
    Bounds3 b;
    Vec3 c;
    std::uint32_t ref = 0;
};

struct Builder {
    std::vector<BuildPrim>& prims;
    std::vector<BvhNode>& nodes;
    bool parallel;
    std::atomic<std::uint32_t> next_node{1};
    std::atomic<std::size_t> leaves{0};
    std::atomic<int> max_depth{0};

    void make_leaf(BvhNode& node, std::uint32_t begin, std::uint32_t n) {
        node.offset = begin;
        node.count = static_cast<std::uint16_t>(n);
        leaves.fetch_add(1, std::memory_order_relaxed);
    }

    void build(std::uint32_t node_index, std::uint32_t begin, std::uint32_t end, int depth) {
        int seen = max_depth.load(std::memory_order_relaxed);
        while (depth > seen && !max_depth.compare_exchange_weak(seen, depth)) {
        }
        Bounds3 b, cb;
        for (std::uint32_t i = begin; i < end; ++i) {
            const BuildPrim& p = prims[i];
            b.grow(p.b);
            cb.grow(p.c);
        }
        BvhNode& node = nodes[node_index];
        for (int a = 0; a < 3; ++a) {
            node.box[a] = b.lo[a];
            node.box[3 + a] = b.hi[a];
        }
        const std::uint32_t n = end - begin;
        if (n == 1) return make_leaf(node, begin, n);

        int axis = -1;
        std::uint32_t mid = begin;
        const Vec3 ext = cb.extent();
        if (depth < kSahMaxDepth) {
            int best_axis = -1, best_split = -1;
            float best_cost = std::numeric_limits<float>::infinity();
            // One pass bins the centroids along all three axes.
            Bounds3 bins_b[3][kBins];
            std::uint32_t bins_n[3][kBins] = {};
            float scale[3];
            for (int a = 0; a < 3; ++a)
                scale[a] = ext[a] > 0.f ? kBins / ext[a] : 0.f;
            for (std::uint32_t i = begin; i < end; ++i) {
                const BuildPrim& p = prims[i];
                const float c[3] = {p.c.x - cb.lo.x, p.c.y - cb.lo.y, p.c.z - cb.lo.z};
                for (int a = 0; a < 3; ++a) {
                    const int k = std::min(kBins - 1, static_cast<int>(c[a] * scale[a]));
                    ++bins_n[a][k];
                    bins_b[a][k].grow(p.b);
                }
            }
            for (int a = 0; a < 3; ++a) {
                if (!(ext[a] > 0.f)) continue;
                const Bounds3* bin_b = bins_b[a];
                const std::uint32_t* bin_n = bins_n[a];
                // Sweep from the right to get the right-side areas, then from the left.
                float right_area[kBins];
                std::uint32_t right_n[kBins];
                Bounds3 acc;
                std::uint32_t acc_n = 0;
                for (int k = kBins - 1; k > 0; --k) {
                    acc.grow(bin_b[k]);
                    acc_n += bin_n[k];
                    right_area[k] = acc.surface_area();
                    right_n[k] = acc_n;
                }
                acc = Bounds3{};
                acc_n = 0;
                for (int k = 0; k < kBins - 1; ++k) {
                    acc.grow(bin_b[k]);
                    acc_n += bin_n[k];
                    if (acc_n == 0 || right_n[k + 1] == 0) continue;
                    const float cost = acc.surface_area() * static_cast<float>(acc_n) +
                                       right_area[k + 1] * static_cast<float>(right_n[k + 1]);
                    if (cost < best_cost) {
                        best_cost = cost;
                        best_axis = a;
                        best_split = k;
                    }
                }
            }
            const float area = b.surface_area();
            const float leaf_cost = kIntersectCost * static_cast<float>(n);
            const float split_cost =
                area > 0.f ? kTraversalCost + kIntersectCost * best_cost / area : leaf_cost;
            if (n <= static_cast<std::uint32_t>(kBvhMaxLeafPrims) &&
                (best_axis < 0 || leaf_cost <= split_cost))
                return make_leaf(node, begin, n);
            if (best_axis >= 0) {
                const float sc = scale[best_axis];
                const float lo = cb.lo[best_axis];
                const int ax = best_axis;
                auto it = std::partition(
                    prims.begin() + begin, prims.begin() + end, [&](const BuildPrim& p) {
                        const float c = ax == 0 ? p.c.x : ax == 1 ? p.c.y : p.c.z;
                        return std::min(kBins - 1, static_cast<int>((c - lo) * sc)) <= best_split;
                    });
                mid = static_cast<std::uint32_t>(it - prims.begin());
                if (mid > begin && mid < end) axis = best_axis;
            }
        }
        if (axis < 0) {
            // No usable SAH split (coincident centroids, or too deep): object median.
            if (n <= static_cast<std::uint32_t>(kBvhMaxLeafPrims)) return make_leaf(node, begin, n);
            axis = max_dimension(ext);
            mid = begin + n / 2;
            std::nth_element(
                prims.begin() + begin, prims.begin() + mid, prims.begin() + end,
                [&](const BuildPrim& x, const BuildPrim& y) { return x.c[axis] < y.c[axis]; });
        }
        const std::uint32_t child = next_node.fetch_add(2, std::memory_order_relaxed);
        node.offset = child;
        node.count = 0;
        node.axis = static_cast<std::uint8_t>(axis);
        if (parallel && n >= kParallelMinPrims) {
            tbb::parallel_invoke([&] { build(child, begin, mid, depth + 1); },
                                 [&] { build(child + 1, mid, end, depth + 1); });
        } else {
            build(child, begin, mid, depth + 1);
            build(child + 1, mid, end, depth + 1);
        }
    }
};

/// Per-ray constants of the slab test: the inverse direction and, per axis, the offset (0 or 3)
/// of the near and far plane in a node's {lo, hi} floats, chosen by the direction's sign.
struct SlabRay {
    Vec3 o, inv_d;
    int near[3], far[3];
};

/// Conservative ray-box slab test. NaN products (0 * inf, from axis-parallel rays with an
/// origin on a slab) are ignored by the comparison order, as in pbrt-v4.
/// On a hit, t_enter receives the entry distance (at least tmin).
inline bool hit_box(const BvhNode& n, const SlabRay& r, float tmin, float tmax, float& t_enter) {
    const float* b = n.box;
    const float tx0 = (b[r.near[0]] - r.o.x) * r.inv_d.x;
    const float tx1 = (b[r.far[0]] - r.o.x) * r.inv_d.x * kSlabFarScale;
    const float ty0 = (b[r.near[1]] - r.o.y) * r.inv_d.y;
    const float ty1 = (b[r.far[1]] - r.o.y) * r.inv_d.y * kSlabFarScale;
    const float tz0 = (b[r.near[2]] - r.o.z) * r.inv_d.z;
    const float tz1 = (b[r.far[2]] - r.o.z) * r.inv_d.z * kSlabFarScale;
    tmin = tx0 > tmin ? tx0 : tmin;
    tmin = ty0 > tmin ? ty0 : tmin;
    tmin = tz0 > tmin ? tz0 : tmin;
    tmax = tx1 < tmax ? tx1 : tmax;
    tmax = ty1 < tmax ? ty1 : tmax;
    tmax = tz1 < tmax ? tz1 : tmax;
    t_enter = tmin;
    return tmin <= tmax;
}

} // namespace

BvhAccel::BvhAccel(const Scene& scene, TriangleTest test, int build_threads)
    : scene_(scene), test_(test) {
    const auto start = std::chrono::steady_clock::now();
    // Scene-wide primitive numbering: triangles of mesh 0, mesh 1, ..., then spheres.
    mesh_first_ref_.resize(scene.meshes.size() + 1);
    std::uint64_t total = 0;
    for (std::size_t g = 0; g < scene.meshes.size(); ++g) {
        mesh_first_ref_[g] = static_cast<std::uint32_t>(total);
        total += scene.meshes[g].triangle_count();
    }
    mesh_first_ref_.back() = static_cast<std::uint32_t>(total);
    sphere_first_ref_ = static_cast<std::uint32_t>(total);
    total += scene.spheres.size();
    if (total >= std::numeric_limits<std::uint32_t>::max() / 2)
        throw Error(ErrorKind::Scene,
                    "builtin BVH: too many primitives (" + std::to_string(total) + ")");
    const auto n = static_cast<std::uint32_t>(total);

    std::vector<BuildPrim> info(n);
    auto fill = [&](std::uint32_t lo, std::uint32_t hi) {
        for (std::uint32_t r = lo; r < hi; ++r) {
            BuildPrim& bp = info[r];
            bp.ref = r;
            bp.b = Bounds3{};
            if (r >= sphere_first_ref_) {
                const Sphere& s = scene.spheres[r - sphere_first_ref_];
                const Vec3 pad((max_component(vabs(s.center)) + s.radius) * kSphereBoxPad);
                bp.b.grow(s.center - Vec3(s.radius) - pad);
                bp.b.grow(s.center + Vec3(s.radius) + pad);
            } else {
                const std::size_t g =
                    std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), r) -
                    mesh_first_ref_.begin() - 1;
                const Mesh& m = scene.meshes[g];
                const std::uint32_t j = r - mesh_first_ref_[g];
                for (int k = 0; k < 3; ++k)
                    bp.b.grow(m.positions[m.indices[3 * j + k]]);
            }
            bp.c = bp.b.center();
        }
    };
    nodes_.resize(n == 0 ? 1 : 2 * static_cast<std::size_t>(n) - 1);
    const bool parallel = build_threads != 1;
    Builder builder{info, nodes_, parallel};
    auto run = [&] {
        if (parallel)
            tbb::parallel_for(
                tbb::blocked_range<std::uint32_t>(0, n, 1024),
                [&](const tbb::blocked_range<std::uint32_t>& r) { fill(r.begin(), r.end()); });
        else
            fill(0, n);
        if (n > 0) builder.build(0, 0, n, 1);
    };
    if (parallel) {
        tbb::task_arena arena(build_threads > 0 ? build_threads : tbb::task_arena::automatic);
        arena.execute(run);
    } else {
        run();
    }
    if (n == 0) {
        nodes_.resize(1); // never traversed: trace() returns before reading it
    } else {
        nodes_.resize(builder.next_node.load());
        relinearize();
    }
    nodes_.shrink_to_fit();
    leaf_count_ = builder.leaves.load();
    depth_ = builder.max_depth.load();

    prims_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t r = info[i].ref;
        BvhPrim& p = prims_[i];
        p.ref = r;
        if (r >= sphere_first_ref_) {
            const Sphere& s = scene.spheres[r - sphere_first_ref_];
            p.p0 = s.center;
            p.p1 = Vec3(s.radius, 0.f, 0.f);
        } else {
            const std::size_t g =
                std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), r) -
                mesh_first_ref_.begin() - 1;
            const Mesh& m = scene.meshes[g];
            const std::uint32_t j = r - mesh_first_ref_[g];
            p.p0 = m.positions[m.indices[3 * j]];
            p.p1 = m.positions[m.indices[3 * j + 1]];
            p.p2 = m.positions[m.indices[3 * j + 2]];
        }
    }
    build_seconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void BvhAccel::relinearize() {
    // A parallel build interleaves the node pairs of concurrently built subtrees; rewrite the
    // array in depth-first order (each sibling pair adjacent, the left child's subtree right
    // after the pair) so that a descent touches nearby memory. Serial builds are already in
    // this order, so the layout does not depend on the thread count.
    std::vector<BvhNode> out;
    out.reserve(nodes_.size());
    out.push_back(nodes_[0]);
    // (index in nodes_, index in out) of inner nodes whose children are still to be copied.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo;
    auto expand = [&](std::uint32_t src, std::uint32_t dst) {
        const std::uint32_t c = nodes_[src].offset;
        const auto first = static_cast<std::uint32_t>(out.size());
        out[dst].offset = first;
        out.push_back(nodes_[c]);
        out.push_back(nodes_[c + 1]);
        // Right child pushed first so that the left subtree is laid out first.
        if (nodes_[c + 1].count == 0) todo.emplace_back(c + 1, first + 1);
        if (nodes_[c].count == 0) todo.emplace_back(c, first);
    };
    if (nodes_[0].count == 0) todo.emplace_back(0, 0);
    while (!todo.empty()) {
        const auto [src, dst] = todo.back();
        todo.pop_back();
        expand(src, dst);
    }
    nodes_.swap(out);
}

Hit BvhAccel::decode(std::uint32_t ref, float t, float u, float v) const {
    if (ref >= sphere_first_ref_)
        return Hit{t, 0.f, 0.f, scene_.sphere_geom_id(), ref - sphere_first_ref_};
    const std::size_t g = std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), ref) -
                          mesh_first_ref_.begin() - 1;
    return Hit{t, u, v, static_cast<std::uint32_t>(g), ref - mesh_first_ref_[g]};
}

template <TriangleTest kTest, bool kSpheres, bool kAnyHit>
bool BvhAccel::trace(const Ray& ray, Hit& hit) const {
    SlabRay sr;
    sr.o = ray.o;
    sr.inv_d = Vec3(1.f / ray.d.x, 1.f / ray.d.y, 1.f / ray.d.z);
    int neg[3];
    for (int a = 0; a < 3; ++a) {
        neg[a] = sr.inv_d[a] < 0.f;
        sr.near[a] = neg[a] ? 3 + a : a;
        sr.far[a] = neg[a] ? a : 3 + a;
    }
    WatertightRay wr;
    if (kTest == TriangleTest::Watertight) wr = make_watertight_ray(ray.d);
    if (prims_.empty()) return false;
    float tmax = ray.tmax;
    std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
    float best_u = 0.f, best_v = 0.f;
    // The stack holds nodes whose box the ray enters, with the entry distance, so that nodes
    // lying beyond a hit found meanwhile are dropped when popped.
    std::uint32_t stack[kStackSize];
    float stack_t[kStackSize];
    int sp = 0;
    float t_enter;
    if (!hit_box(nodes_[0], sr, ray.tmin, tmax, t_enter)) return false;
    std::uint32_t idx = 0;
    for (;;) {
        const BvhNode& node = nodes_[idx];
        if (node.count == 0) {
            // Near child first: the low side of the split axis when the ray travels toward
            // +axis. Children whose boxes the ray misses are never pushed.
            const std::uint32_t near = node.offset + static_cast<std::uint32_t>(neg[node.axis]);
            const std::uint32_t far = node.offset + 1 - static_cast<std::uint32_t>(neg[node.axis]);
            float t_near, t_far;
            const bool hit_near = hit_box(nodes_[near], sr, ray.tmin, tmax, t_near);
            const bool hit_far = hit_box(nodes_[far], sr, ray.tmin, tmax, t_far);
            if (hit_near) {
                if (hit_far) {
                    stack[sp] = far;
                    stack_t[sp++] = t_far;
                }
                idx = near;
                continue;
            }
            if (hit_far) {
                idx = far;
                continue;
            }
        } else {
            const std::uint32_t end = node.offset + node.count;
            for (std::uint32_t i = node.offset; i < end; ++i) {
                const BvhPrim& p = prims_[i];
                if (kSpheres && p.ref >= sphere_first_ref_) {
                    float t;
                    if (!intersect_sphere(ray.o, ray.d, p.p0, p.p1.x, ray.tmin, tmax, t)) continue;
                    if (kAnyHit) return true;
                    tmax = t;
                    best = i;
                    best_u = best_v = 0.f;
                } else {
                    TriangleHit th;
                    const bool h = kTest == TriangleTest::Watertight
                                       ? intersect_triangle_watertight(ray.o, wr, p.p0, p.p1, p.p2,
                                                                       ray.tmin, tmax, th)
                                       : intersect_triangle_mt(ray.o, ray.d, p.p0, p.p1, p.p2,
                                                               ray.tmin, tmax, th);
                    if (!h) continue;
                    if (kAnyHit) return true;
                    tmax = th.t;
                    best = i;
                    best_u = th.u;
                    best_v = th.v;
                }
            }
        }
        // Pop the next node that still begins before the closest hit so far.
        while (sp > 0 && stack_t[sp - 1] > tmax)
            --sp;
        if (sp == 0) break;
        idx = stack[--sp];
    }
    if (best == std::numeric_limits<std::uint32_t>::max()) return false;
    hit = decode(prims_[best].ref, tmax, best_u, best_v);
    return true;
}

std::optional<Hit> BvhAccel::intersect(const Ray& ray) const {
    if (!is_valid_ray(ray)) return std::nullopt;
    Hit hit;
    const bool spheres = !scene_.spheres.empty();
    bool found;
    if (test_ == TriangleTest::Watertight)
        found = spheres ? trace<TriangleTest::Watertight, true, false>(ray, hit)
                        : trace<TriangleTest::Watertight, false, false>(ray, hit);
    else
        found = spheres ? trace<TriangleTest::MollerTrumbore, true, false>(ray, hit)
                        : trace<TriangleTest::MollerTrumbore, false, false>(ray, hit);
    if (!found) return std::nullopt;
    return hit;
}

bool BvhAccel::occluded(const Ray& ray) const {
    if (!is_valid_ray(ray)) return false;
    Hit hit;
    const bool spheres = !scene_.spheres.empty();
    if (test_ == TriangleTest::Watertight)
        return spheres ? trace<TriangleTest::Watertight, true, true>(ray, hit)
                       : trace<TriangleTest::Watertight, false, true>(ray, hit);
    return spheres ? trace<TriangleTest::MollerTrumbore, true, true>(ray, hit)
                   : trace<TriangleTest::MollerTrumbore, false, true>(ray, hit);
}

Bounds3 BvhAccel::bounds() const {
    if (prims_.empty()) return Bounds3{};
    const float* b = nodes_[0].box;
    return Bounds3{Vec3(b[0], b[1], b[2]), Vec3(b[3], b[4], b[5])};
}

std::size_t BvhAccel::memory_bytes() const {
    return nodes_.capacity() * sizeof(BvhNode) + prims_.capacity() * sizeof(BvhPrim) +
           mesh_first_ref_.capacity() * sizeof(std::uint32_t);
}

} // namespace candela
