#pragma once
// 4x4 double matrices for the scene graph (column vectors, M * v). Doubles keep the
// composition of deep node hierarchies exact enough before positions are rounded to float.
#include "candela/math/vec.h"

namespace candela {

struct Mat4 {
    double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};

    static Mat4 zero() {
        Mat4 r;
        for (auto& row : r.m)
            for (double& v : row)
                v = 0.0;
        return r;
    }
    /// From 16 numbers in row-major order (COLLADA `<matrix>`).
    static Mat4 from_row_major(const double* v) {
        Mat4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                r.m[i][j] = v[4 * i + j];
        return r;
    }
    static Mat4 translate(const Vec3d& t) {
        Mat4 r;
        r.m[0][3] = t.x;
        r.m[1][3] = t.y;
        r.m[2][3] = t.z;
        return r;
    }
    static Mat4 scale(const Vec3d& s) {
        Mat4 r;
        r.m[0][0] = s.x;
        r.m[1][1] = s.y;
        r.m[2][2] = s.z;
        return r;
    }
    /// Rotation by angle_deg degrees about axis (right-handed, counter-clockwise looking down
    /// the axis), as COLLADA `<rotate>` defines it.
    static Mat4 rotate(const Vec3d& axis, double angle_deg);
    /// Camera-style look-at (COLLADA `<lookat>`): local -Z looks from eye toward target, +Y up.
    static Mat4 look_at(const Vec3d& eye, const Vec3d& target, const Vec3d& up);

    Mat4 operator*(const Mat4& b) const {
        Mat4 r = zero();
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                for (int k = 0; k < 4; ++k)
                    r.m[i][j] += m[i][k] * b.m[k][j];
        return r;
    }
    /// Transforms a point and divides by w (spec `proj`).
    Vec3d point(const Vec3d& p) const {
        double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
        double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
        double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
        double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
        return w == 1.0 ? Vec3d(x, y, z) : Vec3d(x / w, y / w, z / w);
    }
    /// Transforms a direction (w = 0): no translation.
    Vec3d vector(const Vec3d& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    /// Transforms a normal with the inverse transpose of the linear part.
    Vec3d normal(const Vec3d& n) const;
    /// Determinant of the upper-left 3x3 block (negative for mirroring transforms).
    double det3() const;
    Vec3d column(int j) const { return {m[0][j], m[1][j], m[2][j]}; }
    bool is_finite() const;
};

} // namespace candela
