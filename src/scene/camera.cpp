// The camera's batch kernel: pinhole ray directions for a batch of film positions.
#include "candela/scene/camera.h"
#include "candela/util/batch_kernel.h"

namespace candela {

// The loop is float arithmetic, a square root and a division per direction with no branches:
// GCC vectorises it, and target_clones adds an AVX2 version (eight directions per instruction)
// picked when the program loads. No FMA in either, so each direction is bit for bit the one
// pinhole_direction() returns.
CANDELA_BATCH_KERNEL void CameraProjection::pinhole_directions(std::size_t n, const float* fx,
                                                               const float* fy, float* dx,
                                                               float* dy, float* dz) const {
    // A local copy: the stores below cannot alias it, so its fields stay in registers.
    const CameraProjection camera = *this;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 d = camera.pinhole_direction(fx[i], fy[i]);
        dx[i] = d.x;
        dy[i] = d.y;
        dz[i] = d.z;
    }
}

} // namespace candela
