#pragma once
// The Embree 3 backend: zero-copy triangle meshes, spheres as user geometry, errors reported
// through candela::Error.
#include "candela/accel/accel.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>

namespace candela {

/// The Embree ray (with an empty hit) for candela ray `ray`: tnear from open_tnear(ray.tmin),
/// all mask bits set. Used by EmbreeAccel and by the raw-Embree ceiling of `candela bench`, so
/// both trace exactly the same rays.
inline RTCRayHit to_embree_rayhit(const Ray& ray) {
    RTCRayHit rh;
    rh.ray.org_x = ray.o.x;
    rh.ray.org_y = ray.o.y;
    rh.ray.org_z = ray.o.z;
    rh.ray.dir_x = ray.d.x;
    rh.ray.dir_y = ray.d.y;
    rh.ray.dir_z = ray.d.z;
    rh.ray.tnear = open_tnear(ray.tmin);
    rh.ray.tfar = ray.tmax;
    rh.ray.time = 0.f;
    rh.ray.mask = std::numeric_limits<unsigned>::max();
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

/// An Embree device whose error callback records the first error; check() turns a recorded
/// error into a candela::Error, so no Embree failure is printed and then ignored.
class EmbreeDevice {
  public:
    /// `isa` is "" (Embree's own choice) or an Embree isa name such as "avx2"; `threads` 0 means
    /// all available. Throws Error(Internal) when the device cannot be created.
    EmbreeDevice(const std::string& isa, int threads);
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDevice get() const { return device_; }
    /// Throws Error(Internal) "embree: <what>: <message>" if an error was recorded since the
    /// last check (the recorded error is cleared).
    void check(const char* what);
    /// The config string passed to rtcNewDevice.
    const std::string& config() const { return config_; }

    /// The ISA candela asks for by default (embree_default_isa()).
    static std::string default_isa() { return embree_default_isa(); }

  private:
    static void on_error(void* user, RTCError code, const char* str);
    RTCDevice device_ = nullptr;
    std::mutex mutex_;
    std::string error_;
    std::string config_;
};

/// Embree build quality of AccelOptions::Quality.
RTCBuildQuality embree_build_quality(AccelOptions::Quality q);

class EmbreeAccel final : public Accel {
  public:
    /// Builds over `scene` (which must outlive the accelerator). `isa` as in EmbreeDevice;
    /// opt.embree_robust sets RTC_SCENE_FLAG_ROBUST, opt.quality the build quality.
    EmbreeAccel(const Scene& scene, const AccelOptions& opt,
                const std::string& isa = EmbreeDevice::default_isa());
    ~EmbreeAccel() override;
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override;
    /// rtcIntersect1M over the records in place (coherent batches with Embree's coherent
    /// context flag, so that it traces them in packets).
    void intersect_batch(BatchRayHit* rays, std::size_t n, BatchCoherence coherence) const override;
    /// rtcOccluded1M over the records in place.
    void occluded_batch(BatchRay* rays, std::size_t n) const override;
    Bounds3 bounds() const override;
    const char* name() const override { return "embree"; }
    /// Bytes Embree allocated while building (from its memory monitor callback).
    std::size_t memory_bytes() const override { return memory_bytes_; }
    double build_seconds() const { return build_seconds_; }

  private:
    const Scene& scene_;
    EmbreeDevice device_;
    RTCScene scene_rtc_ = nullptr;
    std::size_t memory_bytes_ = 0;
    double build_seconds_ = 0.0;
};

/// Attaches the scene's meshes (shared buffers, geometry id = mesh index) and spheres (user
/// geometry, id Scene::sphere_geom_id()) to `rtc`; used by EmbreeAccel and the raw benchmark.
void attach_embree_geometry(RTCDevice device, RTCScene rtc, const Scene& scene,
                            RTCBuildQuality quality);

} // namespace candela
