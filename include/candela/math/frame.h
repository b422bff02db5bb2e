#pragma once
#include "candela/math/vec.h"

namespace candela {

/// Orthonormal frame (s, t, n). BSDFs work in local coordinates where n = +z.
/// Built with the branchless method of Duff et al., "Building an Orthonormal Basis, Revisited"
/// (JCGT 2017), which is continuous except at n.z = -1 exactly and never divides by zero.
struct Frame {
    Vec3 s, t, n;
    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3& normal) : n(normal) {
        float sign = std::copysign(1.f, n.z);
        float a = -1.f / (sign + n.z);
        float b = n.x * n.y * a;
        s = Vec3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
        t = Vec3(b, sign + n.y * n.y * a, -n.y);
    }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

} // namespace candela
