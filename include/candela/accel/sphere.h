#pragma once
// Robust ray-sphere intersection.
#include "candela/math/bbox.h"
#include "candela/math/mat3.h"
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

/// Nearest root t in (tmin, tmax] of the ray o + t d against the ellipsoid {p : |inv (p - c)| =
/// 1}, with the same conventions as intersect_sphere. The ray is carried into the object space of
/// the unit sphere (origin inv (o - c), direction inv d, not normalised) and intersected there by
/// intersect_sphere: a linear map keeps the ray parameter, so t needs no conversion back.
template <typename T>
inline bool intersect_ellipsoid(const Vec3T<T>& o, const Vec3T<T>& d, const Vec3T<T>& c,
                                const Mat3T<T>& inv, T tmin, T tmax, T& t_out) {
    const Vec3T<T> oo = inv * (o - c);
    const Vec3T<T> dd = inv * d;
    return intersect_sphere(oo, dd, Vec3T<T>(T(0)), T(1), tmin, tmax, t_out);
}

/// The float test of one scene sphere record S (candela::Sphere, scene/scene.h): the ellipsoid
/// test when it is an ellipsoid, else intersect_sphere. Every float backend calls this, so they
/// agree bit for bit.
template <class S>
inline bool intersect_sphere_prim(const S& s, const Vec3& o, const Vec3& d, float tmin, float tmax,
                                  float& t_out) {
    if (s.is_ellipsoid())
        return intersect_ellipsoid(o, d, s.center, s.to_object, tmin, tmax, t_out);
    return intersect_sphere(o, d, s.center, s.radius, tmin, tmax, t_out);
}

/// The same test in double on the float record (the double-precision reference).
template <class S>
inline bool intersect_sphere_prim_double(const S& s, const Vec3d& o, const Vec3d& d, double tmin,
                                         double tmax, double& t_out) {
    if (s.is_ellipsoid())
        return intersect_ellipsoid(o, d, Vec3d(s.center), Mat3d(s.to_object), tmin, tmax, t_out);
    return intersect_sphere(o, d, Vec3d(s.center), double(s.radius), tmin, tmax, t_out);
}

/// Box of a scene sphere record for an accelerator: its exact bounds grown by rel_pad times
/// (|centre| + largest half extent) times the record's map_error. The float root finder may
/// place a grazing hit a few ulps outside the exact surface, and for an ellipsoid those ulps
/// are amplified by the maps into and out of object space (map_error, 1 for spheres, so that
/// their boxes are exactly the padded centre +- radius).
template <class S> inline Bounds3 padded_sphere_box(const S& s, float rel_pad) {
    const Bounds3 b = s.bounds();
    const float half = s.is_ellipsoid() ? max_component(b.hi - b.lo) * 0.5f : s.radius;
    const Vec3 pad((max_component(vabs(s.center)) + half) * rel_pad * s.map_error);
    return Bounds3{b.lo - pad, b.hi + pad};
}

} // namespace candela
