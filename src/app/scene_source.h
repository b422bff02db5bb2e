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

inline Scene load_scene_or_procedural(const std::string& path, const std::string& procedural,
                                      bool strict) {
    if (!procedural.empty()) {
        if (!path.empty())
            throw Error(ErrorKind::Usage, "give either a scene file or --procedural");
        return make_procedural_scene(procedural);
    }
    if (path.empty()) throw Error(ErrorKind::Usage, "a scene file is required");
    check_scene_file(path);
    Diagnostics diag(strict);
    Scene scene = load_scene(path, BuildOptions{}, diag);
    diag.flush();
    return scene;
}

/// The scene of a render's settings: its file with the environment map (-e), the camera file
/// (-c, the one check_render_files read when it did) and the lens options (-b, -d) applied.
inline Scene load_render_scene(const RenderArgs& args) {
    Diagnostics diag(args.strict);
    BuildOptions build = args.build;
    if (!args.env_map.empty()) build.env_map = load_envmap(args.env_map);
    Scene scene = load_scene(args.scene, build, diag);
    diag.flush();
    if (!args.camera_file.empty())
        apply_camera_file(args.camera ? *args.camera : read_camera_file(args.camera_file), scene);
    if (args.lens_radius) scene.camera.lens_radius = *args.lens_radius;
    if (args.focal_distance) scene.camera.focal_distance = *args.focal_distance;
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
