// The table of designed differences from the CS184 reference and which apply to a scene.
#include "candela/scene/cs184_differences.h"

#include <algorithm>

namespace candela {

const std::vector<Cs184Difference>& cs184_differences() {
    // The cells are the document's Markdown, byte for byte.
    static const std::vector<Cs184Difference> rows = {
        {"area-light pdf",
         "`dist / (area cos)`: light-sampled contributions are multiplied by the distance to the "
         "light",
         "solid-angle pdf `dist² / (area cos)`", Cs184Trigger::AreaLights},
        {"area lights seen by rays", "invisible; an emissive stand-in mesh makes the panel visible",
         "the `<area>` rectangle is a visible, one-sided luminaire; its coplanar emissive stand-in "
         "mesh is dropped (a note says so), so each light counts once",
         Cs184Trigger::AreaLights},
        {"emissive meshes and spheres",
         "not lights: found only by hemisphere sampling or after delta bounces",
         "area lights: sampled by next-event estimation, hit by BSDF rays, combined by MIS",
         Cs184Trigger::EmissiveShapes},
        {"point lights", "no distance falloff; attenuation ignored",
         "inverse-square law, colour = radiant intensity (W/sr); attenuation ignored with a note",
         Cs184Trigger::PointLights},
        {"spot lights", "broken (no contribution)",
         "COLLADA `falloff_angle` (full cone) and `falloff_exponent`, inverse square",
         Cs184Trigger::SpotLights},
        {"directional lights", "direction leaks the node translation", "the node's −Z axis",
         Cs184Trigger::DirectionalLights},
        {"ambient light", "uniform hemisphere light that camera rays never see",
         "uniform radiance from the upper hemisphere (world +Y), seen by every ray that escapes",
         Cs184Trigger::AmbientLight},
        {"glass Fresnel", "Schlick's approximation", "exact dielectric Fresnel",
         Cs184Trigger::Glass},
        {"`<roughness>` on glass and refraction", "parsed, unused",
         "a rough dielectric (Walter et al. 2007, Beckmann α = roughness) above 10⁻³",
         Cs184Trigger::RoughDielectric},
        {"non-uniform `<scale>` on a sphere", "ignored (a unit sphere)",
         "the ellipsoid the transform describes, in every backend; emissive ellipsoids are sampled "
         "exactly",
         Cs184Trigger::Ellipsoids},
        {"`-H` with point, spot or directional lights", "those lights are lost",
         "sampled directly (a note says so)", Cs184Trigger::DeltaLights},
        {"microfacet Smith Λ", "`a·π` in the denominator",
         "textbook Beckmann Λ with `a·√π`; conductor Fresnel at the microfacet normal",
         Cs184Trigger::Microfacet},
        {"field of view", "`-r` keeps the pixel pitch of the 800×600 view (a crop)",
         "the file's horizontal FOV spans the image at every resolution; `--framing cs184` "
         "keeps the course's pitch (below)",
         Cs184Trigger::Always},
        {"normals", "recomputed; boundary vertices get a quirky rule",
         "the file's `NORMAL` input when present, else area-weighted smooth normals",
         Cs184Trigger::Meshes},
        {"`translate`, `rotate`, `scale`, `lookat`, nested nodes", "undefined behaviour or ignored",
         "COLLADA semantics", Cs184Trigger::Transforms},
        {"n-gons", "one triangle per polygon",
         "fan-triangulated (a note per mesh; non-planar or non-convex polygons warn)",
         Cs184Trigger::Polygons},
        {"several primitive groups per mesh", "all but the first dropped",
         "all read, each with its bound material", Cs184Trigger::PrimitiveGroups},
        {"ray offsets", "a global `EPS_F = 1e-5`",
         "origins offset by floating-point error bounds (pbrt-v4)", Cs184Trigger::Always},
        {"random numbers", "one unsynchronised `mt19937` per translation unit",
         "a sampler seeded by (seed, pixel, sample index): bit-identical images for any thread "
         "count",
         Cs184Trigger::Always},
        {"`-m`, `-o`", "at most m bounces; `-o 0` keeps only bounce m",
         "the same, with `-o 0` dropping the directly seen emitters when m ≥ 1",
         Cs184Trigger::Always},
        {"Russian roulette", "constant continuation probability",
         "√(throughput) after `--rr-depth` scattering events (unbiased)", Cs184Trigger::Always},
        {"`-o`", "any integer; > 0 accumulates",
         "only 0 and 1 are accepted (anything else is a usage error)", Cs184Trigger::Always},
        {"`-p` cell renders", "a frame-sized image, mostly stale rate image",
         "an EXR whose data window is the cell inside the full frame, so it composites and merges "
         "in place; the rate image covers the cell",
         Cs184Trigger::Always},
        {"sample-rate image", "always written beside the PNG",
         "written for adaptive renders (the default relative sampler and `-a`), beside an 8-bit "
         "image (`-f x.png`, or `--preview` with an EXR); not with `--adaptive none`, nor beside "
         "an EXR alone",
         Cs184Trigger::Always},
        {"output", "8-bit PNG with exposure √2 and gamma 2.2",
         "HDR EXR with alpha (coverage), auxiliary channels and metadata; 8-bit previews in any "
         "OpenImageIO format use `--exposure` (default 0 EV), `--tonemap` and the sRGB curve, or "
         "with `--look cs184` the course's curve exactly (below)",
         Cs184Trigger::Always},
        {"missing `<up_axis>`", "scene collapses to the origin",
         "Y_UP with a warning (an error with `--strict`)", Cs184Trigger::MissingUpAxis},
        {"15-number `<matrix>` (CBgems camera)", "missing entries read as 0",
         "bottom row taken as (0 0 0 1), with a warning", Cs184Trigger::ShortMatrix},
    };
    return rows;
}

namespace {

std::string count_of(std::size_t n, const char* what) {
    return std::to_string(n) + " " + what;
}

std::size_t lights_of(const Scene& scene, LightKind kind) {
    return std::size_t(std::count_if(scene.lights.begin(), scene.lights.end(),
                                     [kind](const Light& l) { return l.kind == kind; }));
}

/// The materials in use (those some mesh or sphere refers to) that satisfy `pred`.
template <typename Pred> std::size_t materials_used(const Scene& scene, Pred pred) {
    std::vector<bool> used(scene.materials.size(), false);
    for (const Mesh& m : scene.meshes)
        if (m.material < used.size()) used[m.material] = true;
    for (const Sphere& s : scene.spheres)
        if (s.material < used.size()) used[s.material] = true;
    std::size_t n = 0;
    for (std::size_t i = 0; i < used.size(); ++i)
        n += used[i] && pred(scene.materials[i]) ? 1 : 0;
    return n;
}

/// Why `trigger` holds for the scene, "" when it does not.
std::string why(Cs184Trigger trigger, const SceneDesc& desc, const Scene& scene) {
    auto if_any = [](std::size_t n, const char* what) { return n > 0 ? count_of(n, what) : ""; };
    switch (trigger) {
    case Cs184Trigger::Always:
        return "every scene";
    case Cs184Trigger::AreaLights:
        return if_any(lights_of(scene, LightKind::Area), "area light(s)");
    case Cs184Trigger::EmissiveShapes:
        return if_any(lights_of(scene, LightKind::Mesh) + lights_of(scene, LightKind::Sphere),
                      "emissive mesh(es) or sphere(s)");
    case Cs184Trigger::PointLights:
        return if_any(lights_of(scene, LightKind::Point), "point light(s)");
    case Cs184Trigger::SpotLights:
        return if_any(lights_of(scene, LightKind::Spot), "spot light(s)");
    case Cs184Trigger::DirectionalLights:
        return if_any(lights_of(scene, LightKind::Directional), "directional light(s)");
    case Cs184Trigger::AmbientLight:
        return if_any(lights_of(scene, LightKind::Ambient), "ambient light(s)");
    case Cs184Trigger::Glass:
        return if_any(materials_used(scene,
                                     [](const Material& m) {
                                         return m.kind == BsdfKind::Glass ||
                                                m.kind == BsdfKind::Refraction;
                                     }),
                      "glass or refraction material(s)");
    case Cs184Trigger::RoughDielectric:
        return if_any(
            materials_used(scene, [](const Material& m) { return m.is_rough_dielectric(); }),
            "rough glass or refraction material(s)");
    case Cs184Trigger::Ellipsoids:
        return if_any(std::size_t(std::count_if(scene.spheres.begin(), scene.spheres.end(),
                                                [](const Sphere& s) { return s.ellipsoid; })),
                      "sphere(s) under a non-uniform scale");
    case Cs184Trigger::DeltaLights: {
        const std::size_t n = lights_of(scene, LightKind::Point) +
                              lights_of(scene, LightKind::Spot) +
                              lights_of(scene, LightKind::Directional);
        return n > 0 ? count_of(n, "point, spot or directional light(s), with -H") : "";
    }
    case Cs184Trigger::Microfacet:
        return if_any(
            materials_used(scene, [](const Material& m) { return m.kind == BsdfKind::Microfacet; }),
            "microfacet material(s)");
    case Cs184Trigger::Meshes:
        return if_any(scene.meshes.size(), "mesh(es)");
    case Cs184Trigger::Transforms:
        return if_any(desc.composed_transforms + desc.nested_nodes,
                      "<translate>/<rotate>/<scale>/<lookat> element(s) or nested node(s)");
    case Cs184Trigger::Polygons: {
        std::size_t n = 0;
        for (const DescGeometry& g : desc.geometries)
            n += g.fanned_polygons;
        return if_any(n, "polygon(s) of more than 3 vertices");
    }
    case Cs184Trigger::PrimitiveGroups:
        return if_any(
            std::size_t(std::count_if(desc.geometries.begin(), desc.geometries.end(),
                                      [](const DescGeometry& g) { return g.groups.size() > 1; })),
            "mesh(es) with several primitive groups");
    case Cs184Trigger::MissingUpAxis:
        return desc.up_axis_given ? "" : "no <up_axis>";
    case Cs184Trigger::ShortMatrix:
        return if_any(desc.short_matrices, "<matrix> element(s) of 12-15 numbers");
    }
    return "";
}

} // namespace

std::vector<AppliedDifference> cs184_differences_for(const SceneDesc& desc, const Scene& scene) {
    std::vector<AppliedDifference> out;
    for (const Cs184Difference& row : cs184_differences()) {
        std::string w = why(row.trigger, desc, scene);
        if (!w.empty()) out.push_back({&row, std::move(w)});
    }
    return out;
}

} // namespace candela
