#pragma once
// The one way to build a Scene in code: the COLLADA builder, the procedural scenes, the numerics
// suite and the tests all add their materials, meshes, spheres and lights through SceneEditor,
// which keeps the links between emissive primitives and their light records, and check the
// result with finalize().
#include "candela/scene/scene.h"

#include <cstdint>
#include <string>

namespace candela {

/// Appends to a Scene it edits in place. Indices returned are final: a material, mesh, sphere or
/// light keeps the index it was given (nothing is reordered or removed), so the order of the
/// calls is the order of Scene::materials, meshes, spheres and lights.
///
/// Emissive primitives get their light record when they are added: a mesh whose material emits
/// becomes a two-sided LightKind::Mesh light (area-sampling CDF included), an emissive sphere or
/// ellipsoid a LightKind::Sphere light. A rectangle light is an Area record (add_light) that
/// add_rect_panel() can make visible to rays as an emissive two-triangle mesh.
class SceneEditor {
  public:
    explicit SceneEditor(Scene& scene) : s_(scene) {}

    Scene& scene() { return s_; }
    const Scene& scene() const { return s_; }

    /// Appends a material; returns its index.
    std::uint32_t add_material(const Material& m);

    /// Appends `m` (its `light` must be -1) and, when its material emits, the Mesh light that
    /// samples it. Returns the mesh index. Throws Error when the material index is out of range.
    std::uint32_t add_mesh(Mesh m);

    /// Appends a sphere or ellipsoid (its `light` must be -1) and, when its material emits, its
    /// Sphere light. Returns the sphere index.
    std::uint32_t add_sphere(const Sphere& s);

    /// Appends a light of a kind that is not tied to a primitive: Point, Spot, Directional,
    /// Ambient, Environment (Scene::env is set separately) or Area (a record that is invisible
    /// to rays until add_rect_panel()). Mesh and Sphere lights come from add_mesh and add_sphere;
    /// passing one throws. Returns the light index.
    std::uint32_t add_light(Light l);

    /// Makes Area light `light` visible to rays: appends an emission material of its radiance
    /// named `name` and a two-triangle mesh covering the rectangle, with shading normal n and
    /// winding facing n, linked to the light both ways. Returns the mesh index.
    std::uint32_t add_rect_panel(std::uint32_t light, const std::string& name);

    /// add_light(rect) then add_rect_panel(): a visible rectangle light. Returns the light index.
    std::uint32_t add_rect_light(const Light& rect, const std::string& name);

    /// Checks the scene (check_scene) and computes its bounds and features (Scene::finalize).
    /// Call once, after the last addition.
    void finalize();

  private:
    Scene& s_;
};

/// Checks the invariants every consumer of a Scene relies on and throws Error(ErrorKind::Scene)
/// naming the scene, the primitive or light and what is wrong when one fails:
///  - every mesh has 3k indices, each below its vertex count; normals are absent or one per
///    vertex; its positions carry the spare Vec3 Embree reads (PaddedPositions);
///  - every material index is in range;
///  - a mesh or sphere has a light record exactly when its material emits, and that record
///    points back at it (Mesh lights at meshes with a full CDF, Sphere lights at spheres, Area
///    lights at the panel mesh that shows them);
///  - every Mesh or Sphere light is the record of such a primitive; an Environment light has
///    Scene::env.
void check_scene(const Scene& scene);

} // namespace candela
