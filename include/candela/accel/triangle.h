#pragma once
// Ray-triangle tests. All of them are double-sided (no culling) and report barycentrics in
// Embree's convention: the hit point is (1-u-v) p0 + u p1 + v p2. Every test treats a NaN
// anywhere in its arithmetic as a miss (comparisons are written so that NaN fails them).
// Accepted hits have tmin < t <= tmax: the near end is open, as in Embree's kernels, so that a
// ray starting exactly on a surface (t computed as +0 or -0) does not report that surface.
#include "candela/math/float_error.h"
#include "candela/math/vec.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace candela {

/// Parametric distance and barycentrics of a ray-triangle hit.
struct TriangleHit {
    float t = 0.f;
    float u = 0.f, v = 0.f;
};

/// Moller-Trumbore (JGT 1997), double-sided. Returns true and fills `out` when the ray
/// o + t d hits triangle (p0, p1, p2) with t in (tmin, tmax]. A zero determinant (ray parallel
/// to the plane, or a degenerate triangle) is a miss; no epsilon is involved.
inline bool intersect_triangle_mt(const Vec3& o, const Vec3& d, const Vec3& p0, const Vec3& p1,
                                  const Vec3& p2, float tmin, float tmax, TriangleHit& out) {
    const Vec3 e1 = p1 - p0;
    const Vec3 e2 = p2 - p0;
    const Vec3 pvec = cross(d, e2);
    const float det = dot(e1, pvec);
    if (det == 0.f) return false;
    const float inv_det = 1.f / det;
    const Vec3 tvec = o - p0;
    const float u = dot(tvec, pvec) * inv_det;
    if (!(u >= 0.f && u <= 1.f)) return false;
    const Vec3 qvec = cross(tvec, e1);
    const float v = dot(d, qvec) * inv_det;
    if (!(v >= 0.f && u + v <= 1.f)) return false;
    const float t = dot(e2, qvec) * inv_det;
    if (!(t > tmin && t <= tmax)) return false;
    out.t = t;
    out.u = u;
    out.v = v;
    return true;
}

/// Double-precision Moller-Trumbore, the ground truth for tests (same conventions).
struct TriangleHitD {
    double t = 0.0;
    double u = 0.0, v = 0.0;
};
inline bool intersect_triangle_mt_double(const Vec3d& o, const Vec3d& d, const Vec3d& p0,
                                         const Vec3d& p1, const Vec3d& p2, double tmin, double tmax,
                                         TriangleHitD& out) {
    const Vec3d e1 = p1 - p0;
    const Vec3d e2 = p2 - p0;
    const Vec3d pvec = cross(d, e2);
    const double det = dot(e1, pvec);
    if (det == 0.0) return false;
    const double inv_det = 1.0 / det;
    const Vec3d tvec = o - p0;
    const double u = dot(tvec, pvec) * inv_det;
    if (!(u >= 0.0 && u <= 1.0)) return false;
    const Vec3d qvec = cross(tvec, e1);
    const double v = dot(d, qvec) * inv_det;
    if (!(v >= 0.0 && u + v <= 1.0)) return false;
    const double t = dot(e2, qvec) * inv_det;
    if (!(t > tmin && t <= tmax)) return false;
    out.t = t;
    out.u = u;
    out.v = v;
    return true;
}

/// Per-ray constants of the watertight test: the axis permutation that makes the dominant
/// direction component z, and the shear that maps the direction to +z.
struct WatertightRay {
    int kx = 0, ky = 1, kz = 2;
    float sx = 0.f, sy = 0.f, sz = 1.f;
};

/// Precomputes the shear of direction d (non-zero, finite).
inline WatertightRay make_watertight_ray(const Vec3& d) {
    WatertightRay w;
    w.kz = max_dimension(vabs(d));
    w.kx = w.kz == 2 ? 0 : w.kz + 1;
    w.ky = w.kx == 2 ? 0 : w.kx + 1;
    // Swap to preserve the winding of the triangle when the dominant component is negative.
    if (d[w.kz] < 0.f) std::swap(w.kx, w.ky);
    w.sx = d[w.kx] / d[w.kz];
    w.sy = d[w.ky] / d[w.kz];
    w.sz = 1.f / d[w.kz];
    return w;
}

/// Sheared triangle coordinates of the watertight test, relative to the ray origin.
template <class T> struct ShearedTriangle { T ax, ay, az, bx, by, bz, cx, cy, cz; };

/// pbrt-v4's bound on the rounding error of the watertight test's t (section 6.8.7), from the
/// sheared coordinates, the edge functions U, V, W and 1/det. `gz` and `gxy` bound the relative
/// error of the sheared z and of x, y (they depend on how many roundings made them); ge and gt
/// are the factors of the edge functions' and of t's own arithmetic.
template <class T>
T watertight_t_error(const ShearedTriangle<T>& s, T U, T V, T W, T inv_det, T gz, T gxy, T ge,
                     T gt) {
    const T max_zt = std::max(std::abs(s.az), std::max(std::abs(s.bz), std::abs(s.cz)));
    const T max_xt = std::max(std::abs(s.ax), std::max(std::abs(s.bx), std::abs(s.cx)));
    const T max_yt = std::max(std::abs(s.ay), std::max(std::abs(s.by), std::abs(s.cy)));
    const T delta_z = gz * max_zt;
    const T delta_x = gxy * (max_xt + max_zt);
    const T delta_y = gxy * (max_yt + max_zt);
    const T delta_e = T(2) * (ge * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    const T max_e = std::max(std::abs(U), std::max(std::abs(V), std::abs(W)));
    return T(3) * (gt * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * std::abs(inv_det);
}

/// The decision step of the watertight test, in double: sheared coordinates, edge functions, t
/// and its error bound recomputed from the float inputs (the differences p - o are exact in
/// double). Returns the hit when t is certainly positive in double and lies in (tmin, tmax].
/// Called only for float hits too close to 0 to be certified in float.
inline bool watertight_hit_double(const Vec3& o, const WatertightRay& w, const Vec3& p0,
                                  const Vec3& p1, const Vec3& p2, float tmin, float tmax,
                                  TriangleHit& out) {
    const double sx = w.sx, sy = w.sy, sz = w.sz;
    auto shear = [&](const Vec3& p, double& x, double& y, double& z) {
        const double a[3] = {double(p[0]) - o[0], double(p[1]) - o[1], double(p[2]) - o[2]};
        x = a[w.kx] - sx * a[w.kz];
        y = a[w.ky] - sy * a[w.kz];
        z = sz * a[w.kz];
    };
    double ax, ay, az, bx, by, bz, cx, cy, cz;
    shear(p0, ax, ay, az);
    shear(p1, bx, by, bz);
    shear(p2, cx, cy, cz);
    const double U = cx * by - cy * bx;
    const double V = ax * cy - ay * cx;
    const double W = bx * ay - by * ax;
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return false;
    const double det = U + V + W;
    if (det == 0.0) return false;
    const double inv_det = 1.0 / det;
    const double t = (U * az + V * bz + W * cz) * inv_det;
    // Double roundings; the subtraction p - o is exact, so z has one rounding fewer than in
    // float and x, y one fewer as well.
    const double delta_t = watertight_t_error<double>({ax, ay, az, bx, by, bz, cx, cy, cz}, U, V, W,
                                                      inv_det, double_gamma(2), double_gamma(4),
                                                      double_gamma(2), double_gamma(3));
    if (!(t > delta_t)) return false;
    const float tf = static_cast<float>(t);
    if (!(tf > tmin && tf <= tmax)) return false;
    out.t = tf;
    out.u = static_cast<float>(V * inv_det);
    out.v = static_cast<float>(W * inv_det);
    return true;
}

/// Watertight ray-triangle test of Woop, Benthin and Wald (JCGT 2(1), 2013), double-sided.
/// Rays through a shared edge or vertex of a closed mesh hit at least one of its triangles.
/// Hits must also have t certainly positive given the arithmetic's error bound (pbrt-v4), so a
/// ray starting on (or within rounding of) a triangle's plane does not hit it. The float bound
/// grows with the triangle's extent, so a real hit close to the origin, such as a ray spawned
/// near a concave edge crossing the neighbouring face, can fall inside it: such hits are
/// recomputed in double (watertight_hit_double) and kept when double certifies them.
/// Edge functions that round to exactly zero are recomputed in double, as the paper does.
inline bool intersect_triangle_watertight(const Vec3& o, const WatertightRay& w, const Vec3& p0,
                                          const Vec3& p1, const Vec3& p2, float tmin, float tmax,
                                          TriangleHit& out) {
    const Vec3 A = p0 - o;
    const Vec3 B = p1 - o;
    const Vec3 C = p2 - o;
    const float ax = A[w.kx] - w.sx * A[w.kz];
    const float ay = A[w.ky] - w.sy * A[w.kz];
    const float bx = B[w.kx] - w.sx * B[w.kz];
    const float by = B[w.ky] - w.sy * B[w.kz];
    const float cx = C[w.kx] - w.sx * C[w.kz];
    const float cy = C[w.ky] - w.sy * C[w.kz];
    // U, V, W are the scaled barycentrics of p0, p1, p2.
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    if (U == 0.f || V == 0.f || W == 0.f) {
        U = static_cast<float>(double(cx) * double(by) - double(cy) * double(bx));
        V = static_cast<float>(double(ax) * double(cy) - double(ay) * double(cx));
        W = static_cast<float>(double(bx) * double(ay) - double(by) * double(ax));
    }
    if ((U < 0.f || V < 0.f || W < 0.f) && (U > 0.f || V > 0.f || W > 0.f)) return false;
    const float det = U + V + W;
    if (det == 0.f) return false;
    const float az = w.sz * A[w.kz];
    const float bz = w.sz * B[w.kz];
    const float cz = w.sz * C[w.kz];
    const float T = U * az + V * bz + W * cz;
    const float inv_det = 1.f / det;
    const float t = T * inv_det;
    if (!(t > tmin && t <= tmax)) return false;
    // Conservative t > 0 (pbrt-v4 section 6.8.7): reject hits whose t is not certainly
    // positive given the rounding of the sheared coordinates and edge functions, so a ray
    // spawned just off a surface cannot re-hit it through rounding.
    const float delta_t =
        watertight_t_error<float>({ax, ay, az, bx, by, bz, cx, cy, cz}, U, V, W, inv_det,
                                  float_gamma(3), float_gamma(5), float_gamma(2), float_gamma(3));
    if (!(t > delta_t)) return watertight_hit_double(o, w, p0, p1, p2, tmin, tmax, out);
    out.t = t;
    out.u = V * inv_det;
    out.v = W * inv_det;
    return true;
}

} // namespace candela
