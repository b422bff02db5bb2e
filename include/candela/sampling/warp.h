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

// ---- Visible slopes of the Beckmann distribution -----------------------------------------------
// Heitz & d'Eon, "Importance Sampling Microfacet-Based BSDFs using the Distribution of Visible
// Normals" (EGSR 2014), their derivation for Beckmann: for alpha = 1 and a viewer at angle theta in
// the xz plane, the slopes (x, y) = (-m.x/m.z, -m.y/m.z) of the microfacets it sees have density
// proportional to (cos theta - x sin theta)^+ P22(x, y), with the Beckmann slope density
// P22(x, y) = exp(-x^2 - y^2) / pi. P22 factors, so y is a standard slope (density
// exp(-y^2) / sqrt(pi)) independent of x, and x has the marginal density
//     p(x) = (1 - t x) exp(-x^2) / Z(t)   on x <= 1/t,   t = tan(theta),
// whose cumulative integral from -infinity has the closed form
//     F(x) = sqrt(pi)/2 erfc(-x) + t/2 exp(-x^2)           (d/dx of the second term: -t x e^-x^2)
// and Z(t) = F(1/t) = sqrt(pi) (1 + Lambda(theta)) with the Smith Lambda of alpha = 1 (t = 0:
// Z = sqrt(pi), the plain Gaussian of y). Both terms of F are positive, so F has no cancellation
// anywhere. sample_visible_slope inverts F numerically: Newton's method kept inside a bracket
// that every step shrinks (bisection when a Newton step leaves it).

namespace warp_detail {

constexpr double kSqrtPi = 1.7724538509055160273;

/// Unnormalised cumulative F(x) of the visible-slope density (1 - t x) exp(-x^2), x <= 1/t.
inline double visible_slope_cdf(double x, double t) {
    return 0.5 * kSqrtPi * std::erfc(-x) + 0.5 * t * std::exp(-x * x);
}

/// Starting point for the inversion: the quantile of the standard slope density at probability
/// p (erfinv(2p - 1)) by Winitzki's closed-form approximation of erfinv ("A handy approximation
/// for the error function and its inverse", 2008; constant a = 0.147, relative error ~2e-3).
inline double approx_slope_quantile(double p) {
    constexpr double kA = 0.147;
    const double z = 2.0 * p - 1.0;
    const double l = std::log(std::max(1e-300, (1.0 - z) * (1.0 + z)));
    const double b = 2.0 / (kPiD * kA) + 0.5 * l;
    const double r = std::sqrt(std::max(0.0, std::sqrt(b * b - l / kA) - b));
    return z < 0.0 ? -r : r;
}

} // namespace warp_detail

/// Slopes beyond this magnitude (microfacets steeper than 88 degrees for alpha = 1) carry a
/// probability below exp(-30^2): the inversion clamps to it, and every u representable in float
/// maps inside.
constexpr double kMaxVisibleSlope = 30.0;

/// A slope x with density p(x) = (1 - t x)^+ exp(-x^2) / Z(t) (see above), t = tan_theta >= 0;
/// t = 0 gives the standard Beckmann slope (density exp(-x^2) / sqrt(pi)). Monotone in u.
///
/// The density is a Gaussian part exp(-x^2) (mass sqrt(pi)/2 erfc(-1/t) on the support) plus
/// a part -t x exp(-x^2), which for large t is a Rayleigh density on x < 0 with quantile
/// -sqrt(-ln u). The starting point mixes the two quantiles by the Gaussian part's share of Z;
/// Newton then takes 3 steps on average for t = 0 and 4-5 for t > 0 (measured over u on a
/// grid for t in [0.3, 3000]). Below the median it solves F(x) = u Z; above it, for t > 0, it
/// solves sqrt(Z - F(x)) = sqrt((1 - u) Z), which is close to linear in x near the support's
/// end 1/t, where the density vanishes linearly and Newton on F would converge only linearly.
inline float sample_visible_slope(float u, float tan_theta) {
    using namespace warp_detail;
    // Newton steps are quadratic once close: after a step below 1e-5 the error is ~1e-10, far
    // below the float the caller receives. The bracket halves on any step that leaves it.
    constexpr int kMaxIter = 64;
    constexpr double kTol = 1e-5;
    const double t = std::max(0.0, static_cast<double>(tan_theta));
    const double ud = static_cast<double>(u);
    double hi = t > 0.0 ? std::min(kMaxVisibleSlope, 1.0 / t) : kMaxVisibleSlope;
    double lo = -kMaxVisibleSlope; // F(lo) is 0 in double: erfc(30) and exp(-900) underflow
    const double gauss = 0.5 * kSqrtPi * std::erfc(-hi);
    const double z = gauss + 0.5 * t * std::exp(-hi * hi); // F(hi)
    const double target = ud * z;
    if (!(target > 0.0)) return static_cast<float>(lo);
    const bool upper = t > 0.0 && target > 0.5 * z;
    const double sqrt_rest = upper ? std::sqrt(z - target) : 0.0;
    const double gauss_share = gauss / z;
    const double rayleigh = -std::sqrt(-std::log(std::max(ud, 1e-300)));
    double x = gauss_share * approx_slope_quantile(ud) + (1.0 - gauss_share) * rayleigh;
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    for (int i = 0; i < kMaxIter; ++i) {
        const double e = std::exp(-x * x);
        const double cdf = 0.5 * kSqrtPi * std::erfc(-x) + 0.5 * t * e;
        if (cdf < target)
            lo = x;
        else
            hi = x;
        const double df = (1.0 - t * x) * e; // F'(x) >= 0 on the support
        double step;
        if (upper) {
            // d/dx sqrt(Z - F) = -F' / (2 sqrt(Z - F)).
            const double h = std::sqrt(std::max(0.0, z - cdf));
            step = -(h - sqrt_rest) * 2.0 * h / df;
        } else {
            step = (cdf - target) / df;
        }
        double next = df > 0.0 && std::isfinite(step) ? x - step : 0.5 * (lo + hi);
        // A Newton step this small means x is the root to the tolerance (tested before the
        // bracket, which rounding can close onto x itself once converged).
        if (std::abs(next - x) <= kTol * (1.0 + std::abs(x))) {
            x = next;
            break;
        }
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        x = next;
    }
    return static_cast<float>(std::min(x, t > 0.0 ? 1.0 / t : kMaxVisibleSlope));
}

/// Density of sample_visible_slope at x for tan_theta >= 0.
inline float sample_visible_slope_pdf(float x, float tan_theta) {
    using namespace warp_detail;
    const double t = std::max(0.0, static_cast<double>(tan_theta));
    const double xd = static_cast<double>(x);
    const double w = 1.0 - t * xd;
    if (!(w > 0.0)) return 0.f;
    const double hi = t > 0.0 ? std::min(kMaxVisibleSlope, 1.0 / t) : kMaxVisibleSlope;
    return static_cast<float>(w * std::exp(-xd * xd) / visible_slope_cdf(hi, t));
}

} // namespace candela
