#pragma once
// Bounds on the rounding error of float and double arithmetic, used wherever a computed
// position or distance must be certified (ray-triangle tests, ray origin offsets, light
// sampling points).
#include <limits>

namespace candela {

/// Unit roundoff of float (half the machine epsilon).
constexpr float kFloatUnitRoundoff = std::numeric_limits<float>::epsilon() * 0.5f;

/// The classic bound gamma(n) = n u / (1 - n u) on the relative error accumulated by n
/// successive float roundings (Higham; pbrt-v4 section 6.8.1).
constexpr float float_gamma(int n) {
    return (static_cast<float>(n) * kFloatUnitRoundoff) /
           (1.f - static_cast<float>(n) * kFloatUnitRoundoff);
}

/// The same bound for double arithmetic.
constexpr double double_gamma(int n) {
    constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
    return (static_cast<double>(n) * u) / (1.0 - static_cast<double>(n) * u);
}

} // namespace candela
