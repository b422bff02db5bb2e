// Rotations, look-at, the 3x3 determinant and the normal transform of the 4x4 scene-graph matrices.
#include "candela/math/mat4.h"

#include "candela/math/constants.h"

#include <cmath>

namespace candela {

Mat4 Mat4::rotate(const Vec3d& axis, double angle_deg) {
    Mat4 r;
    double len = length(axis);
    if (len == 0.0) return r;
    Vec3d a = axis / len;
    double th = deg_to_rad(angle_deg);
    double c = std::cos(th), s = std::sin(th), t = 1.0 - c;
    // Rodrigues' rotation formula in matrix form.
    r.m[0][0] = t * a.x * a.x + c;
    r.m[0][1] = t * a.x * a.y - s * a.z;
    r.m[0][2] = t * a.x * a.z + s * a.y;
    r.m[1][0] = t * a.x * a.y + s * a.z;
    r.m[1][1] = t * a.y * a.y + c;
    r.m[1][2] = t * a.y * a.z - s * a.x;
    r.m[2][0] = t * a.x * a.z - s * a.y;
    r.m[2][1] = t * a.y * a.z + s * a.x;
    r.m[2][2] = t * a.z * a.z + c;
    return r;
}

Mat4 Mat4::look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up) {
    Vec3d z = normalize(eye - target); // camera looks along -z
    Vec3d x = normalize(cross(up, z));
    Vec3d y = cross(z, x);
    Mat4 r;
    for (int i = 0; i < 3; ++i) {
        r.m[i][0] = x[i];
        r.m[i][1] = y[i];
        r.m[i][2] = z[i];
        r.m[i][3] = eye[i];
    }
    return r;
}

double Mat4::det3() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Vec3d Mat4::normal(const Vec3d& n) const {
    // Inverse transpose of the 3x3 block = cofactor matrix / det; the 1/det scale does not
    // matter for a direction except for its sign, which keeps orientation under mirroring.
    double c[3][3];
    c[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    c[0][1] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    c[0][2] = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    c[1][0] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
    c[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    c[1][2] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    c[2][0] = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    c[2][1] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    c[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    double d = det3();
    double sgn = d < 0 ? -1.0 : 1.0;
    return Vec3d(c[0][0] * n.x + c[0][1] * n.y + c[0][2] * n.z,
                 c[1][0] * n.x + c[1][1] * n.y + c[1][2] * n.z,
                 c[2][0] * n.x + c[2][1] * n.y + c[2][2] * n.z) *
           sgn;
}

bool Mat4::is_finite() const {
    for (const auto& row : m)
        for (double v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

} // namespace candela
