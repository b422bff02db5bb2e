#pragma once
// Warps from the unit square [0,1)^2 to common domains, with their densities.
// Directions are in a local frame with the pole at +z; densities are per unit solid angle
// unless stated otherwise. References: Shirley & Chiu, "A Low Distortion Map Between Disk and
// Square" (JGT 1997); Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed., ch. A.5;
// Walter et al., "Microfacet Models for Refraction through Rough Surfaces" (EGSR 2007).
#include "candela/math/sincos.h"
#include "candela/math/vec.h"

#include <algorithm>
#include <cmath>

namespace candela {

/// Concentric map of the square onto the unit disk (area-preserving up to a constant: the density
/// per unit disk area is 1/pi).
inline Vec2 square_to_uniform_disk_concentric(Vec2 u) {
    float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
    if (ox == 0.f && oy == 0.f) return {0.f, 0.f};
    // theta = phi with |phi| <= pi/4 in the first case, pi/2 - phi in the second (cos and sin
    // trade places), so one quarter-range sincos serves both.
    float s, c;
    if (std::abs(ox) > std::abs(oy)) {
        sincos_quarter((kPi / 4.f) * (oy / ox), &s, &c);
        return {ox * c, ox * s};
    }
    sincos_quarter((kPi / 4.f) * (ox / oy), &s, &c);
    return {oy * s, oy * c};
}

/// Cosine-weighted direction on the +z hemisphere (Malley's method on the concentric disk).
inline Vec3 square_to_cosine_hemisphere(Vec2 u) {
    Vec2 d = square_to_uniform_disk_concentric(u);
    float z = std::sqrt(std::max(0.f, 1.f - d.x * d.x - d.y * d.y));
    return {d.x, d.y, z};
}
/// Solid-angle density of square_to_cosine_hemisphere: cos(theta)/pi above the horizon, else 0.
inline float square_to_cosine_hemisphere_pdf(const Vec3& w) {
    return w.z > 0.f ? w.z * kInvPi : 0.f;
}

/// Uniform direction on the +z hemisphere.
inline Vec3 square_to_uniform_hemisphere(Vec2 u) {
    float z = u.x;
    float r = std::sqrt(std::max(0.f, 1.f - z * z));
    float s, c;
    sincos_turns(u.y, &s, &c); // phi = 2 pi u.y
    return {r * c, r * s, z};
}
/// Solid-angle density of square_to_uniform_hemisphere: 1/(2 pi) for z >= 0, else 0.
inline float square_to_uniform_hemisphere_pdf(const Vec3& w) {
    return w.z >= 0.f ? kInv2Pi : 0.f;
}

/// Uniform direction on the unit sphere.
inline Vec3 square_to_uniform_sphere(Vec2 u) {
    float z = 1.f - 2.f * u.x;
    float r = std::sqrt(std::max(0.f, 1.f - z * z));
    float s, c;
    sincos_turns(u.y, &s, &c); // phi = 2 pi u.y
    return {r * c, r * s, z};
}
/// Solid-angle density of square_to_uniform_sphere: 1/(4 pi).
inline float square_to_uniform_sphere_pdf(const Vec3& /*w*/) {
    return kInv4Pi;
}

/// Uniform point on a triangle, as barycentrics (b0, b1, b2) summing to 1; the point is
/// b0*p0 + b1*p1 + b2*p2. Density per unit triangle area is 1/area.
inline Vec3 square_to_uniform_triangle(Vec2 u) {
    float su = std::sqrt(u.x);
    float b1 = u.y * su;
    float b0 = 1.f - su;
    return {b0, b1, std::max(0.f, 1.f - b0 - b1)};
}

/// Smallest cone solid-angle factor (1 - cos_max) used by the cone pdf: below it float cannot
/// resolve the cone, and the density would overflow.
constexpr float kMinConeOneMinusCos = 1e-7f;

/// Uniform direction inside the cone of half-angle acos(cos_max) around +z.
inline Vec3 square_to_uniform_cone(Vec2 u, float cos_max) {
    // 1 - z computed directly: sqrt(1 - z^2) would cancel for narrow cones.
    float one_minus_z = u.x * (1.f - cos_max);
    float z = 1.f - one_minus_z;
    float r = std::sqrt(std::max(0.f, one_minus_z * (2.f - one_minus_z)));
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
/// Solid-angle density of square_to_uniform_cone: 1/(2 pi (1 - cos_max)) inside, 0 outside.
inline float square_to_uniform_cone_pdf(const Vec3& w, float cos_max) {
    if (w.z < cos_max) return 0.f;
    return kInv2Pi / std::max(1.f - cos_max, kMinConeOneMinusCos);
}

/// Beckmann microfacet normal m with density D(m) cos(theta_m) per solid angle (alpha > 0).
/// tan^2(theta) = -alpha^2 log(1 - u.x), phi = 2 pi u.y (Walter et al. 2007, eq. 28).
inline Vec3 square_to_beckmann(Vec2 u, float alpha) {
    float tan2 = -alpha * alpha * std::log1p(-u.x);
    float cos_t = 1.f / std::sqrt(1.f + tan2);
    // sin = tan * cos, not sqrt(1 - cos^2), which cancels and quantises narrow lobes.
    float sin_t = std::sqrt(tan2) * cos_t;
    float phi = 2.f * kPi * u.y;
    return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}
/// Solid-angle density of square_to_beckmann: D(m) cos(theta_m) with Beckmann D, 0 for m.z <= 0.
inline float square_to_beckmann_pdf(const Vec3& m, float alpha) {
    if (m.z <= 0.f) return 0.f;
    float cos2 = m.z * m.z;
    // sin^2 from the tangential components: 1 - cos^2 would cancel near the pole, and the
    // exponent amplifies that error by 1/alpha^2.
    float tan2 = (m.x * m.x + m.y * m.y) / cos2;
    float a2 = alpha * alpha;
    // exp(-tan2/a2) / (pi a2 cos^4) * cos; written to avoid overflow when cos is tiny.
    float e = std::exp(-tan2 / a2);
    if (e == 0.f) return 0.f;
    return e / (kPi * a2 * cos2 * m.z);
}

} // namespace candela
