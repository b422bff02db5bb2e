// The queries of the builtin BVH: BvhAccel's closest-hit and occlusion entry points, one ray
// or a batch at a time, each a call of the traversal kernel chosen at build time, and the
// decoding of its result into a Hit.
#include "bvh_kernels.h"
#include "bvh_layout.h"

#include "candela/accel/bvh.h"
#include "candela/accel/sphere.h"
#include "candela/scene/scene.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace candela {

using bvh_detail::kLeafFloats;

void BvhAccel::select_kernels(BvhIsa isa) {
    if (isa == BvhIsa::Avx2 && !bvh_cpu_has_avx2())
        throw Error(ErrorKind::Usage,
                    "builtin BVH: AVX2 traversal requested on a CPU without AVX2");
    isa_ = isa == BvhIsa::Auto ? (bvh_cpu_has_avx2() ? BvhIsa::Avx2 : BvhIsa::Sse2) : isa;
    const bvh_detail::KernelSet ks =
        isa_ == BvhIsa::Avx2 ? bvh_detail::avx2_kernels() : bvh_detail::sse2_kernels();
    const int wt = test_ == TriangleTest::Watertight ? 1 : 0;
    // Kernels without sphere code for triangle-only scenes, and without ellipsoid code
    // unless some sphere is an ellipsoid: a scene pays only for the primitives it has.
    int sp = scene_.spheres.empty() ? 0 : 1;
    for (const Sphere& s : scene_.spheres)
        if (s.is_ellipsoid()) sp = 2;
    closest_ = ks.fn[wt][sp][0];
    any_ = ks.fn[wt][sp][1];
}

bool bvh_cpu_has_avx2() {
    return __builtin_cpu_supports("avx2");
}

Hit BvhAccel::decode(const TraceHit& h) const {
    if (h.ref >= sphere_first_ref_)
        return Hit{h.t, 0.f, 0.f, scene_.sphere_geom_id(), h.ref - sphere_first_ref_};
    const std::size_t g = std::upper_bound(mesh_first_ref_.begin(), mesh_first_ref_.end(), h.ref) -
                          mesh_first_ref_.begin() - 1;
    return Hit{h.t, h.u, h.v, static_cast<std::uint32_t>(g), h.ref - mesh_first_ref_[g]};
}

std::optional<Hit> BvhAccel::intersect(const Ray& ray) const {
    if (prim_count_ == 0 || !is_valid_ray(ray)) return std::nullopt;
    const TraceData data{nodes_.data(), leaf_data_.data(), root_, sphere_first_ref_,
                         scene_.spheres.data()};
    TraceHit h;
    if (!closest_(data, ray, h)) return std::nullopt;
    return decode(h);
}

bool BvhAccel::occluded(const Ray& ray) const {
    if (prim_count_ == 0 || !is_valid_ray(ray)) return false;
    const TraceData data{nodes_.data(), leaf_data_.data(), root_, sphere_first_ref_,
                         scene_.spheres.data()};
    TraceHit h;
    return any_(data, ray, h);
}

void BvhAccel::intersect_batch(BatchRayHit* rays, std::size_t n, BatchCoherence) const {
    if (prim_count_ == 0) return;
    const TraceData data{nodes_.data(), leaf_data_.data(), root_, sphere_first_ref_,
                         scene_.spheres.data()};
    for (std::size_t i = 0; i < n; ++i) {
        BatchRayHit& r = rays[i];
        if (!(r.ray.tnear <= r.ray.tfar)) continue; // an invalid ray (set_batch_ray)
        TraceHit h;
        if (!closest_(data, batch_ray(r.ray), h)) continue;
        const Hit hit = decode(h);
        r.ray.tfar = hit.t;
        r.hit.u = hit.u;
        r.hit.v = hit.v;
        r.hit.geom_id = hit.geom_id;
        r.hit.prim_id = hit.prim_id;
    }
}

void BvhAccel::occluded_batch(BatchRay* rays, std::size_t n) const {
    if (prim_count_ == 0) return;
    const TraceData data{nodes_.data(), leaf_data_.data(), root_, sphere_first_ref_,
                         scene_.spheres.data()};
    for (std::size_t i = 0; i < n; ++i) {
        BatchRay& r = rays[i];
        if (!(r.tnear <= r.tfar)) continue;
        TraceHit h;
        if (any_(data, batch_ray(r), h)) r.tfar = -std::numeric_limits<float>::infinity();
    }
}

std::uint32_t BvhAccel::leaf_prim_ref(std::uint32_t leaf, std::uint32_t k) const {
    const std::uint32_t c = (leaf & 7u) + 1;
    const std::size_t first = (leaf & ~kBvhLeafBit) >> 3;
    CANDELA_CHECK((leaf & kBvhLeafBit) && k < c && first + c <= prim_count_,
                  "BvhAccel::leaf_prim_ref: not a primitive of a leaf");
    std::uint32_t ref;
    std::memcpy(&ref, leaf_data_.data() + kLeafFloats * first + 9 * c + k, sizeof ref);
    return ref;
}

Bounds3 BvhAccel::bounds() const {
    return bounds_;
}

std::size_t BvhAccel::memory_bytes() const {
    return nodes_.capacity() * sizeof(Bvh8Node) + leaf_data_.capacity() * sizeof(float) +
           mesh_first_ref_.capacity() * sizeof(std::uint32_t);
}

} // namespace candela
