#pragma once
// Cameras the tests share.
#include "candela/math/mat4.h"
#include "candela/scene/camera.h"
#include "candela/scene/scene_desc.h"

namespace candela::test {

/// A pinhole camera at (1, 2, 3) looking along -x (right = -z, up = +y), 60 degrees wide, clip
/// planes 0.1 and 50: an orientation no axis-aligned convention gets right by accident.
inline Camera sideways_camera() {
    Camera cam;
    cam.pos = Vec3(1.f, 2.f, 3.f);
    cam.x = Vec3(0.f, 0.f, -1.f); // right
    cam.y = Vec3(0.f, 1.f, 0.f);  // up
    cam.z = Vec3(1.f, 0.f, 0.f);  // back toward the viewer: it looks along -x
    cam.hfov_deg = 60.f;
    cam.znear = 0.1f;
    cam.zfar = 50.f;
    return cam;
}

/// Adds to a scene description a camera named "camera" with horizontal field of view `xfov`
/// degrees and the default clip planes, and its instance at `world`.
inline void add_desc_camera(SceneDesc& d, float xfov, const Mat4& world) {
    DescCamera cam;
    cam.name = "camera";
    cam.xfov = xfov;
    d.cameras.push_back(cam);
    DescInstance ci;
    ci.kind = DescInstanceKind::Camera;
    ci.index = int(d.cameras.size()) - 1;
    ci.node_name = "camera";
    ci.world = world;
    d.instances.push_back(ci);
}

} // namespace candela::test
