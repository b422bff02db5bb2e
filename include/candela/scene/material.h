#pragma once
// Surface materials as the scene holds them: plain parameters of a closed set of BSDF kinds.
// The BSDF code (candela/bsdf/bsdf.h) switches on `kind`; nothing here is virtual.
#include "candela/math/vec.h"
#include <cmath>
#include <cstdint>
#include <string>

namespace candela {

enum class BsdfKind : std::uint8_t {
    Diffuse = 0, ///< Lambertian, f = albedo / pi
    Emission,    ///< emits `radiance`, reflects nothing (f = 0)
    Mirror,      ///< perfect specular reflection tinted by `reflectance`
    Glass,       ///< smooth dielectric, exact Fresnel split between reflection and refraction
    Refraction,  ///< smooth dielectric that only transmits
    Microfacet,  ///< rough conductor: Beckmann D, Smith G, conductor Fresnel from eta, k
    Count
};
constexpr int kBsdfKindCount = static_cast<int>(BsdfKind::Count);
const char* bsdf_kind_name(BsdfKind k);

/// Dielectric roughness (Beckmann alpha) below which Glass and Refraction are smooth: such a
/// lobe is narrower than 0.06 degrees, indistinguishable from a delta in any image, while its
/// densities (~1/alpha^2) and the float Jacobians of refraction lose precision.
constexpr float kMinDielectricRoughness = 1e-3f;
/// |ior - 1| below which a rough dielectric is treated as smooth: an index-matched interface
/// transmits straight through whatever its roughness (a delta), and near it the refraction
/// Jacobian's denominator (wo.h + eta wi.h)^2 vanishes.
constexpr float kMinRoughIndexGap = 1e-3f;

struct Material {
    BsdfKind kind = BsdfKind::Diffuse;
    std::string name;
    Rgb albedo{0.5f};       ///< Diffuse reflectance
    Rgb reflectance{1.f};   ///< Mirror and Glass reflection tint
    Rgb transmittance{1.f}; ///< Glass and Refraction transmission tint
    /// Emitted radiance (two-sided). Emission materials only emit; any other kind may emit too
    /// (for example the diffuse, glowing wall of a furnace test), which the COLLADA dialect
    /// cannot express but scenes built in code can.
    Rgb radiance{0.f};
    float ior = 1.5f; ///< Glass, Refraction: interior index (the exterior is vacuum)
    /// Glass, Refraction: Beckmann alpha of a rough interface (alpha = roughness; see
    /// is_rough_dielectric()); below kMinDielectricRoughness the interface is smooth.
    float roughness = 0.f;
    float alpha = 0.5f; ///< Microfacet: Beckmann roughness
    Rgb eta{1.f};       ///< Microfacet: conductor index, per channel
    Rgb k{0.f};         ///< Microfacet: conductor absorption, per channel

    /// A Glass or Refraction material with roughness at least kMinDielectricRoughness (and a
    /// usable index that differs from 1 by at least kMinRoughIndexGap) is the rough dielectric
    /// of Walter et al. 2007 (bsdf.h); otherwise it is the smooth, delta interface.
    bool is_rough_dielectric() const {
        return (kind == BsdfKind::Glass || kind == BsdfKind::Refraction) &&
               roughness >= kMinDielectricRoughness && std::isfinite(roughness) && ior > 0.f &&
               std::isfinite(ior) && std::abs(ior - 1.f) >= kMinRoughIndexGap;
    }
    /// Mirror and the smooth Glass and Refraction scatter into a single direction (f is a
    /// Dirac delta). A rough dielectric is not delta: it has a density, and next-event
    /// estimation applies at it.
    bool is_delta() const {
        return kind == BsdfKind::Mirror ||
               ((kind == BsdfKind::Glass || kind == BsdfKind::Refraction) &&
                !is_rough_dielectric());
    }
    /// Glass and Refraction, smooth or rough, scatter into both hemispheres (transmission), so
    /// a direction chosen at them may lie on either side of the surface.
    bool has_transmission() const {
        return kind == BsdfKind::Glass || kind == BsdfKind::Refraction;
    }
    bool is_emissive() const { return !is_black(radiance); }
};

} // namespace candela
