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

} // namespace candela
