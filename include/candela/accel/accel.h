#pragma once
// The accelerator interface: one virtual call per ray or per batch of rays, nothing finer.
// Backends: embree (Embree 3), builtin (candela's SAH BVH), brute (linear scan, the test oracle).
#include "candela/math/bbox.h"
#include "candela/math/float_bits.h"
#include "candela/math/ray.h"
#include "candela/scene/hit.h"
#include "candela/util/enum_table.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

namespace candela {

class Scene;

enum class AccelKind { Embree, Builtin, Brute };
/// --accel (util/enum_table.h).
inline constexpr EnumTable<AccelKind, 3> kAccelKinds = {{
    {AccelKind::Embree, "embree", ""},
    {AccelKind::Builtin, "builtin", ""},
    {AccelKind::Brute, "brute", ""},
}};

enum class TriangleTest { MollerTrumbore, Watertight };
/// --triangle.
inline constexpr EnumTable<TriangleTest, 2> kTriangleTests = {{
    {TriangleTest::MollerTrumbore, "mt", "Moller-Trumbore"},
    {TriangleTest::Watertight, "watertight", ""},
}};

struct AccelOptions {
    AccelKind kind = AccelKind::Embree;
    TriangleTest triangle = TriangleTest::MollerTrumbore;               ///< builtin and brute only
    bool embree_robust = false;                                         ///< RTC_SCENE_FLAG_ROBUST
    enum class Quality { Low, Medium, High } quality = Quality::Medium; ///< Embree build quality
    int build_threads = 0;                                              ///< 0 = all available
    /// Embree instruction set: "" for embree_default_isa(), else an Embree isa name ("avx2").
    std::string embree_isa;
};
/// --embree-quality.
inline constexpr EnumTable<AccelOptions::Quality, 3> kEmbreeQualities = {{
    {AccelOptions::Quality::Low, "low", ""},
    {AccelOptions::Quality::Medium, "medium", ""},
    {AccelOptions::Quality::High, "high", ""},
}};

/// One ray of a batch query, in the memory layout of Embree's RTCRay (the Embree backend hands
/// whole batches to its stream API without a copy; accel/embree_accel.cpp checks the layout).
/// The interval is closed, [tnear, tfar]: set_batch_ray() stores a candela ray's open near end
/// tmin as the next float above it. After an occlusion query tfar is -infinity when the ray is
/// occluded.
struct alignas(16) BatchRay {
    float org_x, org_y, org_z, tnear;
    float dir_x, dir_y, dir_z, time;
    float tfar;
    std::uint32_t mask, id, flags;
};

/// The hit part of a closest-hit batch record (Embree's RTCHit layout). geom_id is
/// kNoHit when the ray hit nothing; otherwise the ray's tfar holds the hit distance.
struct alignas(16) BatchHit {
    float ng_x, ng_y, ng_z;
    float u, v;
    std::uint32_t prim_id, geom_id, inst_id;
};

struct BatchRayHit {
    BatchRay ray;
    BatchHit hit;
};

/// BatchHit::geom_id of a ray that hit nothing.
constexpr std::uint32_t kNoHit = 0xffffffffu;

/// Whether the rays of a batch start near one point and point alike (camera rays of a tile),
/// which packet traversal exploits, or not (bounce and shadow rays).
enum class BatchCoherence { Coherent, Incoherent };

/// Embree accepts hits with tnear <= t (its robust kernels do return t == tnear for a ray that
/// starts exactly on a surface), while candela's contract is tmin < t. tnear is therefore the
/// next float above tmin, but never below the smallest normal float: a subnormal tnear (the
/// float after 0) puts subnormals into Embree's traversal arithmetic, which measured 1.4x
/// slower for shadow rays. Hits at 0 < t < 1.2e-38 are thus not reported by Embree; no real
/// hit is that close, since spawned rays are offset by far more (scene/interaction.h).
inline float open_tnear(float tmin) {
    if (tmin >= 0.f && tmin < std::numeric_limits<float>::min())
        return std::numeric_limits<float>::min();
    return next_float_up(tmin);
}

/// The closed interval [tnear, tfar] of a batch record for `ray`, given tnear_open =
/// open_tnear(ray.tmin) (a caller whose rays share one tmin computes it once). A ray that
/// is_valid_ray() rejects gets an empty interval, so that every backend skips it (no hit, not
/// occluded). Without branches, so that a loop over many rays vectorises.
struct BatchInterval {
    float tnear, tfar;
};
inline BatchInterval batch_interval(const Ray& ray, float tnear_open) {
    // A tmax of -infinity is the "occluded" answer, so an interval ending there is emptied too.
    const bool valid = is_valid_ray(ray) && ray.tmax != -std::numeric_limits<float>::infinity();
    // tnear > tfar: every backend skips the ray.
    return {valid ? tnear_open : 0.f, valid ? ray.tmax : -1.f};
}

/// Writes a ray with origin o, direction d and the interval batch_interval() gave it into a
/// batch record.
inline void write_batch_ray(BatchRay& out, const Vec3& o, const Vec3& d, BatchInterval t) {
    out.org_x = o.x;
    out.org_y = o.y;
    out.org_z = o.z;
    out.dir_x = d.x;
    out.dir_y = d.y;
    out.dir_z = d.z;
    out.time = 0.f;
    out.mask = 0xffffffffu;
    out.id = 0;
    out.flags = 0;
    out.tnear = t.tnear;
    out.tfar = t.tfar;
}

/// Writes `ray` into a batch record with an empty hit (batch_interval: an invalid ray gets an
/// empty interval).
inline void set_batch_ray(BatchRay& out, const Ray& ray) {
    write_batch_ray(out, ray.o, ray.d, batch_interval(ray, open_tnear(ray.tmin)));
}
/// Empties the hit of a batch record before it is traced.
inline void clear_batch_hit(BatchHit& hit) {
    hit.geom_id = kNoHit;
    hit.prim_id = kNoHit;
    hit.inst_id = kNoHit;
}
inline void set_batch_ray(BatchRayHit& out, const Ray& ray) {
    set_batch_ray(out.ray, ray);
    clear_batch_hit(out.hit);
}
/// The candela ray of a batch record (the inverse of set_batch_ray() for valid rays).
Ray batch_ray(const BatchRay& r);
/// The Hit of a batch record whose hit.geom_id is not kNoHit.
inline Hit batch_hit(const BatchRayHit& r) {
    return Hit{r.ray.tfar, r.hit.u, r.hit.v, r.hit.geom_id, r.hit.prim_id};
}
inline bool batch_occluded(const BatchRay& r) {
    return r.tfar == -std::numeric_limits<float>::infinity();
}

class Accel {
  public:
    virtual ~Accel() = default;
    /// Closest hit with t in (ray.tmin, ray.tmax], or nullopt. Invalid rays (is_valid_ray()
    /// false) return nullopt without traversal.
    virtual std::optional<Hit> intersect(const Ray& ray) const = 0;
    /// True when any hit exists with t in (ray.tmin, ray.tmax]. Equals intersect(ray).has_value().
    virtual bool occluded(const Ray& ray) const = 0;
    /// Closest hits of n rays: each record's hit (and its ray's tfar) as intersect() would
    /// find it. One virtual call per batch; the default asks intersect() ray by ray.
    virtual void intersect_batch(BatchRayHit* rays, std::size_t n, BatchCoherence coherence) const;
    /// Occlusion of n rays: tfar becomes -infinity for each occluded ray. The default asks
    /// occluded() ray by ray.
    virtual void occluded_batch(BatchRay* rays, std::size_t n) const;
    virtual Bounds3 bounds() const = 0;
    virtual const char* name() const = 0;
    /// Bytes used by the acceleration structure itself, beyond the scene's own arrays.
    virtual std::size_t memory_bytes() const = 0;
};

/// Builds the accelerator `opt.kind` over `scene`, which must outlive it.
std::unique_ptr<Accel> make_accel(const Scene& scene, const AccelOptions& opt);

/// The instruction set candela asks Embree for by default: "avx2" when the CPU has it (Embree's
/// AVX2 kernels measured as fast or faster than its AVX-512 ones on the target machines), else
/// "" (Embree's own choice). Reading it creates no Embree device.
std::string embree_default_isa();

/// True when every one of kEnclosureRays rays from `p`, spread evenly over the sphere of
/// directions, hits a surface: `p` is inside a closed room (or a closed object).
bool enclosed_point(const Accel& accel, const Vec3& p);

/// A name of kAccelKinds; throws Error(Usage) naming --accel, the choices and the nearest one.
AccelKind parse_accel_kind(const std::string& s);
constexpr const char* accel_kind_name(AccelKind k) {
    return enum_name(kAccelKinds, k);
}

} // namespace candela
