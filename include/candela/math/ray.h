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
inline bool is_valid_ray(const Ray& r) {
    return is_finite(r.o) && is_finite(r.d) && length_squared(r.d) > 0.f && !std::isnan(r.tmin) &&
           !std::isnan(r.tmax) && r.tmin <= r.tmax;
}

} // namespace candela
