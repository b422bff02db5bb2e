#pragma once
// SceneDesc: what a scene file says, in the file's local spaces, with every node flattened to a
// world matrix. The COLLADA reader (io/collada.h) produces it; the scene builder
// (scene/builder.h) turns it into a Scene. It holds no rendering logic.
#include "candela/math/mat4.h"
#include "candela/math/vec.h"
#include "candela/scene/material.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// A `<material>` resolved through its `<effect>` (spec §1.8).
struct DescMaterial {
    Material material; ///< material.name is the `<material>` name (or id)
    int line = 0;      ///< line of the `<material>` element
};

/// One primitive group (`<triangles>`, `<polylist>` or `<polygons>`) after fan triangulation.
struct DescPrimGroup {
    std::string material_symbol; ///< the group's `material` attribute; empty when absent
    int line = 0;
    /// Three position indices per triangle, counter-clockwise as written in the file.
    std::vector<std::uint32_t> position_index;
    /// Three indices into DescGeometry::normals per triangle, or empty without normals.
    std::vector<std::uint32_t> normal_index;

    std::size_t triangle_count() const { return position_index.size() / 3; }
};

enum class DescGeometryKind : std::uint8_t { Mesh, Sphere };

/// A `<geometry>`: a mesh in its local space, or a CGL sphere (spec §1.6).
struct DescGeometry {
    DescGeometryKind kind = DescGeometryKind::Mesh;
    std::string name; ///< name attribute, else id
    int line = 0;
    std::vector<Vec3> positions;       ///< Mesh: local positions
    std::vector<Vec3> normals;         ///< Mesh: local normals the groups index (may be empty)
    std::vector<DescPrimGroup> groups; ///< Mesh: every primitive group, in document order
    std::size_t fanned_polygons = 0;   ///< Mesh: polygons of more than 3 vertices (fanned)
    float radius = 0.f;                ///< Sphere: local radius (> 0)

    std::size_t triangle_count() const {
        std::size_t n = 0;
        for (const auto& g : groups)
            n += g.triangle_count();
        return n;
    }
};

enum class DescLightKind : std::uint8_t { Ambient, Directional, Point, Spot, Area };

/// A `<light>` (spec §1.5): the CGL technique when present, else technique_common.
struct DescLight {
    DescLightKind kind = DescLightKind::Point;
    std::string name; ///< name attribute, else id
    int line = 0;
    Rgb color{1.f};
    float falloff_angle_deg = 180.f; ///< Spot: full cone angle (COLLADA default 180)
    float falloff_exponent = 0.f;    ///< Spot: COLLADA default 0
    bool has_attenuation = false;    ///< Point/Spot: attenuation coefficients were given
};

/// A perspective `<camera>` (spec §1.4). Angles in degrees.
struct DescCamera {
    std::string name;
    int line = 0;
    std::optional<float> xfov, yfov, aspect_ratio;
    float znear = 0.001f;
    float zfar = 1000.f;

    /// Horizontal field of view in degrees: xfov, else 2·atan(tan(yfov/2)·aspect), else 50.
    float hfov_deg() const;
    /// The horizontal field of view in degrees the course shows in a window of `aspect` (W/H)
    /// (spec §1.4, §3.2 configure): hFov = xfov or 50, vFov = yfov or 2·atan(tan(hFov/2) /
    /// aspect_ratio), and the narrower of the two is widened to the window's aspect.
    float course_hfov_deg(double aspect) const;
};

enum class DescInstanceKind : std::uint8_t { Geometry, Light, Camera };

/// One `instance_geometry`, `instance_light` or `instance_camera` of a node, flattened.
struct DescInstance {
    DescInstanceKind kind = DescInstanceKind::Geometry;
    int index = 0; ///< into SceneDesc::geometries, lights or cameras by kind
    Mat4 world;    ///< W = U·P·L (up-axis matrix, parents, local transforms)
    /// Geometry: the first bound material (index into SceneDesc::materials) or -1 for none.
    int material = -1;
    /// Geometry meshes: per primitive group, the material bound to the group's symbol, or
    /// `material` when the symbol is not bound (same size as the geometry's groups).
    std::vector<int> group_materials;
    std::string node_name; ///< the enclosing `<node>`'s name, else id
    int line = 0;          ///< line of the instance element
};

/// Everything the file says, in the file's terms.
struct SceneDesc {
    std::string source; ///< the display name used in messages (normally the path)
    Mat4 up;            ///< U of spec §1.2
    std::vector<DescMaterial> materials;
    std::vector<DescGeometry> geometries;
    std::vector<DescLight> lights;
    std::vector<DescCamera> cameras;
    std::vector<DescInstance> instances; ///< in document (pre-)order of the nodes
    bool up_axis_given = true;           ///< false: no <asset>/<up_axis> (Y_UP assumed)
    std::size_t short_matrices = 0;      ///< <matrix> elements of 12-15 numbers (completed)
    /// <translate>, <rotate>, <scale> and <lookat> elements (the course reads <matrix> only).
    std::size_t composed_transforms = 0;
    std::size_t nested_nodes = 0; ///< <node> elements inside another <node>
};

namespace loader_limits {
/// Most triangles in a scene, counted after fan triangulation and after instancing (every
/// instance of a mesh counts its triangles again); the reader and the builder both reject a
/// scene beyond it before allocating anything proportional to it. 2^28 triangles already need
/// > 10 GiB of world-space vertices and indices.
constexpr std::uint64_t kMaxTriangles = std::uint64_t(1) << 28;
} // namespace loader_limits

} // namespace candela
