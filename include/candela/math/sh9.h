#pragma once
// Real spherical harmonics of orders 0 to 2 (nine functions), for the irradiance a surface of a
// given orientation receives from distant light: Ramamoorthi and Hanrahan, "An Efficient
// Representation for Irradiance Environment Maps" (SIGGRAPH 2001). Projecting a radiance
// function L(w) on the nine functions and scaling order l by A_l (the clamped cosine's own
// coefficients, A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4) gives the coefficients of the
// irradiance E(n) = integral of L(w) max(0, n . w) dw, whose remaining orders are small (A_l
// vanishes for odd l > 1 and falls as l^-2.5 for even l).
#include "candela/math/constants.h"
#include "candela/math/vec.h"

#include <array>

namespace candela {

/// Coefficients of the nine functions, in the order of sh9_basis().
using Sh9 = std::array<float, 9>;

/// The nine orthonormal real harmonics at unit direction d: Y00; Y1-1, Y10, Y11 (y, z, x);
/// Y2-2, Y2-1, Y20, Y21, Y22 (xy, yz, 3z^2 - 1, xz, x^2 - y^2), with the normalisations of
/// Ramamoorthi and Hanrahan's equation 3.
inline Sh9 sh9_basis(const Vec3& d) {
    return {0.282095f,
            0.488603f * d.y,
            0.488603f * d.z,
            0.488603f * d.x,
            1.092548f * d.x * d.y,
            1.092548f * d.y * d.z,
            0.315392f * (3.f * d.z * d.z - 1.f),
            1.092548f * d.x * d.z,
            0.546274f * (d.x * d.x - d.y * d.y)};
}

/// A_l of the clamped cosine for coefficient i of sh9_basis() (its order l = 0, 1 or 2).
inline float sh9_cosine_lobe(int i) {
    return i == 0 ? kPi : i < 4 ? 2.f * kPi / 3.f : kPi / 4.f;
}

/// The function with coefficients `c` at unit direction d.
inline float sh9_eval(const Sh9& c, const Vec3& d) {
    const Sh9 y = sh9_basis(d);
    float sum = 0.f;
    for (int i = 0; i < 9; ++i)
        sum += c[std::size_t(i)] * y[std::size_t(i)];
    return sum;
}

} // namespace candela
