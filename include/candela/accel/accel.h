#pragma once
// The accelerator interface: one virtual call per ray, nothing finer. Backends: embree (Embree 3),
// builtin (candela's SAH BVH), brute (linear scan, the test oracle).
#include "candela/accel/hit.h"
#include "candela/math/bbox.h"
#include "candela/math/ray.h"

#include <memory>
#include <optional>
#include <string>

namespace candela {

class Scene;

enum class AccelKind { Embree, Builtin, Brute };
enum class TriangleTest { MollerTrumbore, Watertight };

struct AccelOptions {
    AccelKind kind = AccelKind::Embree;
    TriangleTest triangle = TriangleTest::MollerTrumbore; ///< builtin and brute only
    bool embree_robust = false;                           ///< RTC_SCENE_FLAG_ROBUST
    enum class Quality { Low, Medium, High } quality = Quality::Medium; ///< Embree build quality
    int build_threads = 0; ///< 0 = all available
};

class Accel {
public:
    virtual ~Accel() = default;
    /// Closest hit with t in [ray.tmin, ray.tmax], or nullopt. Invalid rays (is_valid_ray()
    /// false) return nullopt without traversal.
    virtual std::optional<Hit> intersect(const Ray& ray) const = 0;
    /// True when any hit exists with t in [ray.tmin, ray.tmax]. Equals intersect(ray).has_value().
    virtual bool occluded(const Ray& ray) const = 0;
    virtual Bounds3 bounds() const = 0;
    virtual const char* name() const = 0;
    /// Bytes used by the acceleration structure itself, beyond the scene's own arrays.
    virtual std::size_t memory_bytes() const = 0;
};

/// Builds the accelerator `opt.kind` over `scene`, which must outlive it.
std::unique_ptr<Accel> make_accel(const Scene& scene, const AccelOptions& opt);

AccelKind parse_accel_kind(const std::string& s); ///< "embree" | "builtin" | "brute"; throws Usage
const char* accel_kind_name(AccelKind k);

} // namespace candela
