#pragma once
// A scene named on the command line: a COLLADA file, or `--procedural SPEC` for scaling runs.
#include "candela/accel/accel.h"
#include "candela/app/cli.h"
#include "candela/io/collada.h"
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
