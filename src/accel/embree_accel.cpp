// The Embree 3 backend: its device, the scene of triangle meshes and user-geometry spheres,
// traversal.
#include "embree_accel.h"

#include "candela/accel/sphere.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>

namespace candela {

// Spheres are Embree *user geometry*, not RTC_GEOMETRY_TYPE_SPHERE_POINT: the user callback
// runs candela's own robust intersect_sphere(), the very code the builtin and brute backends
// use, so sphere hits agree bit for bit across backends and keep the spec's semantics (nearest
// root in range, hits from inside report the far side). Embree's native sphere points are
// double-sided ray-disc-like approximations tuned for hair and particles and would create
// backend disagreements for no gain: CS184 scenes have at most a handful of spheres. Ellipsoids
// (spheres under a non-similarity transform) are the same user geometry: the callbacks run
// intersect_sphere_prim(), which carries the ray into the ellipsoid's object space.

namespace {

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* scene = static_cast<const Scene*>(args->geometryUserPtr);
    // Same padding rationale as the builtin BVH: the float root may land a few ulps outside.
    constexpr float kPad = 8.f * std::numeric_limits<float>::epsilon();
    const Bounds3 box = padded_sphere_box(scene->spheres[args->primID], kPad);
    RTCBounds* b = args->bounds_o;
    b->lower_x = box.lo.x;
    b->lower_y = box.lo.y;
    b->lower_z = box.lo.z;
    b->upper_x = box.hi.x;
    b->upper_y = box.hi.y;
    b->upper_z = box.hi.z;
}

/// Unnormalised outward normal of sphere record s at the world point q (Embree's Ng; candela's
/// shading recomputes it in make_interaction).
Vec3 sphere_normal(const Sphere& s, const Vec3& q) {
    if (s.is_ellipsoid()) return s.to_object.transpose_mul(s.to_object * (q - s.center));
    return q - s.center;
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* scene = static_cast<const Scene*>(args->geometryUserPtr);
    const Sphere& s = scene->spheres[args->primID];
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const Vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                     RTCRayN_org_z(ray, args->N, i));
        const Vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                     RTCRayN_dir_z(ray, args->N, i));
        float t;
        if (!intersect_sphere_prim(s, o, d, RTCRayN_tnear(ray, args->N, i),
                                   RTCRayN_tfar(ray, args->N, i), t))
            continue;
        const Vec3 n = sphere_normal(s, o + d * t);
        RTCRayN_tfar(ray, args->N, i) = t;
        RTCHitN_Ng_x(hit, args->N, i) = n.x;
        RTCHitN_Ng_y(hit, args->N, i) = n.y;
        RTCHitN_Ng_z(hit, args->N, i) = n.z;
        RTCHitN_u(hit, args->N, i) = 0.f;
        RTCHitN_v(hit, args->N, i) = 0.f;
        RTCHitN_primID(hit, args->N, i) = args->primID;
        RTCHitN_geomID(hit, args->N, i) = args->geomID;
        RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* scene = static_cast<const Scene*>(args->geometryUserPtr);
    const Sphere& s = scene->spheres[args->primID];
    RTCRayN* ray = args->ray;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const Vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                     RTCRayN_org_z(ray, args->N, i));
        const Vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                     RTCRayN_dir_z(ray, args->N, i));
        float t;
        if (intersect_sphere_prim(s, o, d, RTCRayN_tnear(ray, args->N, i),
                                  RTCRayN_tfar(ray, args->N, i), t))
            RTCRayN_tfar(ray, args->N, i) = -std::numeric_limits<float>::infinity();
    }
}

const char* rtc_error_name(RTCError code) {
    switch (code) {
    case RTC_ERROR_NONE:
        return "none";
    case RTC_ERROR_UNKNOWN:
        return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT:
        return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
        return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
        return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
        return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
        return "cancelled";
    }
    return "error";
}

// Embree's memory monitor is per device; the accelerator owns its device, so a per-device
// counter measures exactly this structure.
bool memory_monitor(void* user, ssize_t bytes, bool /*post*/) {
    static_cast<std::atomic<long long>*>(user)->fetch_add(bytes, std::memory_order_relaxed);
    return true;
}

} // namespace

std::string embree_default_isa() {
#if defined(__x86_64__) || defined(__i386__)
    return __builtin_cpu_supports("avx2") ? "avx2" : "";
#else
    return "";
#endif
}

EmbreeDevice::EmbreeDevice(const std::string& isa, int threads) {
    if (!isa.empty()) config_ = "isa=" + isa;
    if (threads > 0)
        config_ += (config_.empty() ? "" : ",") + std::string("threads=") + std::to_string(threads);
    // Incoherent rays fetch BVH nodes at random, so large scenes benefit from huge pages (as the
    // builtin BVH's arrays do); Embree falls back to normal pages where none are available.
    config_ += std::string(config_.empty() ? "" : ",") + "hugepages=1";
    device_ = rtcNewDevice(config_.c_str());
    if (!device_)
        throw Error(ErrorKind::Internal,
                    std::string("embree: rtcNewDevice(\"") + config_ +
                        "\") failed: " + rtc_error_name(rtcGetDeviceError(nullptr)));
    rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, this);
}

EmbreeDevice::~EmbreeDevice() {
    if (device_) rtcReleaseDevice(device_);
}

void EmbreeDevice::on_error(void* user, RTCError code, const char* str) {
    auto* self = static_cast<EmbreeDevice*>(user);
    std::lock_guard<std::mutex> lock(self->mutex_);
    if (self->error_.empty())
        self->error_ = std::string(rtc_error_name(code)) + (str ? std::string(": ") + str : "");
}

void EmbreeDevice::check(const char* what) {
    std::string msg;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        msg.swap(error_);
    }
    if (!msg.empty()) throw Error(ErrorKind::Internal, std::string("embree: ") + what + ": " + msg);
}

RTCBuildQuality embree_build_quality(AccelOptions::Quality q) {
    switch (q) {
    case AccelOptions::Quality::Low:
        return RTC_BUILD_QUALITY_LOW;
    case AccelOptions::Quality::Medium:
        return RTC_BUILD_QUALITY_MEDIUM;
    case AccelOptions::Quality::High:
        return RTC_BUILD_QUALITY_HIGH;
    }
    return RTC_BUILD_QUALITY_MEDIUM;
}

void attach_embree_geometry(RTCDevice device, RTCScene rtc, const Scene& scene,
                            RTCBuildQuality quality) {
    for (std::size_t g = 0; g < scene.meshes.size(); ++g) {
        const Mesh& m = scene.meshes[g];
        if (m.triangle_count() == 0 || m.positions.empty()) continue; // id stays unused
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Zero-copy: Embree reads the scene's arrays. Its 16-byte loads at the last vertex are
        // covered by the spare Vec3 that PaddedPositions keeps after the vertices.
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                   m.positions.data(), 0, sizeof(Vec3), m.positions.size());
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                   m.indices.data(), 0, 3 * sizeof(std::uint32_t),
                                   m.triangle_count());
        rtcSetGeometryBuildQuality(geom, quality);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(rtc, geom, static_cast<unsigned>(g));
        rtcReleaseGeometry(geom);
    }
    if (!scene.spheres.empty()) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(scene.spheres.size()));
        rtcSetGeometryUserData(geom, const_cast<Scene*>(&scene));
        rtcSetGeometryBoundsFunction(geom, &sphere_bounds, nullptr);
        rtcSetGeometryIntersectFunction(geom, &sphere_intersect);
        rtcSetGeometryOccludedFunction(geom, &sphere_occluded);
        rtcSetGeometryBuildQuality(geom, quality);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(rtc, geom, scene.sphere_geom_id());
        rtcReleaseGeometry(geom);
    }
}

EmbreeAccel::EmbreeAccel(const Scene& scene, const AccelOptions& opt, const std::string& isa)
    : scene_(scene), device_(isa, opt.build_threads) {
    const Stopwatch timer;
    std::atomic<long long> allocated{0};
    rtcSetDeviceMemoryMonitorFunction(device_.get(), &memory_monitor, &allocated);
    scene_rtc_ = rtcNewScene(device_.get());
    device_.check("rtcNewScene");
    rtcSetSceneFlags(scene_rtc_, opt.embree_robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene_rtc_, embree_build_quality(opt.quality));
    try {
        attach_embree_geometry(device_.get(), scene_rtc_, scene, embree_build_quality(opt.quality));
        device_.check("creating geometry");
        rtcCommitScene(scene_rtc_);
        device_.check("rtcCommitScene");
    } catch (...) {
        rtcSetDeviceMemoryMonitorFunction(device_.get(), nullptr, nullptr);
        rtcReleaseScene(scene_rtc_);
        throw;
    }
    rtcSetDeviceMemoryMonitorFunction(device_.get(), nullptr, nullptr);
    const long long bytes = allocated.load();
    memory_bytes_ = bytes > 0 ? static_cast<std::size_t>(bytes) : 0;
    build_seconds_ = timer.seconds();
}

EmbreeAccel::~EmbreeAccel() {
    if (scene_rtc_) rtcReleaseScene(scene_rtc_);
}

std::optional<Hit> EmbreeAccel::intersect(const Ray& ray) const {
    if (!is_valid_ray(ray)) return std::nullopt;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = to_embree_rayhit(ray);
    rtcIntersect1(scene_rtc_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    return Hit{rh.ray.tfar, rh.hit.u, rh.hit.v, rh.hit.geomID, rh.hit.primID};
}

bool EmbreeAccel::occluded(const Ray& ray) const {
    // A tfar of -inf is Embree's "occluded" answer, so an interval ending at -inf (which holds
    // no hit anyway) must not reach it.
    if (!is_valid_ray(ray) || ray.tmax == -std::numeric_limits<float>::infinity()) return false;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r = to_embree_rayhit(ray).ray;
    rtcOccluded1(scene_rtc_, &ctx, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
}

// The batch records are Embree's own structures under candela's names.
static_assert(sizeof(BatchRay) == sizeof(RTCRay) && alignof(BatchRay) == alignof(RTCRay));
static_assert(offsetof(BatchRay, tnear) == offsetof(RTCRay, tnear) &&
              offsetof(BatchRay, dir_x) == offsetof(RTCRay, dir_x) &&
              offsetof(BatchRay, tfar) == offsetof(RTCRay, tfar) &&
              offsetof(BatchRay, flags) == offsetof(RTCRay, flags));
static_assert(sizeof(BatchRayHit) == sizeof(RTCRayHit));
static_assert(offsetof(BatchRayHit, hit) == offsetof(RTCRayHit, hit) &&
              offsetof(BatchHit, u) == offsetof(RTCHit, u) &&
              offsetof(BatchHit, prim_id) == offsetof(RTCHit, primID) &&
              offsetof(BatchHit, geom_id) == offsetof(RTCHit, geomID) &&
              offsetof(BatchHit, inst_id) == offsetof(RTCHit, instID));
static_assert(kNoHit == RTC_INVALID_GEOMETRY_ID);

void EmbreeAccel::intersect_batch(BatchRayHit* rays, std::size_t n,
                                  BatchCoherence coherence) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherence == BatchCoherence::Coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT
                                                      : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    // M is an unsigned int: very large batches go in slices.
    constexpr std::size_t kMaxSlice = std::size_t(1) << 30;
    for (std::size_t first = 0; first < n; first += kMaxSlice)
        rtcIntersect1M(scene_rtc_, &ctx, reinterpret_cast<RTCRayHit*>(rays + first),
                       static_cast<unsigned>(std::min(kMaxSlice, n - first)), sizeof(BatchRayHit));
}

void EmbreeAccel::occluded_batch(BatchRay* rays, std::size_t n) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    constexpr std::size_t kMaxSlice = std::size_t(1) << 30;
    for (std::size_t first = 0; first < n; first += kMaxSlice)
        rtcOccluded1M(scene_rtc_, &ctx, reinterpret_cast<RTCRay*>(rays + first),
                      static_cast<unsigned>(std::min(kMaxSlice, n - first)), sizeof(BatchRay));
}

Bounds3 EmbreeAccel::bounds() const {
    RTCBounds b;
    rtcGetSceneBounds(scene_rtc_, &b);
    Bounds3 out;
    if (b.lower_x <= b.upper_x) {
        out.lo = Vec3(b.lower_x, b.lower_y, b.lower_z);
        out.hi = Vec3(b.upper_x, b.upper_y, b.upper_z);
    }
    return out;
}

} // namespace candela
