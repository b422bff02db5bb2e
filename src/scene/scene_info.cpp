// The summary of a scene behind `candela info`, and the notes a render prints about what it leaves
// out.
#include "candela/scene/scene_info.h"

#include "candela/math/constants.h"
#include "candela/util/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace candela {

namespace {

/// Vertical FOV reported by `info`: the one a 4:3 image gets (spec §11.2).
constexpr double kInfoAspect = 4.0 / 3.0;

std::string num(double v) {
    return fmt::format("{:.6g}", v);
}

/// A coordinate within this share of the scene's largest coordinate is float rounding of a
/// zero: arithmetic on coordinates of size S leaves residues of a few units in the last place of
/// S (2^-23 S each), and 16 of them cannot be told from 0.
constexpr double kZeroShareOfScale = 16.0 * std::numeric_limits<float>::epsilon();

/// The largest absolute coordinate of the bounds and the camera: the size rounding scales with.
double coordinate_scale(const Scene& s) {
    double scale = 0.0;
    for (const Vec3& v : {s.camera.pos, s.camera.target})
        for (int c = 0; c < 3; ++c)
            scale = std::max(scale, std::abs(double(v[c])));
    if (!s.bounds.empty())
        for (const Vec3& v : {s.bounds.lo, s.bounds.hi})
            for (int c = 0; c < 3; ++c)
                scale = std::max(scale, std::abs(double(v[c])));
    return scale;
}

/// `v` with the coordinates that are rounding of a zero at `scale` set to 0.
Vec3 rounding_zeroed(Vec3 v, double scale) {
    for (int c = 0; c < 3; ++c)
        if (std::abs(double(v[c])) <= kZeroShareOfScale * scale) v[c] = 0.f;
    return v;
}

std::string vec_text(const Vec3& u, double scale) {
    const Vec3 v = rounding_zeroed(u, scale);
    return "(" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + ")";
}

nlohmann::ordered_json vec_json(const Vec3& u, double scale) {
    const Vec3 v = rounding_zeroed(u, scale);
    return {float_for_json(v.x), float_for_json(v.y), float_for_json(v.z)};
}

struct Summary {
    std::array<int, kBsdfKindCount> bsdf{};
    std::array<int, kLightKindCount> lights{};
    std::vector<std::string> skipped;
    double vfov_deg = 0.0;
    int ellipsoids = 0; ///< spheres under a non-similarity transform
};

Summary summarize(const Scene& s) {
    Summary r;
    std::vector<bool> used(s.materials.size(), false);
    for (const Mesh& m : s.meshes)
        if (m.triangle_count() > 0) used[m.material] = true;
    for (const Sphere& sp : s.spheres)
        used[sp.material] = true;
    bool any_delta = false, any_rough_dielectric = false;
    for (std::size_t i = 0; i < used.size(); ++i)
        if (used[i]) {
            ++r.bsdf[static_cast<int>(s.materials[i].kind)];
            any_delta |= s.materials[i].is_delta();
            any_rough_dielectric |= s.materials[i].is_rough_dielectric();
        }
    for (const Light& l : s.lights)
        ++r.lights[static_cast<int>(l.kind)];
    auto has = [&](LightKind k) { return r.lights[static_cast<int>(k)] > 0; };
    auto has_b = [&](BsdfKind k) { return r.bsdf[static_cast<int>(k)] > 0; };

    if (s.spheres.empty()) r.skipped.push_back("no sphere intersection path (no spheres)");
    for (const Sphere& sp : s.spheres)
        r.ellipsoids += sp.is_ellipsoid() ? 1 : 0;
    if (!s.spheres.empty() && r.ellipsoids == 0)
        r.skipped.push_back("no ellipsoid intersection path (every sphere is round)");
    if (!any_delta)
        r.skipped.push_back(
            "no delta-BSDF paths (no mirror, smooth glass or smooth refraction materials)");
    if (!has_b(BsdfKind::Microfacet) && !any_rough_dielectric)
        r.skipped.push_back(
            "no microfacet evaluation (no microfacet materials, no rough glass or refraction)");
    if (!has(LightKind::Area) && !has(LightKind::Mesh) && !has(LightKind::Sphere))
        r.skipped.push_back("no area-light sampling (no area, mesh or sphere lights)");
    if (!has(LightKind::Point) && !has(LightKind::Spot) && !has(LightKind::Directional))
        r.skipped.push_back("no delta-light sampling (no point, spot or directional lights)");
    if (!has(LightKind::Ambient)) r.skipped.push_back("no ambient lookups (no ambient light)");
    if (!has(LightKind::Environment))
        r.skipped.push_back("no environment importance table (no environment)");
    r.vfov_deg =
        rad_to_deg(2.0 * std::atan(std::tan(deg_to_rad(0.5 * s.camera.hfov_deg)) / kInfoAspect));
    return r;
}

} // namespace

std::vector<std::string> skipped_features(const Scene& s) {
    return summarize(s).skipped;
}

std::string describe_scene(const Scene& s, bool json) {
    Summary sum = summarize(s);
    const double scale = coordinate_scale(s);
    if (json) {
        using Json = nlohmann::ordered_json;
        Json materials = Json::object(), lights = Json::object();
        for (int k = 0; k < kBsdfKindCount; ++k)
            materials[bsdf_kind_name(static_cast<BsdfKind>(k))] =
                sum.bsdf[static_cast<std::size_t>(k)];
        for (int k = 0; k < kLightKindCount; ++k)
            lights[light_kind_name(static_cast<LightKind>(k))] =
                sum.lights[static_cast<std::size_t>(k)];
        const Json bounds = s.bounds.empty() ? Json(nullptr)
                                             : Json{{"min", vec_json(s.bounds.lo, scale)},
                                                    {"max", vec_json(s.bounds.hi, scale)}};
        const Json j = {{"source", s.source},
                        {"triangles", s.triangle_count()},
                        {"spheres", s.spheres.size()},
                        {"ellipsoids", sum.ellipsoids},
                        {"meshes", s.meshes.size()},
                        {"materials", materials},
                        {"lights", lights},
                        {"bounds", bounds},
                        {"camera",
                         {{"position", vec_json(s.camera.pos, scale)},
                          {"target", vec_json(s.camera.target, scale)},
                          {"hfov_deg", float_for_json(s.camera.hfov_deg)},
                          {"vfov_deg_4x3", sum.vfov_deg}}},
                        {"skipped", sum.skipped}};
        return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
    }
    std::ostringstream o;
    o << "scene      " << s.source << "\n";
    o << "triangles  " << s.triangle_count() << " in " << s.meshes.size() << " meshes\n";
    o << "spheres    " << s.spheres.size();
    if (sum.ellipsoids > 0) o << " (" << sum.ellipsoids << " of them ellipsoids)";
    o << "\n";
    o << "materials ";
    for (int k = 0; k < kBsdfKindCount; ++k)
        if (int n = sum.bsdf[static_cast<std::size_t>(k)])
            o << " " << bsdf_kind_name(static_cast<BsdfKind>(k)) << " " << n;
    o << "\nlights    ";
    for (int k = 0; k < kLightKindCount; ++k)
        if (int n = sum.lights[static_cast<std::size_t>(k)])
            o << " " << light_kind_name(static_cast<LightKind>(k)) << " " << n;
    if (s.lights.empty()) o << " none";
    o << "\nbounds     ";
    if (s.bounds.empty())
        o << "empty\n";
    else
        o << vec_text(s.bounds.lo, scale) << " .. " << vec_text(s.bounds.hi, scale) << "\n";
    o << "camera     at " << vec_text(s.camera.pos, scale) << " looking at "
      << vec_text(s.camera.target, scale) << ", FOV " << num(s.camera.hfov_deg) << " x "
      << num(sum.vfov_deg) << " deg (4:3)\n";
    o << "skips\n";
    for (const auto& line : sum.skipped)
        o << "  " << line << "\n";
    return o.str();
}

} // namespace candela
