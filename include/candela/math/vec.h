#pragma once
// Small fixed-size vectors. Vec3 (float) is the renderer's working type; Vec3d (double) is used
// by the loader's transform stack and by the double-precision reference intersector.
#include "candela/math/constants.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace candela {

template <typename T> struct Vec2T {
    T x{}, y{};
    constexpr Vec2T() = default;
    constexpr Vec2T(T x_, T y_) : x(x_), y(y_) {}
    constexpr T operator[](int i) const { return i == 0 ? x : y; }
    constexpr Vec2T operator+(Vec2T b) const { return {x + b.x, y + b.y}; }
    constexpr Vec2T operator-(Vec2T b) const { return {x - b.x, y - b.y}; }
    constexpr Vec2T operator*(T s) const { return {x * s, y * s}; }
};

template <typename T> struct Vec3T {
    T x{}, y{}, z{};
    constexpr Vec3T() = default;
    constexpr explicit Vec3T(T s) : x(s), y(s), z(s) {}
    constexpr Vec3T(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <typename U>
    constexpr explicit Vec3T(const Vec3T<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}

    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    constexpr Vec3T operator+(const Vec3T& b) const { return {x + b.x, y + b.y, z + b.z}; }
    constexpr Vec3T operator-(const Vec3T& b) const { return {x - b.x, y - b.y, z - b.z}; }
    constexpr Vec3T operator*(const Vec3T& b) const { return {x * b.x, y * b.y, z * b.z}; }
    constexpr Vec3T operator/(const Vec3T& b) const { return {x / b.x, y / b.y, z / b.z}; }
    constexpr Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3T operator-() const { return {-x, -y, -z}; }
    constexpr Vec3T& operator+=(const Vec3T& b) {
        x += b.x;
        y += b.y;
        z += b.z;
        return *this;
    }
    constexpr Vec3T& operator-=(const Vec3T& b) {
        x -= b.x;
        y -= b.y;
        z -= b.z;
        return *this;
    }
    constexpr Vec3T& operator*=(const Vec3T& b) {
        x *= b.x;
        y *= b.y;
        z *= b.z;
        return *this;
    }
    constexpr Vec3T& operator*=(T s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    constexpr Vec3T& operator/=(T s) {
        x /= s;
        y /= s;
        z /= s;
        return *this;
    }
    constexpr bool operator==(const Vec3T& b) const { return x == b.x && y == b.y && z == b.z; }
    constexpr bool operator!=(const Vec3T& b) const { return !(*this == b); }
};

template <typename T> constexpr Vec3T<T> operator*(T s, const Vec3T<T>& v) {
    return v * s;
}
template <typename T> constexpr T dot(const Vec3T<T>& a, const Vec3T<T>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T> constexpr Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> inline T length_squared(const Vec3T<T>& v) {
    return dot(v, v);
}
template <typename T> inline T length(const Vec3T<T>& v) {
    return std::sqrt(dot(v, v));
}
/// Unit vector along v. The caller guarantees v is non-zero (a zero v yields NaNs). One division
/// and three products: each component is rounded twice (relative error <= 2 ulp + sqrt's half).
template <typename T> inline Vec3T<T> normalize(const Vec3T<T>& v) {
    return v * (T(1) / length(v));
}
template <typename T> inline Vec3T<T> vmin(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <typename T> inline Vec3T<T> vmax(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
template <typename T> inline Vec3T<T> vabs(const Vec3T<T>& a) {
    return {std::abs(a.x), std::abs(a.y), std::abs(a.z)};
}
/// c ? a : b, component by component: three scalar selects, which a compiler turns into
/// branch-free code (a select of whole vectors stays a branch and stops vectorisation).
template <typename T> inline Vec3T<T> vselect(bool c, const Vec3T<T>& a, const Vec3T<T>& b) {
    return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z};
}
template <typename T> inline T max_component(const Vec3T<T>& a) {
    return std::max(a.x, std::max(a.y, a.z));
}
template <typename T> inline int max_dimension(const Vec3T<T>& a) {
    return a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
}
template <typename T> inline bool is_finite(const Vec3T<T>& a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

using Vec2 = Vec2T<float>;
using Vec3 = Vec3T<float>;
using Vec3d = Vec3T<double>;

/// Linear RGB radiance, reflectance or throughput. Same arithmetic as a vector; a separate name
/// keeps signatures readable.
using Rgb = Vec3;

/// Relative luminance of linear Rec.709 RGB (spec §6.5).
inline float luminance(const Rgb& c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
inline bool is_black(const Rgb& c) {
    return c.x == 0.f && c.y == 0.f && c.z == 0.f;
}

} // namespace candela
