#pragma once
// Beckmann microfacet distribution with the Smith height-correlated shadowing-masking form
// G = 1 / (1 + Lambda(wo) + Lambda(wi)) (Walter et al., "Microfacet Models for Refraction
// through Rough Surfaces", EGSR 2007; Heitz, "Understanding the Masking-Shadowing Function in
// Microfacet-Based BRDFs", JCGT 2014). Local frame: macro normal +z.
#include "candela/math/vec.h"
#include "candela/sampling/warp.h"

#include <algorithm>
#include <cmath>

namespace candela {

/// Smallest Beckmann alpha used: below it D overflows float for near-normal h; rougher than a
/// float can distinguish from a mirror anyway.
constexpr float kMinBeckmannAlpha = 1e-4f;
/// tan(theta) below which a direction is treated as the normal itself (Lambda = 0).
constexpr float kMinTanTheta = 1e-7f;

/// Beckmann normal distribution D(m) = exp(-tan^2/alpha^2) / (pi alpha^2 cos^4), per unit
/// solid angle of microfacet normals (projected-area normalised: integral of D cos = 1).
/// Returns 0 for m.z <= 0.
inline float beckmann_d(const Vec3& m, float alpha) {
    if (m.z <= 0.f) return 0.f;
    return square_to_beckmann_pdf(m, alpha) / m.z;
}

/// Smith Lambda for Beckmann (textbook form, a = 1 / (alpha tan(theta))):
/// Lambda = (erf(a) - 1 + exp(-a^2) / (a sqrt(pi))) / 2, written with erfc to avoid cancellation.
/// Returns 0 at normal incidence and a non-negative value otherwise (w.z <= 0 is treated by |z|).
inline float beckmann_lambda(const Vec3& w, float alpha) {
    float z = std::min(1.f, std::abs(w.z));
    float sin_t = std::sqrt(std::max(0.f, 1.f - z * z));
    if (sin_t <= kMinTanTheta * z) return 0.f;
    // Grazing: tan -> inf, a -> 0, Lambda -> inf; G then goes to 0 smoothly.
    double a = static_cast<double>(z) / (static_cast<double>(alpha) * sin_t);
    constexpr double kSqrtPi = 1.7724538509055160273;
    double lambda = 0.5 * (std::exp(-a * a) / (a * kSqrtPi) - std::erfc(a));
    return static_cast<float>(std::max(0.0, lambda));
}

/// Height-correlated Smith shadowing-masking G(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi)).
inline float beckmann_g(const Vec3& wo, const Vec3& wi, float alpha) {
    float s = 1.f + beckmann_lambda(wo, alpha) + beckmann_lambda(wi, alpha);
    return std::isfinite(s) ? 1.f / s : 0.f;
}

/// Smith masking of one direction, G1(w) = 1 / (1 + Lambda(w)), the form consistent with the
/// height-correlated G above.
inline float beckmann_g1(const Vec3& w, float alpha) {
    return 1.f / (1.f + beckmann_lambda(w, alpha));
}

/// Density of the distribution of visible normals seen from wo (wo.z > 0), per unit solid
/// angle of m: D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z (Heitz & d'Eon 2014, eq. 2). It
/// integrates to 1 over the hemisphere: the projected area of the visible microfacets equals
/// that of the macrosurface.
inline float beckmann_visible_pdf(const Vec3& m, const Vec3& wo, float alpha) {
    if (wo.z <= 0.f) return 0.f;
    const float wo_m = dot(wo, m);
    if (wo_m <= 0.f) return 0.f;
    const float pdf = beckmann_g1(wo, alpha) * wo_m * beckmann_d(m, alpha) / wo.z;
    return std::isfinite(pdf) ? pdf : 0.f;
}

/// A microfacet normal m drawn with density beckmann_visible_pdf(m, wo, alpha), wo.z > 0.
/// Heitz & d'Eon 2014 (the Beckmann method; the later "Sampling the GGX Distribution of Visible
/// Normals", Heitz 2018, is specific to GGX): stretch wo to the configuration of alpha = 1,
/// draw the visible slopes there (sample_visible_slope: x at the stretched incidence, y a
/// standard slope), rotate them to the azimuth of wo, unstretch by alpha, and turn the slope
/// into the normal (-x, -y, 1) / |.|.
inline Vec3 sample_beckmann_visible(const Vec3& wo, float alpha, Vec2 u) {
    const Vec3 ws = normalize(Vec3(alpha * wo.x, alpha * wo.y, wo.z));
    const float sin_t = std::sqrt(ws.x * ws.x + ws.y * ws.y);
    // tan = sin / cos; the stretched direction keeps wo.z > 0, so cos > 0.
    const float tan_t = sin_t / ws.z;
    const float sx = sample_visible_slope(u.x, tan_t);
    const float sy = sample_visible_slope(u.y, 0.f);
    float cos_phi = 1.f, sin_phi = 0.f;
    if (sin_t > 0.f) {
        cos_phi = ws.x / sin_t;
        sin_phi = ws.y / sin_t;
    }
    const float rx = alpha * (cos_phi * sx - sin_phi * sy);
    const float ry = alpha * (sin_phi * sx + cos_phi * sy);
    return normalize(Vec3(-rx, -ry, 1.f));
}

} // namespace candela
