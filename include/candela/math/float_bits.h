#pragma once
// Stepping a float to its neighbours through its bit pattern: what std::nextafter does toward
// +-infinity, without the library call (these run for every spawned ray).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace candela {

inline std::uint32_t float_to_bits(float f) {
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

inline float bits_to_float(std::uint32_t b) {
    float f;
    std::memcpy(&f, &b, sizeof f);
    return f;
}

/// The next float above v (+infinity and NaN stay; -0 counts as +0), equal to
/// std::nextafter(v, +infinity) for every other value.
inline float next_float_up(float v) {
    if (std::isinf(v) && v > 0.f) return v;
    if (std::isnan(v)) return v;
    if (v == 0.f) v = 0.f; // -0 -> +0
    std::uint32_t b = float_to_bits(v);
    b = v >= 0.f ? b + 1 : b - 1;
    return bits_to_float(b);
}

/// The next float below v (-infinity and NaN stay; +0 counts as -0), equal to
/// std::nextafter(v, -infinity) for every other value.
inline float next_float_down(float v) {
    if (std::isinf(v) && v < 0.f) return v;
    if (std::isnan(v)) return v;
    if (v == 0.f) v = -0.f; // +0 -> -0
    std::uint32_t b = float_to_bits(v);
    b = v > 0.f ? b - 1 : b + 1;
    return bits_to_float(b);
}

/// v stepped one float in the direction of `dir`'s sign: std::nextafter(v, copysign(inf, dir))
/// when dir != 0, v itself when dir is +-0; infinities and NaN stay. Without branches on the
/// signs (which are random for ray offsets, so branches would mispredict half the time).
inline float next_float_toward_sign(float v, float dir) {
    std::uint32_t vb = float_to_bits(v);
    const std::uint32_t db = float_to_bits(dir);
    constexpr std::uint32_t kSign = 0x80000000u, kMagnitude = 0x7fffffffu;
    constexpr std::uint32_t kExponent = 0x7f800000u;
    // A zero takes the direction's sign, so that the step below moves it off zero that way.
    vb = (vb & kMagnitude) == 0 ? (db & kSign) : vb;
    // Same sign: away from zero, one more in the magnitude; opposite signs: one less.
    const std::uint32_t step = ((vb ^ db) & kSign) ? 0xffffffffu : 1u;
    const bool moves = (db & kMagnitude) != 0 && (vb & kExponent) != kExponent;
    return moves ? bits_to_float(vb + step) : v;
}

} // namespace candela
