#pragma once
// COLLADA (.dae) reader for the CS184 dialect (spec §1, with candela's decisions of §11).
//
// The reader produces a SceneDesc: a plain description of what the file says, in the file's
// local spaces, with every node flattened to a world matrix. It holds no rendering logic; the
// scene builder (scene/builder.h) turns it into a Scene.
#include "candela/math/mat4.h"
#include "candela/math/vec.h"
#include "candela/scene/material.h"
#include "candela/util/log.h"

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
};

/// Resource limits of the reader and the builder. Inputs beyond them are rejected with a
/// `file:line: error:` message before anything proportional to the claimed size is allocated, so
/// a hostile file fails fast instead of exhausting memory.
namespace loader_limits {
/// Largest scene file load_collada() reads (and largest text parse_collada() accepts). The
/// largest course scene is ~2 MiB; 512 MiB leaves room for big exports yet keeps the parsed DOM
/// (several times the text) well inside a workstation's memory.
constexpr std::uint64_t kMaxFileBytes = std::uint64_t(512) << 20;
/// Deepest nesting of elements with content (the document element is level 1); a
/// self-closing element may sit one level deeper. This is tinyxml2 9's own limit (it counts
/// the document node too and stops at TINYXML2_MAX_ELEMENT_DEPTH = 100); the reader reports it
/// as a nesting error, and its recursive <node> walk is bounded by it.
constexpr int kMaxXmlDepth = 98;
/// Most triangles in a scene, counted after fan triangulation and after instancing (every
/// instance of a mesh counts its triangles again). 2^28 triangles already need > 10 GiB of
/// world-space vertices and indices.
constexpr std::uint64_t kMaxTriangles = std::uint64_t(1) << 28;
/// Largest accessor stride (floats per vector). Real files interleave a handful of components.
constexpr std::uint32_t kMaxAccessorStride = 1024;
/// Largest `offset` of a primitive group's `<input>`; the index stride is the largest offset + 1.
/// Real files use one offset per input (at most a handful).
constexpr std::uint32_t kMaxInputOffset = 1023;
} // namespace loader_limits

/// Reads and parses the file at `path`. Throws Error(Io) when it cannot be read or is larger
/// than loader_limits::kMaxFileBytes (checked before reading), and Error(Scene) with a
/// `path:line: error: ...` message when its content is invalid.
SceneDesc load_collada(const std::string& path, Diagnostics& diag);

/// Parses COLLADA text; `display_name` prefixes every message. Throws Error(Scene), also when
/// the text breaks a loader_limits bound.
SceneDesc parse_collada(const std::string& xml_text, const std::string& display_name,
                        Diagnostics& diag);

} // namespace candela
