#pragma once
// A scene named on the command line: a COLLADA file, or `--procedural SPEC` for scaling runs.
#include "candela/accel/accel.h"
#include "candela/app/cli.h"
#include "candela/io/camera_file.h"
#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/scene/builder.h"
#include "candela/scene/procedural.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <string>
#include <vector>

namespace candela::app {

/// A scene file loaded with `build` and the environment map `env_map` (none when empty), its
/// warnings printed (errors with `strict`).
inline Scene load_scene_with_env(const std::string& path, BuildOptions build,
                                 const std::string& env_map, bool strict) {
    if (!env_map.empty()) build.env_map = load_envmap(env_map);
    Diagnostics diag(strict);
    Scene scene = load_scene(path, build, diag);
    diag.flush();
    return scene;
}

inline Scene load_scene_or_procedural(const std::string& path, const std::string& procedural,
                                      bool strict) {
    if (!procedural.empty()) {
        if (!path.empty())
            throw Error(ErrorKind::Usage, "give either a scene file or --procedural");
        return make_procedural_scene(procedural);
    }
    if (path.empty()) throw Error(ErrorKind::Usage, "a scene file is required");
    check_scene_file(path);
    return load_scene_with_env(path, BuildOptions{}, "", strict);
}

/// How a scene file is viewed and lit beyond the file itself: an environment map (-e), the
/// camera of the COLLADA pose or the CS184 framing (--camera), a CS184 camera file (-c). The
/// render command's options, for the commands that measure renders of the same scenes.
struct SceneView {
    std::string env_map, camera_file;
    CameraMode camera_mode = CameraMode::Framed;
    bool empty() const {
        return env_map.empty() && camera_file.empty() && camera_mode == CameraMode::Framed;
    }
};

/// load_scene_or_procedural() with `view` applied as the render command applies it; a
/// procedural scene takes no view (Error(Usage) when one is given).
inline Scene load_scene_with_view(const std::string& path, const std::string& procedural,
                                  bool strict, const SceneView& view) {
    if (view.empty()) return load_scene_or_procedural(path, procedural, strict);
    if (!procedural.empty())
        throw Error(ErrorKind::Usage, "-e, --camera and -c apply to a scene file, not to "
                                      "--procedural");
    if (path.empty()) throw Error(ErrorKind::Usage, "a scene file is required");
    check_scene_file(path);
    BuildOptions build;
    build.camera_mode = view.camera_mode;
    Scene scene = load_scene_with_env(path, build, view.env_map, strict);
    if (!view.camera_file.empty()) apply_camera_file(read_camera_file(view.camera_file), scene);
    return scene;
}

/// The scene of a render's settings: its file with the environment map (-e), the camera file
/// (-c, the one check_render_files read when it did), the lens options (-b, -d), the view
/// overrides (--look-from, --look-at, --fov) and the framing (--framing) applied.
inline Scene load_render_scene(const RenderArgs& args) {
    Scene scene = load_scene_with_env(args.scene, args.build, args.env_map, args.strict);
    if (!args.camera_file.empty())
        apply_camera_file(args.camera ? *args.camera : read_camera_file(args.camera_file), scene);
    if (args.lens_radius) scene.camera.lens_radius = *args.lens_radius;
    if (args.focal_distance) scene.camera.focal_distance = *args.focal_distance;
    apply_camera_overrides(scene.camera, args.camera_overrides);
    if (args.camera_file.empty())
        frame_camera(scene.camera, args.build.framing, args.settings.width);
    return scene;
}

/// Parses --triangle by kTriangleTests.
inline TriangleTest parse_triangle_test(const std::string& name) {
    return parse_enum(kTriangleTests, "--triangle", name);
}

/// Parses a comma-separated backend list ("embree,builtin,brute").
inline std::vector<AccelKind> parse_accel_list(const std::string& list) {
    std::vector<AccelKind> out;
    for (const std::string& item : split_string(list, ','))
        if (!item.empty()) out.push_back(parse_accel_kind(item));
    if (out.empty()) throw Error(ErrorKind::Usage, "--accel: no backend given");
    return out;
}

} // namespace candela::app
