// SceneEditor: appends primitives with their light records; check_scene: the invariants.
#include "candela/scene/scene_editor.h"

#include "candela/util/error.h"

#include <string>

namespace candela {

namespace {

std::string scene_name(const Scene& s) {
    return s.source.empty() ? std::string("scene built in code") : "scene '" + s.source + "'";
}

[[noreturn]] void fail(const Scene& s, const std::string& what) {
    throw Error(ErrorKind::Scene, scene_name(s) + ": " + what);
}

std::string mesh_label(const Scene& s, std::size_t i) {
    return "mesh " + std::to_string(i) + " ('" + s.meshes[i].name + "')";
}

std::string light_label(const Scene& s, std::size_t i) {
    return std::string(light_kind_name(s.lights[i].kind)) + " light " + std::to_string(i);
}

/// The two-sided Mesh light of mesh `index`: radiance of its material, area in double, and the
/// choice of a triangle in proportion to its area with each triangle's area per probability.
Light mesh_light(const Mesh& m, std::uint32_t index, const Material& mat) {
    Light l;
    l.kind = LightKind::Mesh;
    l.L = mat.radiance;
    l.geom_id = index;
    double total = 0.0;
    std::vector<double> area(m.triangle_count());
    for (std::size_t t = 0; t < area.size(); ++t) {
        const Vec3d p0(m.positions[m.indices[3 * t]]);
        area[t] = 0.5 * length(cross(Vec3d(m.positions[m.indices[3 * t + 1]]) - p0,
                                     Vec3d(m.positions[m.indices[3 * t + 2]]) - p0));
        total += area[t];
    }
    l.area = static_cast<float>(total);
    if (area.empty()) return l;
    l.tri_choice = UnitCdf(round_to_units(area));
    l.tri_area_per_pmf.resize(area.size());
    for (std::size_t t = 0; t < area.size(); ++t) {
        const double pmf = double(l.tri_choice.pmf(t));
        l.tri_area_per_pmf[t] = pmf > 0.0 ? static_cast<float>(area[t] / pmf) : 0.f;
    }
    return l;
}

void check_mesh(const Scene& s, std::size_t i) {
    const Mesh& m = s.meshes[i];
    if (m.indices.size() % 3 != 0)
        fail(s, mesh_label(s, i) + " has " + std::to_string(m.indices.size()) +
                    " indices, not a multiple of 3");
    for (std::size_t c = 0; c < m.indices.size(); ++c)
        if (m.indices[c] >= m.positions.size())
            fail(s, mesh_label(s, i) + ": index " + std::to_string(c) + " is " +
                        std::to_string(m.indices[c]) + ", out of range (" +
                        std::to_string(m.positions.size()) + " vertices)");
    if (!m.normals.empty() && m.normals.size() != m.positions.size())
        fail(s, mesh_label(s, i) + " has " + std::to_string(m.normals.size()) + " normals for " +
                    std::to_string(m.positions.size()) + " vertices");
    if (m.positions.padded_size() != m.positions.size() + 1 ||
        m.positions.data()[m.positions.size()] != Vec3(0.f))
        fail(s, mesh_label(s, i) + " lacks the spare Vec3 after its positions");
    if (m.material >= s.materials.size())
        fail(s, mesh_label(s, i) + " has material " + std::to_string(m.material) + " of " +
                    std::to_string(s.materials.size()));
    const bool emits = s.materials[m.material].is_emissive();
    if (!emits) {
        if (m.light != -1)
            fail(s, mesh_label(s, i) + " has light record " + std::to_string(m.light) +
                        " but its material does not emit");
        return;
    }
    if (m.light < 0 || static_cast<std::size_t>(m.light) >= s.lights.size())
        fail(s, mesh_label(s, i) + " is emissive but has no light record (light = " +
                    std::to_string(m.light) + ")");
    const Light& l = s.lights[static_cast<std::size_t>(m.light)];
    if ((l.kind != LightKind::Mesh && l.kind != LightKind::Area) || l.geom_id != i)
        fail(s, mesh_label(s, i) + " has light record " + std::to_string(m.light) + ", a " +
                    light_kind_name(l.kind) + " light of geometry " + std::to_string(l.geom_id) +
                    ", not its own");
}

void check_sphere(const Scene& s, std::size_t i) {
    const Sphere& sp = s.spheres[i];
    const std::string label = "sphere " + std::to_string(i);
    if (sp.material >= s.materials.size())
        fail(s, label + " has material " + std::to_string(sp.material) + " of " +
                    std::to_string(s.materials.size()));
    const bool emits = s.materials[sp.material].is_emissive();
    if (!emits) {
        if (sp.light != -1)
            fail(s, label + " has light record " + std::to_string(sp.light) +
                        " but its material does not emit");
        return;
    }
    if (sp.light < 0 || static_cast<std::size_t>(sp.light) >= s.lights.size())
        fail(s, label + " is emissive but has no light record (light = " +
                    std::to_string(sp.light) + ")");
    const Light& l = s.lights[static_cast<std::size_t>(sp.light)];
    if (l.kind != LightKind::Sphere || l.geom_id != i)
        fail(s, label + " has light record " + std::to_string(sp.light) + ", a " +
                    light_kind_name(l.kind) + " light of geometry " + std::to_string(l.geom_id) +
                    ", not its own");
}

void check_light(const Scene& s, std::size_t i) {
    const Light& l = s.lights[i];
    const auto self = static_cast<std::int32_t>(i);
    switch (l.kind) {
    case LightKind::Mesh:
        if (l.geom_id >= s.meshes.size() || s.meshes[l.geom_id].light != self)
            fail(s, light_label(s, i) + " names mesh " + std::to_string(l.geom_id) +
                        ", which does not name it back");
        if (l.tri_choice.size() != s.meshes[l.geom_id].triangle_count() ||
            l.tri_area_per_pmf.size() != s.meshes[l.geom_id].triangle_count())
            fail(s, light_label(s, i) + " has " + std::to_string(l.tri_choice.size()) +
                        " triangle choices and " + std::to_string(l.tri_area_per_pmf.size()) +
                        " triangle densities for " + mesh_label(s, l.geom_id) + " of " +
                        std::to_string(s.meshes[l.geom_id].triangle_count()) + " triangles");
        break;
    case LightKind::Sphere:
        if (l.geom_id >= s.spheres.size() || s.spheres[l.geom_id].light != self)
            fail(s, light_label(s, i) + " names sphere " + std::to_string(l.geom_id) +
                        ", which does not name it back");
        break;
    case LightKind::Environment:
        if (!s.env) fail(s, light_label(s, i) + " has no environment map (Scene::env)");
        break;
    case LightKind::Count:
        fail(s, "light " + std::to_string(i) + " has no valid kind");
    default:
        break; // Area (panel checked from its mesh), Point, Spot, Directional, Ambient
    }
}

} // namespace

std::uint32_t SceneEditor::add_material(const Material& m) {
    s_.materials.push_back(m);
    return static_cast<std::uint32_t>(s_.materials.size() - 1);
}

std::uint32_t SceneEditor::add_mesh(Mesh m) {
    const auto index = static_cast<std::uint32_t>(s_.meshes.size());
    if (m.material >= s_.materials.size())
        fail(s_, "mesh '" + m.name + "' added with material " + std::to_string(m.material) +
                     " of " + std::to_string(s_.materials.size()));
    if (m.light != -1)
        fail(s_, "mesh '" + m.name +
                     "' added with a light record already set; the editor makes "
                     "light records");
    const Material& mat = s_.materials[m.material];
    if (mat.is_emissive()) {
        if (m.triangle_count() > UnitCdf::kUnits)
            fail(s_, "emissive mesh '" + m.name + "' has " + std::to_string(m.triangle_count()) +
                         " triangles; a mesh light holds at most 2^23");
        m.light = static_cast<std::int32_t>(s_.lights.size());
        s_.lights.push_back(mesh_light(m, index, mat));
    }
    s_.meshes.push_back(std::move(m));
    return index;
}

std::uint32_t SceneEditor::add_sphere(const Sphere& sphere) {
    const auto index = static_cast<std::uint32_t>(s_.spheres.size());
    if (sphere.material >= s_.materials.size())
        fail(s_, "sphere " + std::to_string(index) + " added with material " +
                     std::to_string(sphere.material) + " of " +
                     std::to_string(s_.materials.size()));
    if (sphere.light != -1)
        fail(s_, "sphere " + std::to_string(index) +
                     " added with a light record already set; the editor makes light records");
    Sphere sp = sphere;
    const Material& mat = s_.materials[sp.material];
    if (mat.is_emissive()) {
        Light l;
        l.kind = LightKind::Sphere;
        l.L = mat.radiance;
        l.p = sp.center;
        l.radius = sp.radius; // 1 for an ellipsoid, whose size is in its map
        l.area = static_cast<float>(sphere_area(sp));
        l.geom_id = index;
        sp.light = static_cast<std::int32_t>(s_.lights.size());
        s_.lights.push_back(std::move(l));
    }
    s_.spheres.push_back(sp);
    return index;
}

std::uint32_t SceneEditor::add_light(Light l) {
    if (l.kind == LightKind::Mesh || l.kind == LightKind::Sphere || l.kind == LightKind::Count)
        fail(s_, std::string("a ") + light_kind_name(l.kind) +
                     " light is made by adding its emissive primitive, not by add_light");
    s_.lights.push_back(std::move(l));
    return static_cast<std::uint32_t>(s_.lights.size() - 1);
}

std::uint32_t SceneEditor::add_rect_panel(std::uint32_t light, const std::string& name) {
    if (light >= s_.lights.size() || s_.lights[light].kind != LightKind::Area)
        fail(s_, "panel '" + name + "' for light " + std::to_string(light) +
                     ", which is not a rect light");
    Material em;
    em.kind = BsdfKind::Emission;
    em.name = name;
    em.radiance = s_.lights[light].L;
    Mesh m;
    m.name = name;
    m.material = add_material(em);
    const Light& l = s_.lights[light];
    const Vec3 hx = l.dx * 0.5f, hy = l.dy * 0.5f;
    m.positions = {l.p - hx - hy, l.p + hx - hy, l.p + hx + hy, l.p - hx + hy};
    m.normals.assign(4, l.n);
    // (0,1,2) has normal cross(dx, dy); reverse the winding when that faces away from n.
    if (dot(cross(l.dx, l.dy), l.n) >= 0.f)
        m.indices = {0, 1, 2, 0, 2, 3};
    else
        m.indices = {0, 2, 1, 0, 3, 2};
    const auto index = static_cast<std::uint32_t>(s_.meshes.size());
    m.light = static_cast<std::int32_t>(light);
    s_.lights[light].geom_id = index;
    s_.meshes.push_back(std::move(m));
    return index;
}

std::uint32_t SceneEditor::add_rect_light(const Light& rect, const std::string& name) {
    const std::uint32_t light = add_light(rect);
    add_rect_panel(light, name);
    return light;
}

void SceneEditor::finalize() {
    check_scene(s_);
    s_.finalize();
}

void check_scene(const Scene& scene) {
    for (std::size_t i = 0; i < scene.meshes.size(); ++i)
        check_mesh(scene, i);
    for (std::size_t i = 0; i < scene.spheres.size(); ++i)
        check_sphere(scene, i);
    for (std::size_t i = 0; i < scene.lights.size(); ++i)
        check_light(scene, i);
}

} // namespace candela
