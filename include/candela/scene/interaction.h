#pragma once
// Hit -> shading data, and robust spawning of secondary rays. make_interaction() is the single
// place every accelerator's Hit becomes geometry, so shading cannot differ between backends.
#include "candela/math/float_bits.h"
#include "candela/math/float_error.h"
#include "candela/math/frame.h"
#include "candela/math/ray.h"
#include "candela/scene/hit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace candela {

class Scene;
struct Sphere;

/// A ray-surface intersection in world space.
struct SurfaceInteraction {
    Vec3 p;       ///< hit point
    Vec3 ng;      ///< unit geometric normal; NOT flipped toward the ray, but on ns's side
    Vec3 ns;      ///< unit shading normal as stored (its side is "outside" for dielectrics)
    Frame frame;  ///< shading frame, frame.n = ns
    Vec3 wo;      ///< unit direction toward the ray origin (-d / |d|)
    Vec3 p_error; ///< conservative absolute error bound of p, per axis
    float t = 0.f;
    std::uint32_t material = 0;
    std::int32_t light = -1; ///< index into Scene::lights when the surface emits, else -1
    std::uint32_t geom_id = 0, prim_id = 0;
};

namespace interaction_detail {
/// Below this squared length an interpolated shading normal is treated as cancelled (opposite
/// vertex normals) and the geometric normal is used instead; far above float underflow.
constexpr float kMinNormalLengthSq = 1e-20f;

/// A direction whose squared length is within this of 1 is taken as unit: a normalized float
/// vector is off by a few ulp (~1e-7), and 4e-7 in squared length (2e-7 in length, 2 ulp more)
/// is far below what any BSDF or offset computation notices.
constexpr float kUnitLengthSqTolerance = 4e-7f;

/// v / |v|, or `fallback` when v is too short or its length overflows. Written as selects, so
/// that loops over many vectors stay branch-free (and vectorise).
inline Vec3 unit_or(const Vec3& v, const Vec3& fallback) {
    const float l2 = length_squared(v);
    const bool usable = l2 > kMinNormalLengthSq && l2 <= std::numeric_limits<float>::max();
    const Vec3 unit = v * (1.f / std::sqrt(l2));
    return vselect(usable, unit, fallback);
}
} // namespace interaction_detail

/// The unit direction toward the origin of a ray with direction d: rays the integrators trace
/// carry unit directions already (to rounding), others are normalized here.
inline Vec3 outgoing_direction(const Vec3& d) {
    const float d2 = length_squared(d);
    const Vec3 unit = normalize(d);
    return vselect(std::abs(d2 - 1.f) <= interaction_detail::kUnitLengthSqTolerance, -d, -unit);
}

/// The geometry of a triangle hit: point, error bound and normals.
struct TriangleSurface {
    Vec3 p, p_error, ng, ns;
};

/// The point at barycentrics (u, v) of corners p1 and p2 on triangle p0 p1 p2, seen along unit
/// wo, with vertex normals n0, n1, n2 (all zero for a mesh without normals: ns is then ng).
/// p = (1-u-v) p0 + u p1 + v p2 with the pbrt-v4 bound gamma(7) sum |b_i p_i|; ng =
/// normalize(cross(p1-p0, p2-p0)) flipped only to agree with ns; ns = normalized interpolated
/// vertex normal (ng when they cancel). make_interaction and the integrator's batch of hits
/// (run vectorised) both compute it here, so both give the same bits.
inline TriangleSurface triangle_surface(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                        const Vec3& n0, const Vec3& n1, const Vec3& n2, float u,
                                        float v, const Vec3& wo) {
    using interaction_detail::unit_or;
    const float b0 = 1.f - u - v, b1 = u, b2 = v;
    TriangleSurface t;
    t.p = p0 * b0 + p1 * b1 + p2 * b2;
    t.p_error = (vabs(p0 * b0) + vabs(p1 * b1) + vabs(p2 * b2)) * float_gamma(7);
    // A hit triangle has a non-zero cross product (both tests reject det == 0); the fallback
    // only guards against overflow in absurdly large triangles.
    const Vec3 ng = unit_or(cross(p1 - p0, p2 - p0), -wo);
    t.ns = unit_or(n0 * b0 + n1 * b1 + n2 * b2, ng);
    t.ng = vselect(dot(t.ns, ng) < 0.f, -ng, ng);
    return t;
}

/// Builds the interaction for `hit` of `ray`, identically for every backend.
/// Triangles: p = (1-u-v) p0 + u p1 + v p2 with the pbrt-v4 bound gamma(7) sum |b_i p_i|;
/// ng = normalize(cross(p1-p0, p2-p0)) flipped only to agree with ns; ns = normalized
/// interpolated vertex normal (ng when the mesh has none or they cancel).
/// Spheres: p re-projected onto the surface; ng = ns = outward normal.
/// Ellipsoids: the hit carried into object space, re-projected onto the unit sphere there and
/// mapped back (ellipsoid_point); ng = ns = normalize(to_object^T x), the outward normal.
/// Throws Error(Internal) when the hit names a primitive the scene does not have.
SurfaceInteraction make_interaction(const Scene& scene, const Ray& ray, const Hit& hit);

/// Shading-normal correction, applied by the integrators to every hit before shading, in two
/// steps (adapted_shading_normal).
///
/// 1. Interpolated normals can put the direction toward the viewer, wo, below the shading
///    surface even though it is above the geometric one (at the silhouettes of smooth meshes,
///    with file normals): a two-sided BSDF would then scatter from the surface's back, mostly
///    into the geometry, and a dielectric would take the ray as leaving when it enters. Where wo
///    is less than kShadingBendFraction x its geometric cosine above the shading surface, ns is
///    bent toward wo in the plane of ns and wo, ns' = normalize(ns + (tau - wo.ns) wo) with tau
///    that bound (taken on wo's side), so wo ends above ns' by about tau.
/// 2. Even with wo above it, a shading normal that leans away from wo can mirror wo below the
///    geometric surface. Such a reflection carries no light (a direction on the wrong geometric
///    side is dropped), so a smooth mirror goes dark where that happens (a narrow lobe loses the
///    part of it that falls below): at a coarse mirror coil, 1.3 % of the image's mean. Where the
///    mirror direction r of wo about ns is less than reflection_min_cos() above the geometric
///    surface, ns is replaced by the normal that mirrors wo into r lifted to that bound (r's
///    tangential direction kept): the half vector of wo and the lifted r.
///
/// Both bends are continuous in wo and leave every other configuration unchanged; flat
/// triangles and spheres (ns = ng) are never bent. Afterwards wo lies on the same side of ns and
/// ng, so a dielectric's side (entering or leaving) is the same decided by either normal; ns
/// stays on ng's side. The frame is rebuilt; wo exactly in the geometric plane gets ns = ng.
void adapt_shading_normal(SurfaceInteraction& si);

/// Fraction of wo's geometric cosine by which adapt_shading_normal keeps wo above the shading
/// surface. Small, so that only shading normals that nearly hide wo are touched, and relative to
/// the geometric cosine, so that the bend vanishes smoothly toward grazing views.
constexpr float kShadingBendFraction = 0.1f;

/// Geometric cosine that step 2 of adapt_shading_normal keeps the mirror direction of wo above
/// the surface: kReflectionLiftCos, or kReflectionLiftOfView x wo's own geometric cosine when
/// that is smaller. Small, so that a reflection is only lifted off the surface, not turned; and
/// never more than wo's own height (0.9 of it), so that a grazing viewer is not asked to
/// reflect steeper than it arrives: the lifted direction then stays on wo's side of the normal
/// that reflects it.
constexpr float kReflectionLiftCos = 0.01f;
constexpr float kReflectionLiftOfView = 0.9f;

inline float reflection_min_cos(float view_cos_g) {
    return std::min(kReflectionLiftOfView * std::abs(view_cos_g), kReflectionLiftCos);
}

/// The shading normal adapt_shading_normal() gives a surface with shading normal ns, geometric
/// normal ng and direction to the viewer wo, without branches (the integrator's triangle stage
/// computes it for a whole batch at once). Every candidate is computed and the right one
/// selected, so the arithmetic, and the bits, are those of the branching form.
inline Vec3 adapted_shading_normal(const Vec3& ns, const Vec3& ng, const Vec3& wo) {
    const float cos_g = dot(wo, ng);
    // Work on wo's side: s = +1 when wo is on the side ns and ng point to.
    const float s = cos_g > 0.f ? 1.f : -1.f;
    const float tau = kShadingBendFraction * std::abs(cos_g);
    const float cos_s = s * dot(wo, ns);
    // ns + k wo with k >= 0 toward wo's side only grows its component along s ng, so it cannot
    // vanish; the test only catches overflow (and NaN).
    const Vec3 bent = ns + wo * (s * (tau - cos_s));
    const float len2 = length_squared(bent);
    const bool usable = len2 > 0.f && len2 <= std::numeric_limits<float>::max();
    const Vec3 n1 = vselect(cos_s >= tau, ns, vselect(usable, bent / std::sqrt(len2), ng));

    // Step 2: r = 2 (wo.n1) n1 - wo, at least t above the geometric surface on wo's side. The
    // lifted direction keeps r's tangential part: r' = t s ng + sqrt(1 - t^2) rt / |rt|, and
    // the normals mirroring wo into r' are +-(their half vector). Both wo and r' are above the
    // surface, so the half vector is too and cannot vanish; rt cannot vanish where r is low
    // (r = -s ng would need n1 on the other side of the surface than ng).
    const Vec3 sng = ng * s;
    const float t = reflection_min_cos(cos_g);
    const Vec3 r = n1 * (2.f * dot(wo, n1)) - wo;
    const float r_up = dot(r, sng);
    const Vec3 rt = r - sng * r_up;
    const float rt2 = length_squared(rt);
    const float rt_scale = rt2 > 0.f ? std::sqrt((1.f - t * t) / rt2) : 0.f;
    const Vec3 half = wo + sng * t + rt * rt_scale;
    const float half2 = length_squared(half);
    const bool lift = r_up < t && rt2 > 0.f && half2 > 0.f;
    // The half vector is on wo's side; mirroring about -h is the same, and ns stays on ng's.
    const Vec3 n2 = vselect(lift, half * (s / std::sqrt(half2 > 0.f ? half2 : 1.f)), n1);
    // wo exactly in the geometric plane: no side to keep it on.
    return vselect(cos_g == 0.f, ng, n2);
}

/// A point of an ellipsoid (Sphere::is_ellipsoid()) with its error bound and outward normal.
struct EllipsoidPoint {
    Vec3 p;       ///< center + to_world * normalize(x)
    Vec3 p_error; ///< conservative absolute error bound of p, per axis (derived in the source)
    Vec3 n;       ///< unit outward normal, normalize(to_object^T normalize(x))
};

/// The ellipsoid point in the direction of the object-space vector x (any non-zero length; the
/// unit sphere point is normalize(x)). `fallback_n` is the normal used if x or the normal
/// cannot be normalised. Shared by make_interaction (x = to_object (hit - center)) and the light
/// sampler (x a sampled unit vector), so both ends of a shadow ray carry the same bound.
EllipsoidPoint ellipsoid_point(const Sphere& s, const Vec3& x, const Vec3& fallback_n);

/// A ray origin just off the surface at p (pbrt-v4 OffsetRayOrigin): p moved along ng by
/// dot(|ng|, p_error) to the side of w, then each moved coordinate is rounded one float further
/// away, so that a ray leaving along w cannot re-hit the surface it starts on.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& p_error, const Vec3& ng, const Vec3& w) {
    const float d = dot(vabs(ng), p_error);
    const Vec3 offset = ng * (dot(w, ng) < 0.f ? -d : d);
    const Vec3 po = p + offset;
    return {next_float_toward_sign(po.x, offset.x), next_float_toward_sign(po.y, offset.y),
            next_float_toward_sign(po.z, offset.z)};
}

/// A ray leaving `si` (point p with error bound p_error and geometric normal ng) along wi (wi
/// need not be unit: the ray keeps it as given, so a renderer passing unit wi gets distances in
/// t): offset origin, tmin 0, tmax +inf.
inline Ray spawn_ray(const Vec3& p, const Vec3& p_error, const Vec3& ng, const Vec3& wi) {
    Ray r;
    r.o = offset_ray_origin(p, p_error, ng, wi);
    r.d = wi;
    r.tmin = 0.f;
    r.tmax = std::numeric_limits<float>::infinity();
    return r;
}
inline Ray spawn_ray(const SurfaceInteraction& si, const Vec3& wi) {
    return spawn_ray(si.p, si.p_error, si.ng, wi);
}

/// Relative shortening of shadow rays so that they stop short of the target surface: the
/// target's own offset covers its rounding error, this covers the rounding of the difference
/// between the two ends and of the traversal's ray parameter (a few ulps), with a wide margin
/// (pbrt-v4 ShadowEpsilon).
constexpr float kShadowEpsilon = 1e-4f;

/// Shadow ray from the point p_from (error bound p_from_error, geometric normal n_from) to a
/// point p_target (with error bound p_target_error and normal n_target; pass a zero normal for
/// points not on a surface, e.g. point lights). Both ends are offset robustly; the direction is
/// the difference of the offset ends, not normalised, so t runs from 0 at the origin to 1 at the
/// target; tmin is 0 and tmax = 1 - kShadowEpsilon, so occluded() answers "is anything strictly
/// between the two surfaces". (Every backend's triangle and sphere tests take any direction
/// length; a hit's t is a fraction of the segment.) Inline: it is on every shadow ray's path.
inline Ray spawn_ray_between(const Vec3& p_from, const Vec3& p_from_error, const Vec3& n_from,
                             const Vec3& p_target, const Vec3& p_target_error,
                             const Vec3& n_target) {
    const Vec3 pf = offset_ray_origin(p_from, p_from_error, n_from, p_target - p_from);
    const Vec3 pt = offset_ray_origin(p_target, p_target_error, n_target, pf - p_target);
    const Vec3 delta = pt - pf;
    // Only the squared length is needed, to tell coincident ends (and ends so far apart that it
    // overflows) from a usable segment: the direction stays unnormalised and t runs from 0 at
    // one end to 1 at the other, which spares a square root and a division per shadow ray.
    const float dist2 = length_squared(delta);
    // Coincident ends get an empty interval (tmax < tmin), which makes the ray invalid, so
    // every accelerator reports it unoccluded without traversal. Selects, not branches: the
    // integrator computes a whole step's segments in one vectorised loop.
    const bool usable = (dist2 > 0.f) & std::isfinite(dist2);
    Ray r;
    r.o = pf;
    r.d = vselect(usable, delta, Vec3(0.f, 0.f, 1.f));
    r.tmin = 0.f;
    r.tmax = usable ? 1.f - kShadowEpsilon : -1.f;
    return r;
}

/// spawn_ray_between() from a surface interaction.
inline Ray spawn_ray_to(const SurfaceInteraction& si, const Vec3& p_target,
                        const Vec3& p_target_error, const Vec3& n_target) {
    return spawn_ray_between(si.p, si.p_error, si.ng, p_target, p_target_error, n_target);
}

} // namespace candela
