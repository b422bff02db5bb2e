#pragma once
// 3x3 matrices (column vectors, M * v) for the linear part of ellipsoid transforms: float for
// the renderer, double for the builder and the double-precision reference intersector.
#include "candela/math/vec.h"

#include <cmath>

namespace candela {

template <typename T> struct Mat3T {
    T m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    constexpr Mat3T() = default;
    template <typename U> constexpr explicit Mat3T(const Mat3T<U>& o) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                m[i][j] = T(o.m[i][j]);
    }
    /// From three columns.
    static Mat3T from_columns(const Vec3T<T>& c0, const Vec3T<T>& c1, const Vec3T<T>& c2) {
        Mat3T r;
        for (int i = 0; i < 3; ++i) {
            r.m[i][0] = c0[i];
            r.m[i][1] = c1[i];
            r.m[i][2] = c2[i];
        }
        return r;
    }

    Vec3T<T> row(int i) const { return {m[i][0], m[i][1], m[i][2]}; }
    Vec3T<T> column(int j) const { return {m[0][j], m[1][j], m[2][j]}; }

    /// M * v, each component a three-term dot product of a row with v.
    Vec3T<T> operator*(const Vec3T<T>& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    /// M^T * v (for normals: the inverse transpose of M^-1 is M^T).
    Vec3T<T> transpose_mul(const Vec3T<T>& v) const {
        return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
                m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
                m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
    }
    Mat3T operator*(const Mat3T& b) const {
        Mat3T r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.m[i][j] = m[i][0] * b.m[0][j] + m[i][1] * b.m[1][j] + m[i][2] * b.m[2][j];
        return r;
    }
    /// The matrix of absolute values |M|, for rounding-error bounds.
    Mat3T abs() const {
        Mat3T r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.m[i][j] = std::abs(m[i][j]);
        return r;
    }
    T det() const {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
    /// Inverse by the adjugate; the caller checks det() != 0.
    Mat3T inverse() const {
        const T inv_det = T(1) / det();
        Mat3T r;
        r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv_det;
        r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv_det;
        r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv_det;
        r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv_det;
        r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv_det;
        r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv_det;
        r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv_det;
        r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv_det;
        r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv_det;
        return r;
    }
    /// Largest absolute row sum (the infinity norm).
    T norm_inf() const {
        T n = 0;
        for (int i = 0; i < 3; ++i)
            n = std::max(n, std::abs(m[i][0]) + std::abs(m[i][1]) + std::abs(m[i][2]));
        return n;
    }
    bool is_finite() const {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (!std::isfinite(m[i][j])) return false;
        return true;
    }
};

using Mat3 = Mat3T<float>;
using Mat3d = Mat3T<double>;

} // namespace candela
