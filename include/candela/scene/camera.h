#pragma once
#include "candela/math/vec.h"

namespace candela {

/// The render camera in world space. It looks along -z (the third basis vector points back
/// toward the viewer), x is right, y is up. The horizontal field of view spans the image width at
/// every resolution; the vertical one follows the image aspect ratio (spec §11.2).
struct Camera {
    Vec3 pos{0.f, 0.f, 0.f};
    Vec3 x{1.f, 0.f, 0.f}, y{0.f, 1.f, 0.f}, z{0.f, 0.f, 1.f};
    float hfov_deg = 50.f;
    float znear = 0.001f;       ///< camera rays start here (distance along the unit direction)
    float zfar = 1000.f;        ///< and end here
    float lens_radius = 0.f;    ///< thin lens; 0 = pinhole
    float focal_distance = 4.7f;
    Vec3 target{0.f, 0.f, 0.f}; ///< the point the camera was aimed at (reported by `info`)
};

} // namespace candela
