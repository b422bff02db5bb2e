#pragma once
// Robust ray-sphere intersection.
#include "candela/math/vec.h"

#include <cmath>
#include <utility>

namespace candela {

/// Nearest root t in (tmin, tmax] (open near end, as for triangles) of |o + t d - c|^2 = r^2 (d
/// need not be unit), written to `t_out`; false when neither root is in range. The discriminant is
/// computed from the distance between c and the ray's point of closest approach (Haines et al.,
/// "Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7; pbrt-v4
/// section 6.8.4), which avoids the catastrophic cancellation of b^2 - 4ac when the sphere is small
/// relative to its distance, and the roots use the cancellation-free form q = -(b' + sign(b')
/// sqrt(disc)). The smaller root is taken when in range, else the larger (hits from inside report
/// the far side), matching spec section 4. T is float for the renderer, double for the
/// double-precision ground truth (accel/brute.h).
template <typename T>
inline bool intersect_sphere(const Vec3T<T>& o, const Vec3T<T>& d, const Vec3T<T>& c, T r, T tmin,
                             T tmax, T& t_out) {
    const Vec3T<T> f = o - c;
    const T a = dot(d, d);
    const T b_half = dot(f, d); // the quadratic is a t^2 + 2 b' t + c0
    const T c0 = dot(f, f) - r * r;
    // |f - (b'/a) d| is the distance from the centre to the closest-approach point.
    const Vec3T<T> l = f - d * (b_half / a);
    const T disc = a * (r * r - dot(l, l)); // = b'^2 - a c0 without cancellation
    if (!(disc >= T(0))) return false;
    const T root = std::sqrt(disc);
    const T q = -(b_half + std::copysign(root, b_half));
    T t0, t1;
    if (q == T(0)) {
        t0 = t1 = T(0); // b' = 0 and disc = 0: the origin is the tangent point
    } else {
        t0 = c0 / q;
        t1 = q / a;
        if (t0 > t1) std::swap(t0, t1);
    }
    if (t0 > tmin && t0 <= tmax) {
        t_out = t0;
        return true;
    }
    if (t1 > tmin && t1 <= tmax) {
        t_out = t1;
        return true;
    }
    return false;
}

} // namespace candela
