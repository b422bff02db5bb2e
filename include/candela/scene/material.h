#pragma once
// Surface materials as the scene holds them: plain parameters of a closed set of BSDF kinds.
// The BSDF code (candela/bsdf/bsdf.h) switches on `kind`; nothing here is virtual.
#include "candela/math/vec.h"
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

struct Material {
    BsdfKind kind = BsdfKind::Diffuse;
    std::string name;
    Rgb albedo{0.5f};        ///< Diffuse reflectance
    Rgb reflectance{1.f};    ///< Mirror and Glass reflection tint
    Rgb transmittance{1.f};  ///< Glass and Refraction transmission tint
    /// Emitted radiance (two-sided). Emission materials only emit; any other kind may emit too
    /// (for example the diffuse, glowing wall of a furnace test), which the COLLADA dialect
    /// cannot express but scenes built in code can.
    Rgb radiance{0.f};
    float ior = 1.5f;        ///< Glass, Refraction: interior index (the exterior is vacuum)
    float roughness = 0.f;   ///< Glass, Refraction: parsed, smooth interfaces only
    float alpha = 0.5f;      ///< Microfacet: Beckmann roughness
    Rgb eta{1.f};            ///< Microfacet: conductor index, per channel
    Rgb k{0.f};              ///< Microfacet: conductor absorption, per channel

    /// Mirror, Glass and Refraction scatter into a single direction (f is a Dirac delta).
    bool is_delta() const {
        return kind == BsdfKind::Mirror || kind == BsdfKind::Glass || kind == BsdfKind::Refraction;
    }
    bool is_emissive() const { return !is_black(radiance); }
};

} // namespace candela
