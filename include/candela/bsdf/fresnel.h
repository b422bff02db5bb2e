#pragma once
// Fresnel reflectance of smooth interfaces for unpolarised light (Born & Wolf, "Principles of
// Optics", 1.5; conductor form as in Pharr et al., PBRT 3rd ed., 8.2.1) and the matching
// reflection / refraction directions. Directions point away from the surface.
#include "candela/math/vec.h"

#include <algorithm>
#include <cmath>

namespace candela {

/// Exact Fresnel reflectance of a dielectric interface. `cos_i` is the cosine between the incident
/// direction and the normal on the outside (+z) side; negative means arriving from the inside.
/// `eta` = n_inside / n_outside. Returns F in [0, 1]; 1 under total internal reflection.
inline float fresnel_dielectric(float cos_i, float eta) {
    cos_i = std::clamp(cos_i, -1.f, 1.f);
    if (cos_i < 0.f) {
        eta = 1.f / eta;
        cos_i = -cos_i;
    }
    float sin2_i = std::max(0.f, 1.f - cos_i * cos_i);
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.f) return 1.f;
    float cos_t = std::sqrt(std::max(0.f, 1.f - sin2_t));
    float denom_par = eta * cos_i + cos_t, denom_perp = cos_i + eta * cos_t;
    // Both denominators vanish only for cos_i = cos_t = 0, i.e. grazing incidence: F = 1.
    if (denom_par <= 0.f || denom_perp <= 0.f) return 1.f;
    float r_par = (eta * cos_i - cos_t) / denom_par;
    float r_perp = (cos_i - eta * cos_t) / denom_perp;
    return std::clamp(0.5f * (r_par * r_par + r_perp * r_perp), 0.f, 1.f);
}

/// Exact Fresnel reflectance of a conductor with complex index eta + i k (relative to vacuum),
/// for one channel. `cos_i` is the cosine of the incidence angle (its absolute value is used).
/// Returns F in [0, 1]; eta = 1, k = 0 gives 0, large k gives values close to 1.
inline float fresnel_conductor(float cos_i, float eta, float k) {
    float c = std::min(1.f, std::abs(cos_i));
    float cos2 = c * c, sin2 = 1.f - cos2;
    float eta2 = eta * eta, k2 = k * k;
    float t0 = eta2 - k2 - sin2;
    float a2pb2 = std::sqrt(std::max(0.f, t0 * t0 + 4.f * eta2 * k2));
    float t1 = a2pb2 + cos2;
    float a = std::sqrt(std::max(0.f, 0.5f * (a2pb2 + t0)));
    float t2 = 2.f * c * a;
    if (t1 + t2 <= 0.f) return 1.f; // grazing incidence on a vacuum-like medium
    float rs = (t1 - t2) / (t1 + t2);
    float t3 = cos2 * a2pb2 + sin2 * sin2;
    float t4 = t2 * sin2;
    float rp = t3 + t4 > 0.f ? rs * (t3 - t4) / (t3 + t4) : rs;
    return std::clamp(0.5f * (rs + rp), 0.f, 1.f);
}

/// Per-channel conductor Fresnel.
inline Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
    return {fresnel_conductor(cos_i, eta.x, k.x), fresnel_conductor(cos_i, eta.y, k.y),
            fresnel_conductor(cos_i, eta.z, k.z)};
}

/// Mirror reflection of w about the unit normal n: 2 (w.n) n - w.
inline Vec3 reflect(const Vec3& w, const Vec3& n) {
    return n * (2.f * dot(w, n)) - w;
}

/// Refracts w (pointing away from the surface on the side of n, w.n > 0) through an interface
/// with relative index eta = n_transmitted / n_incident. Returns false under total internal
/// reflection; otherwise writes the unit transmitted direction (on the other side of n) to wt.
inline bool refract(const Vec3& w, const Vec3& n, float eta, Vec3* wt) {
    float cos_i = dot(n, w);
    float sin2_i = std::max(0.f, 1.f - cos_i * cos_i);
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.f) return false;
    float cos_t = std::sqrt(1.f - sin2_t);
    *wt = -w / eta + n * (cos_i / eta - cos_t);
    return true;
}

} // namespace candela
