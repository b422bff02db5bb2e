#pragma once
#include "candela/math/vec.h"
#include <limits>

namespace candela {

/// Axis-aligned box. The default box is empty (lo = +inf, hi = -inf), so growing it by a point
/// gives that point's box.
struct Bounds3 {
    Vec3 lo{std::numeric_limits<float>::infinity()};
    Vec3 hi{-std::numeric_limits<float>::infinity()};

    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    void grow(const Vec3& p) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
    void grow(const Bounds3& b) {
        lo = vmin(lo, b.lo);
        hi = vmax(hi, b.hi);
    }
    Vec3 extent() const { return empty() ? Vec3(0.f) : hi - lo; }
    Vec3 center() const { return (lo + hi) * 0.5f; }
    bool contains(const Vec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }
};

} // namespace candela
