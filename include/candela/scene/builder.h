#pragma once
// SceneDesc (what the file says) -> Scene (what the renderer needs): flattening to world space,
// normals, luminaire rule and camera framing (spec §11).
#include "candela/scene/scene.h"
#include "candela/util/enum_table.h"
#include "candela/util/log.h"

#include <memory>
#include <optional>

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

/// How the camera's horizontal field of view meets the image size (--framing).
enum class Framing {
    Candela, ///< spec §11.2: the field of view spans the image width at every resolution
    Cs184,   ///< spec §3.2: the 800x600 window's pixel pitch at every resolution
};
/// --framing (util/enum_table.h).
inline constexpr EnumTable<Framing, 2> kFramings = {{
    {Framing::Candela, "candela", "the field of view spans the image at every -r"},
    {Framing::Cs184, "cs184",
     "the course's: every -r is a centre crop, or extension, of the 800x600 view"},
}};
/// The course's batch window (spec §3.2), whose pixel pitch the cs184 framing keeps.
constexpr int kCs184WindowWidth = 800;
constexpr int kCs184WindowHeight = 600;

struct BuildOptions {
    CameraMode camera_mode = CameraMode::Framed;
    /// Framing::Cs184 takes the file camera's horizontal field of view as the course's 800x600
    /// window shows it (DescCamera::course_hfov_deg); frame_camera() then fits it to -r.
    Framing framing = Framing::Candela;
    /// -e: the lat-long environment map (io/envmap_file.h reads one); null = none.
    std::shared_ptr<const EnvMap> env_map;
};

/// Builds the immutable scene. Throws candela::Error with `file:line` context on bad data.
Scene build_scene(const SceneDesc& desc, const BuildOptions& opt, Diagnostics& diag);

/// Explicit look-from / look-at / field-of-view overrides of the scene's camera (spec §11.1:
/// they override the framed and the file camera alike). Up is world +Y.
struct CameraOverrides {
    std::optional<Vec3> from, at;  ///< --look-from, --look-at; unset keeps the camera's
    std::optional<float> hfov_deg; ///< --fov: horizontal, in degrees; unset keeps the camera's
    bool empty() const { return !from && !at && !hfov_deg; }
};
/// Applies `o` to `camera`: the eye at `from`, looking at `at`, with zero roll about world +Y
/// (either one unset keeps the camera's position or its target). Throws Error(Usage) naming
/// the flags when the eye is at the target or looks straight up or down (no roll is defined),
/// or when the field of view is not in (0, 180) degrees.
void apply_camera_overrides(Camera& camera, const CameraOverrides& o);

/// Fits the camera's horizontal field of view to an image `width` pixels wide by `framing`:
/// under Framing::Candela it spans the width unchanged; under Framing::Cs184 it is taken as the
/// 800-pixel-wide window's and the pixel pitch is kept (spec §3.2: hFov = 2 atan(W / (2
/// screenDist))), so a W x H image is the centre crop, or extension, of the 800x600 view (the
/// vertical field of view follows the image's aspect ratio either way, camera.h).
void frame_camera(Camera& camera, Framing framing, int width);

} // namespace candela
