#pragma once
#include "candela/math/vec.h"
#include <limits>

namespace candela {

/// A ray o + t d. Every query accepts hits with t in (tmin, tmax]: the near end is open, so a
/// ray leaving a surface at t = tmin never reports that surface. Renderer rays have unit d, so t
/// is a distance.
struct Ray {
    Vec3 o;
    Vec3 d;
    float tmin = 0.f;
    float tmax = std::numeric_limits<float>::infinity();
};

/// A ray is traceable when its origin and direction are finite, its direction is non-zero and
/// its interval is not empty. Every accelerator rejects other rays before traversal.
/// Every ray a renderer traces passes this test, so it is written without branches: x * 0 is 0
/// for finite x and NaN for an infinite or NaN one, so the sum below is 0 exactly when all six
/// components are finite; a comparison with a NaN is false, so tmin <= tmax also rejects a NaN end.
inline bool is_valid_ray(const Ray& r) {
    const float finite_test =
        (r.o.x * 0.f + r.o.y * 0.f) + (r.o.z * 0.f + r.d.x * 0.f) + (r.d.y * 0.f + r.d.z * 0.f);
    return (finite_test == 0.f) & (length_squared(r.d) > 0.f) & (r.tmin <= r.tmax);
}

} // namespace candela
