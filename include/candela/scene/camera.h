#pragma once
#include "candela/math/constants.h"
#include "candela/math/ray.h"
#include "candela/math/vec.h"
#include "candela/sampling/warp.h"

#include <cmath>
#include <cstddef>

namespace candela {

/// The render camera in world space. It looks along -z (the third basis vector points back
/// toward the viewer), x is right, y is up. The horizontal field of view spans the image width at
/// every resolution; the vertical one follows the image aspect ratio (spec §11.2).
struct Camera {
    Vec3 pos{0.f, 0.f, 0.f};
    Vec3 x{1.f, 0.f, 0.f}, y{0.f, 1.f, 0.f}, z{0.f, 0.f, 1.f};
    float hfov_deg = 50.f;
    float znear = 0.001f;    ///< camera rays start here (distance along the unit direction)
    float zfar = 1000.f;     ///< and end here
    float lens_radius = 0.f; ///< thin lens; 0 = pinhole
    float focal_distance = 4.7f;
    Vec3 target{0.f, 0.f, 0.f}; ///< the point the camera was aimed at (reported by `info`)
};

/// Camera rays of a width x height film. Film position (fx, fy) is in pixels: (0, 0) is the
/// top-left corner of the image, (width, height) the bottom-right one, so row 0 is the top row
/// and pixel (px, py) has its centre at (px + 0.5, py + 0.5).
class CameraProjection {
  public:
    CameraProjection() = default;
    CameraProjection(const Camera& camera, int width, int height)
        : cam_(camera), film_to_ndc_x_(2.f / float(width)), film_to_ndc_y_(2.f / float(height)) {
        tan_half_h_ = std::tan(deg_to_rad(0.5f * camera.hfov_deg));
        tan_half_v_ = tan_half_h_ * float(height) / float(width);
    }

    const Camera& camera() const { return cam_; }

    /// The ray through film position (fx, fy). u_lens picks the point on a thin lens (concentric
    /// disk mapping; (0.5, 0.5) is the lens centre); a pinhole camera ignores it. The ray spans
    /// [znear, zfar] along its unit direction.
    Ray ray(float fx, float fy, Vec2 u_lens) const {
        if (cam_.lens_radius <= 0.f) return pinhole_ray(pinhole_direction(fx, fy));
        const Vec2 d = square_to_uniform_disk_concentric(u_lens);
        const Vec3 p_lens(cam_.lens_radius * d.x, cam_.lens_radius * d.y, 0.f);
        const Vec3 p_focus = film_point(fx, fy) * cam_.focal_distance;
        const Vec3 dir = p_focus - p_lens;
        Ray r;
        r.o = cam_.pos + cam_.x * p_lens.x + cam_.y * p_lens.y;
        r.d = normalize(cam_.x * dir.x + cam_.y * dir.y + cam_.z * dir.z);
        r.tmin = cam_.znear;
        r.tmax = cam_.zfar;
        return r;
    }

    /// A pinhole camera's unit ray direction through film position (fx, fy).
    Vec3 pinhole_direction(float fx, float fy) const {
        const Vec3 s = film_point(fx, fy);
        return normalize(cam_.x * s.x + cam_.y * s.y + cam_.z * s.z);
    }
    /// pinhole_direction() of film positions (fx[i], fy[i]), i < n, into coordinate arrays: the
    /// same arithmetic, vectorised over a batch (camera.cpp).
    void pinhole_directions(std::size_t n, const float* fx, const float* fy, float* dx, float* dy,
                            float* dz) const;
    /// The pinhole camera's ray along unit direction d.
    Ray pinhole_ray(const Vec3& d) const {
        Ray r;
        r.o = cam_.pos;
        r.d = d;
        r.tmin = cam_.znear;
        r.tmax = cam_.zfar;
        return r;
    }

  private:
    /// Film position (fx, fy) on the plane at distance 1 in front of the camera, in camera
    /// space: x right, y up, looking down -z.
    Vec3 film_point(float fx, float fy) const {
        return {(fx * film_to_ndc_x_ - 1.f) * tan_half_h_,
                (1.f - fy * film_to_ndc_y_) * tan_half_v_, -1.f};
    }

    Camera cam_;
    float tan_half_h_ = 1.f, tan_half_v_ = 1.f;
    float film_to_ndc_x_ = 1.f, film_to_ndc_y_ = 1.f;
};

} // namespace candela
