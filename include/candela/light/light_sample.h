#pragma once
// Sampling and evaluation of every light kind (closed set, a switch on Light::kind; no virtual
// calls). Conventions used by all functions below:
//   * `wi` is a unit world direction from the reference point toward the light.
//   * Solid-angle pdfs are per steradian at the reference point; delta lights report pdf 1 and
//     their `L` is already the (intensity / distance^2 or irradiance) factor that multiplies the
//     BSDF and the cosine, so the estimator is f * L * cos / pdf for every kind.
//   * Area lights are sampled without visibility: the caller traces the shadow ray.
//   * Environment radiance is looked up bilinearly (spec section 2.6) by both sample_li and
//     escaped_radiance, so light samples and BSDF samples see the same function (see envmap.h).
//     It comes from Scene::env alone; Light::L of an Environment light is not used.
#include "candela/math/float_error.h"
#include "candela/math/sh9.h"
#include "candela/math/vec.h"
#include "candela/sampling/rng.h"
#include "candela/scene/light.h"
#include "candela/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace candela {

struct LightSample {
    Rgb L;      ///< radiance arriving at the reference point along -wi (before occlusion)
    Vec3 wi;    ///< unit direction from the reference point toward the light
    float dist; ///< distance to p_light; +infinity for infinite (directional, ambient, env) lights
    float pdf;  ///< solid-angle pdf of wi at the reference point; 1 for delta lights
    Vec3 p_light; ///< sampled point on the light (finite lights); the reference point otherwise
    Vec3 n_light; ///< unit surface normal at p_light facing the reference point; -wi when none
    bool is_delta;
    /// Conservative absolute rounding-error bound of p_light, per axis (zero for points that are
    /// not on a surface: point and spot lights, infinite lights). Shadow rays offset their far
    /// end by it (spawn_ray_to), so a sampled point that rounds to just beyond the emitter's
    /// surface cannot make the emitter occlude itself.
    Vec3 p_error;
    /// Mesh lights: the triangle p_light lies on (pdf_li's `prim`); 0 for every other kind.
    std::uint32_t prim = 0;
};

namespace light_detail {

/// Area of the Area light's parallelogram p + s dx + t dy. The (s, t) square maps to it with a
/// constant Jacobian |dx x dy|, so uniform (s, t) samples have area density 1 / this value.
inline float rect_area(const Light& light) {
    return length(cross(light.dx, light.dy));
}

/// A finite-light sample at point p with normal n (any orientation) as seen from ref_p, with
/// area density 1/area converted to solid angle. nullopt when the point is at the reference
/// point or seen (almost) exactly edge-on, where the solid-angle density overflows; pdf_li
/// reports 0 for the same directions, so the two stay consistent and MIS never sees inf/inf.
inline std::optional<LightSample> area_sample(const Rgb& L, const Vec3& ref_p, const Vec3& p,
                                              const Vec3& p_error, const Vec3& n, float area) {
    Vec3 d = p - ref_p;
    float dist2 = length_squared(d);
    // Coincident points and squared distances that overflow (points ~1e19 apart) have no usable
    // direction.
    if (!(dist2 > 0.f) || !std::isfinite(dist2) || !(area > 0.f)) return std::nullopt;
    float dist = std::sqrt(dist2);
    Vec3 wi = d * (1.f / dist);
    float cos_l = dot(n, wi);
    float abs_cos = std::abs(cos_l);
    if (!(abs_cos > 0.f)) return std::nullopt;
    LightSample s;
    s.L = L;
    s.wi = wi;
    s.dist = dist;
    s.pdf = dist2 / (area * abs_cos);
    if (!std::isfinite(s.pdf)) return std::nullopt;
    s.p_light = p;
    s.p_error = p_error;
    s.n_light = cos_l > 0.f ? -n : n; // face the reference point
    s.is_delta = false;
    return s;
}

} // namespace light_detail

/// sample_li() of an Area light, inline: the integrator calls it directly for the most common
/// light of the CS184 scenes, so that the sample is computed where it is used.
inline std::optional<LightSample> sample_rect(const Light& light, const Vec3& ref_p, Vec2 u) {
    const Vec3 ds = light.dx * (u.x - 0.5f), dt = light.dy * (u.y - 0.5f);
    const Vec3 p = light.p + ds + dt;
    // Two products (after the exact u - 1/2) and two sums.
    const Vec3 p_error = (vabs(light.p) + vabs(ds) + vabs(dt)) * float_gamma(4);
    // One-sided: the reference point must lie on the emitting side of the plane.
    if (!(dot(ref_p - light.p, light.n) > 0.f)) return std::nullopt;
    return light_detail::area_sample(light.L, ref_p, p, p_error, light.n,
                                     light_detail::rect_area(light));
}

/// Samples a direction toward `light` from `ref_p` using the uniform point `u` of [0,1)^2 (as
/// 32-bit coordinates: a mesh light chooses its triangle, an environment map its texel from all
/// 32 bits, see sampling/unit_cdf.h; every other kind uses bits_to_unit_point(u)). Returns
/// nullopt when the sample contributes nothing: reference point behind a one-sided Area light,
/// outside a spot cone, below the horizon of a degenerate configuration, or a zero pdf.
/// Otherwise `pdf` is per unit solid angle (1 for delta lights).
std::optional<LightSample> sample_li(const Scene& scene, const Light& light, const Vec3& ref_p,
                                     Bits2 u);
/// sample_li() of the point u of [0, 1)^2 (unit_point_to_bits).
inline std::optional<LightSample> sample_li(const Scene& scene, const Light& light,
                                            const Vec3& ref_p, Vec2 u) {
    return sample_li(scene, light, ref_p, unit_point_to_bits(u));
}

/// True when a ray can meet scene light `index`: its emitting surface is geometry of the scene
/// (Mesh, Sphere, an Area with its panel mesh), or it is an Ambient or Environment light that an
/// escaping ray sees. Only then can a BSDF-sampled direction find its light, and next-event
/// estimation share that light with BSDF sampling by MIS. False for Point, Spot and Directional
/// lights and for an Area record without a panel (SceneEditor::add_light without
/// add_rect_panel): next-event estimation alone gathers their light and must keep all of it.
bool light_found_by_rays(const Scene& scene, std::size_t index);

/// Solid-angle pdf (per steradian at ref_p) with which sample_li(scene, light, ref_p, .) would
/// produce direction `wi`, whose ray first meets the light at `p_light` with geometric normal
/// `n_light` (either orientation), on triangle `prim` of a mesh light (ignored for other kinds).
/// For infinite lights p_light and n_light are ignored. Returns 0 for delta lights and for
/// directions sample_li never produces (e.g. the back of an Area).
float pdf_li(const Scene& scene, const Light& light, const Vec3& ref_p, const Vec3& wi,
             const Vec3& p_light, const Vec3& n_light, std::uint32_t prim);

/// Emitted radiance leaving a point of an emitting surface (Area, Mesh, Sphere) with geometric
/// normal `n_light` toward the unit direction `w_from_light`. Area emits only on the side of its
/// normal (dot(n, w) > 0); Mesh and Sphere emit on both sides. Returns 0 for every other kind.
Rgb light_le(const Light& light, const Vec3& n_light, const Vec3& w_from_light);

/// Radiance of one infinite area light (Ambient: its L when dir.y > 0, else 0; Environment:
/// bilinear map lookup) along the unit direction `dir` of a ray that leaves the scene. 0 for
/// every other kind. Multiple importance sampling weighs each infinite light on its own with
/// this and escaped_pdf(): light sampling evaluates only the light it picked.
Rgb escaped_le(const Scene& scene, const Light& light, const Vec3& dir);
/// escaped_le(), with escaped_pdf() in *pdf (an environment map's lookup made once for both).
Rgb escaped_le(const Scene& scene, const Light& light, const Vec3& dir, float* pdf);

/// Radiance carried by a ray that leaves the scene along unit direction `dir`: the sum of
/// escaped_le() over every light. Zero when the scene has no infinite area light.
Rgb escaped_radiance(const Scene& scene, const Vec3& dir);

/// pdf_li of an infinite area light (Ambient or Environment) along the unit direction `dir`,
/// per steradian. 0 for every other kind (directional lights are delta lights).
float escaped_pdf(const Scene& scene, const Light& light, const Vec3& dir);

/// Scalar (luminance) emitted power of the light in watts-like units, used only to choose
/// lights proportionally to their contribution. Infinite lights give the power through a unit
/// area facing them (their irradiance, or integrated radiance over the sphere divided by pi),
/// whatever the scene's size: the light choice (light_choice.h) weighs them apart from finite
/// lights.
float light_power(const Scene& scene, const Light& light);

/// What the irradiance an infinite light gives a surface is computed from (light_irradiance):
/// the light's kind, the luminance of its radiance, its direction (directional) and the
/// environment map's irradiance coefficients (environment).
struct InfiniteIrradiance {
    LightKind kind = LightKind::Ambient;
    float lum = 0.f; ///< luminance of L (directional, ambient)
    Vec3 dir;        ///< unit direction toward a directional light
    Sh9 sh{};        ///< EnvMap::irradiance_sh() of an environment light
};
/// The model of an infinite light (directional, ambient or environment); Error(Internal) for any
/// other kind.
InfiniteIrradiance infinite_irradiance_model(const Scene& scene, const Light& light);

/// Luminance of the irradiance that an unoccluded surface with unit normal n receives from an
/// infinite light, for light selection: lum max(0, n . dir) for a directional light,
/// lum pi (1 + n.y) / 2 for an ambient one (its upper hemisphere, exactly), the map's
/// order-2 harmonic estimate (at least 0) for an environment.
inline float light_irradiance(const InfiniteIrradiance& m, const Vec3& n) {
    switch (m.kind) {
    case LightKind::Directional:
        return m.lum * std::max(0.f, dot(n, m.dir));
    case LightKind::Ambient:
        return m.lum * kPi * 0.5f * (1.f + n.y);
    default:
        return std::max(0.f, sh9_eval(m.sh, n));
    }
}

} // namespace candela
