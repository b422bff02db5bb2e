#pragma once
// The immutable, flattened, world-space scene that accelerators and integrators read.
// Built once by scene/builder.h from a SceneDesc; passed around as `const Scene&`.
#include "candela/math/bbox.h"
#include "candela/scene/camera.h"
#include "candela/scene/light.h"
#include "candela/scene/material.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace candela {

class EnvMap; // candela/light/envmap.h

/// A triangle mesh in world space. Vertex `i` has position positions[i] and unit shading normal
/// normals[i]; triangle `j` is (indices[3j], indices[3j+1], indices[3j+2]), counter-clockwise
/// about its geometric normal. `positions` is followed in memory by at least one spare Vec3
/// (Embree reads 16 bytes at the last vertex), which the builder guarantees via reserve().
struct Mesh {
    std::string name;
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<std::uint32_t> indices;
    std::uint32_t material = 0;
    std::int32_t light = -1; ///< index into Scene::lights when the material is emissive

    std::size_t triangle_count() const { return indices.size() / 3; }
};

struct Sphere {
    Vec3 center;
    float radius = 1.f;
    std::uint32_t material = 0;
    std::int32_t light = -1;
};

/// What a scene holds, so that a render pays only for what is used (`candela info`).
struct SceneFeatures {
    std::uint32_t bsdf_mask = 0;  ///< bit k set when BsdfKind(k) is used by some primitive
    std::uint32_t light_mask = 0; ///< bit k set when LightKind(k) occurs in Scene::lights
    bool has(BsdfKind k) const { return bsdf_mask & (1u << static_cast<int>(k)); }
    bool has(LightKind k) const { return light_mask & (1u << static_cast<int>(k)); }
    bool any_delta_bsdf() const {
        return has(BsdfKind::Mirror) || has(BsdfKind::Glass) || has(BsdfKind::Refraction);
    }
};

class Scene {
public:
    std::string source; ///< the scene file it was built from
    std::vector<Mesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::shared_ptr<const EnvMap> env; ///< set when an Environment light exists
    Camera camera;
    Bounds3 bounds; ///< all meshes and spheres (lights excluded)
    SceneFeatures features;

    /// Geometry ids in hits: meshes are 0 .. meshes.size()-1; all spheres together form the one
    /// geometry sphere_geom_id(), with primitive id = index into `spheres`.
    std::uint32_t sphere_geom_id() const { return static_cast<std::uint32_t>(meshes.size()); }
    std::size_t triangle_count() const {
        std::size_t n = 0;
        for (const auto& m : meshes) n += m.triangle_count();
        return n;
    }
    /// Recomputes `bounds` and `features` from the contents (the builder calls it last).
    void finalize();
};

} // namespace candela
