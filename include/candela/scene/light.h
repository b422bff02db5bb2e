#pragma once
// Lights as the scene holds them: world-space parameters of a closed set of kinds. Sampling and
// evaluation live in candela/light/light_sample.h and switch on `kind`.
#include "candela/math/vec.h"
#include "candela/sampling/unit_cdf.h"

#include <cstdint>
#include <vector>

namespace candela {

enum class LightKind : std::uint8_t {
    Area = 0,    ///< CGL <area>: one-sided parallelogram (a rectangle), uniform radiance `L`
    Mesh,        ///< emissive triangle mesh: two-sided, uniform radiance `L`
    Sphere,      ///< emissive sphere: uniform radiance `L` on its surface
    Point,       ///< isotropic point, radiant intensity `L` (W/sr), inverse-square falloff
    Spot,        ///< point with a cone: intensity `L` on the axis
    Directional, ///< distant light, irradiance `L` on a surface facing it
    Ambient,     ///< uniform radiance `L` from the upper hemisphere (world +Y), infinitely far
    Environment, ///< lat-long environment map (Scene::env), infinitely far
    Count
};
constexpr int kLightKindCount = static_cast<int>(LightKind::Count);
const char* light_kind_name(LightKind k);

struct Light {
    LightKind kind = LightKind::Point;
    Rgb L{0.f}; ///< radiance, intensity or irradiance as `kind` says
    /// Area: centre. Point, Spot: position. Sphere: centre.
    Vec3 p;
    /// Area: unit normal of the emitting side. Spot: unit axis the light shines along.
    /// Directional: unit direction *toward* the light.
    Vec3 n;
    /// Area: full edge vectors; the rectangle is p + s*dx + t*dy for s, t in [-1/2, 1/2].
    Vec3 dx, dy;
    float radius = 0.f;      ///< Sphere
    float area = 0.f;        ///< Area, Mesh, Sphere: total emitting area
    float cos_total = -1.f;  ///< Spot: cosine of the half-angle of the cone (falloff_angle / 2)
    float falloff_exp = 0.f; ///< Spot: COLLADA falloff_exponent, intensity * cos^exp
    std::uint32_t geom_id =
        0; ///< Mesh: index into Scene::meshes. Sphere: index into Scene::spheres
    /// Mesh: the choice of a triangle for area sampling, in proportion to its area, realised
    /// exactly (sampling/unit_cdf.h); one entry per triangle (empty for a mesh without any).
    UnitCdf tri_choice;
    /// Mesh: per triangle, its area divided by its choice probability: a point sampled on
    /// triangle k has area density 1 / tri_area_per_pmf[k] (0: a triangle without area).
    std::vector<float> tri_area_per_pmf;

    bool is_delta() const {
        return kind == LightKind::Point || kind == LightKind::Spot ||
               kind == LightKind::Directional;
    }
    bool is_infinite() const {
        return kind == LightKind::Directional || kind == LightKind::Ambient ||
               kind == LightKind::Environment;
    }
};

/// A rectangle light centred at `center`, with full edge vectors dx and dy, unit normal `n` of
/// its emitting side and uniform radiance L; its area is |dx x dy|.
Light rect_light(const Vec3& center, const Vec3& n, const Vec3& dx, const Vec3& dy, const Rgb& L);

} // namespace candela
