#pragma once
// Where candela's images differ from the CS184 reference's by design: the rows of the table in
// docs/cs184-differences.md, held here (tests/scene/cs184_differences_test.cpp checks the two
// are the same), and which of them apply to one scene (`candela info --vs-cs184`).
#include "candela/scene/scene.h"
#include "candela/scene/scene_desc.h"

#include <string>
#include <vector>

namespace candela {

/// What in a scene makes a row apply.
enum class Cs184Trigger {
    Always,            ///< every scene (the renderer's own rules)
    AreaLights,        ///< CGL <area> lights
    EmissiveShapes,    ///< emissive meshes or spheres
    PointLights,       ///< point lights
    SpotLights,        ///< spot lights
    DirectionalLights, ///< directional lights
    AmbientLight,      ///< an ambient light
    Glass,             ///< glass or refraction materials
    RoughDielectric,   ///< glass or refraction with a roughness candela uses
    Ellipsoids,        ///< spheres under a non-uniform scale
    DeltaLights,       ///< point, spot or directional lights (the row concerns -H)
    Microfacet,        ///< microfacet conductors
    Meshes,            ///< triangle meshes
    Transforms,        ///< <translate>, <rotate>, <scale>, <lookat> or nested nodes
    Polygons,          ///< polygons of more than three vertices
    PrimitiveGroups,   ///< a mesh with several primitive groups
    MissingUpAxis,     ///< no <asset>/<up_axis>
    ShortMatrix        ///< a <matrix> of 12 to 15 numbers
};

/// One row of the table: its three cells as the document writes them (Markdown), and what in
/// a scene makes it apply.
struct Cs184Difference {
    const char* topic;
    const char* cs184;
    const char* candela;
    Cs184Trigger trigger;
};

/// The rows of docs/cs184-differences.md, in its order.
const std::vector<Cs184Difference>& cs184_differences();

/// A row that applies to a scene and what in the scene makes it apply.
struct AppliedDifference {
    const Cs184Difference* row;
    std::string why;
};

/// The rows that apply to the scene `desc` describes and `scene` was built from, in the table's
/// order.
std::vector<AppliedDifference> cs184_differences_for(const SceneDesc& desc, const Scene& scene);

} // namespace candela
