#pragma once
// The double-precision oracle of the numerics suite and of the tests that classify a float
// backend's answer as right or wrong. Not part of the renderer.
#include "candela/accel/accel.h"

#include <cstdint>
#include <optional>

namespace candela {

class Scene;

/// A closest hit computed in double precision: the exact float inputs (ray and vertices) are
/// converted to double and intersected there, so t, u and v carry relative errors of ~1e-16
/// instead of ~1e-7. Same conventions as Hit.
struct HitD {
    double t = 0.0;
    double u = 0.0, v = 0.0;
    std::uint32_t geom_id = 0;
    std::uint32_t prim_id = 0;
};

/// The ground truth of the numerics tests: a linear scan in double precision (Moller-Trumbore
/// for triangles, the closest-approach sphere test for spheres), same interval convention
/// tmin < t <= tmax. Answers what the float ray as given really hits, up to double rounding,
/// so a float backend's miss or t can be classified as right or wrong. Slow; tests only.
class DoubleBruteAccel final : public Accel {
  public:
    /// `scene` must outlive the accelerator.
    explicit DoubleBruteAccel(const Scene& scene) : scene_(scene) {}
    /// Closest hit in double, t in (ray.tmin, ray.tmax] (in units of |ray.d|), or nullopt.
    /// Invalid rays return nullopt.
    std::optional<HitD> intersect_double(const Ray& ray) const;
    /// intersect_double() rounded to float (t rounded to nearest).
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override { return intersect_double(ray).has_value(); }
    Bounds3 bounds() const override;
    const char* name() const override { return "brute-double"; }
    std::size_t memory_bytes() const override { return 0; }

  private:
    const Scene& scene_;
};

} // namespace candela
