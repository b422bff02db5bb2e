#pragma once
// `candela info`: a summary of what a scene contains and which render features it needs.
#include "candela/scene/scene.h"

#include <string>
#include <vector>

namespace candela {

/// Returns a human-readable report (json = false) or one JSON object (json = true) with:
/// triangle, sphere and mesh counts; the materials in use by BSDF kind; lights by kind; the
/// scene bounds; the render camera (position, target, horizontal and vertical FOV in degrees
/// for a 4:3 image); and the features a render of this scene skips.
std::string describe_scene(const Scene& scene, bool json);

/// What a render of this scene leaves out because the scene does not use it, one short phrase
/// each (also listed by describe_scene).
std::vector<std::string> skipped_features(const Scene& scene);

} // namespace candela
