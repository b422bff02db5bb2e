#pragma once
// SceneDesc (what the file says) -> Scene (what the renderer needs): flattening to world space,
// normals, luminaire rule and camera framing (spec §11).
#include "candela/scene/scene.h"
#include "candela/util/enum_table.h"
#include "candela/util/log.h"

#include <memory>

namespace candela {

struct SceneDesc; // candela/scene/scene_desc.h
class EnvMap;     // candela/scene/envmap.h

enum class CameraMode {
    Framed, ///< course placement rule (spec §3.1): orbit the scene bounds from the file camera
    File,   ///< the COLLADA camera node's pose, literally
};
/// --camera (util/enum_table.h).
inline constexpr EnumTable<CameraMode, 2> kCameraModes = {{
    {CameraMode::Framed, "framed", "CS184 placement around the scene bounds"},
    {CameraMode::File, "file", "the COLLADA pose"},
}};

struct BuildOptions {
    CameraMode camera_mode = CameraMode::Framed;
    /// -e: the lat-long environment map (io/envmap_file.h reads one); null = none.
    std::shared_ptr<const EnvMap> env_map;
};

/// Builds the immutable scene. Throws candela::Error with `file:line` context on bad data.
Scene build_scene(const SceneDesc& desc, const BuildOptions& opt, Diagnostics& diag);

} // namespace candela
