#pragma once
// SceneDesc (what the file says) -> Scene (what the renderer needs): flattening to world space,
// normals, luminaire rule and camera framing (spec §11).
#include "candela/scene/scene.h"
#include "candela/util/log.h"

#include <string>

namespace candela {

struct SceneDesc; // candela/io/collada.h

enum class CameraMode {
    Framed, ///< course placement rule (spec §3.1): orbit the scene bounds from the file camera
    File,   ///< the COLLADA camera node's pose, literally
};

struct BuildOptions {
    CameraMode camera_mode = CameraMode::Framed;
    std::string env_map;    ///< -e: lat-long EXR environment map; empty = none
};

/// Builds the immutable scene. Throws candela::Error with `file:line` context on bad data.
Scene build_scene(const SceneDesc& desc, const BuildOptions& opt, Diagnostics& diag);

/// load_collada() then build_scene(): the one call the commands use.
Scene load_scene(const std::string& path, const BuildOptions& opt, Diagnostics& diag);

} // namespace candela
