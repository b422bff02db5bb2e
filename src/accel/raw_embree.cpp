// Embree called directly (raw_embree.h): the raw loops of `candela bench`.
#include "candela/accel/raw_embree.h"

#include "embree_accel.h"

#include "candela/scene/scene.h"

#include <limits>

namespace candela {

struct RawEmbree::Impl {
    EmbreeDevice device;
    RTCScene scene = nullptr;
    Impl(const std::string& isa) : device(isa, 0) {}
    ~Impl() {
        if (scene) rtcReleaseScene(scene);
    }
};

RawEmbree::RawEmbree(const Scene& s, const std::string& isa, bool robust,
                     AccelOptions::Quality quality)
    : impl_(std::make_unique<Impl>(isa.empty() ? embree_default_isa() : isa)) {
    EmbreeDevice& device = impl_->device;
    RTCScene& scene = impl_->scene;
    scene = rtcNewScene(device.get());
    device.check("rtcNewScene");
    rtcSetSceneFlags(scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene, embree_build_quality(quality));
    attach_embree_geometry(device.get(), scene, s, embree_build_quality(quality));
    rtcCommitScene(scene);
    device.check("rtcCommitScene");
}

RawEmbree::~RawEmbree() = default;

const std::string& RawEmbree::config() const {
    return impl_->device.config();
}

std::uint64_t RawEmbree::count_hits(const Ray* rays, std::size_t n) const {
    const RTCScene scene = impl_->scene;
    std::uint64_t hits = 0;
    for (std::size_t i = 0; i < n; ++i) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh = to_embree_rayhit(rays[i]);
        rtcIntersect1(scene, &ctx, &rh);
        hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
    }
    return hits;
}

std::uint64_t RawEmbree::count_occluded(const Ray* rays, std::size_t n) const {
    const RTCScene scene = impl_->scene;
    std::uint64_t occluded = 0;
    for (std::size_t i = 0; i < n; ++i) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh = to_embree_rayhit(rays[i]);
        rtcOccluded1(scene, &ctx, &rh.ray);
        occluded += rh.ray.tfar == -std::numeric_limits<float>::infinity() ? 1 : 0;
    }
    return occluded;
}

} // namespace candela
