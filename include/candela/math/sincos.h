#pragma once
// Sine and cosine of the angles that samplers produce, by short polynomials instead of the
// library's general range reduction (sincosf ran for every sampled direction).
#include "candela/math/vec.h"

namespace candela {

/// sin(x) and cos(x) for |x| <= pi/4 from their Taylor series to x^9 and x^10. The first omitted
/// terms, x^11/11! and x^12/12!, are below 1.9e-9 and 1.1e-10 on that interval, far under half
/// an ulp of the results (>= 2^-25 for cos, relative 2^-24 for sin), so the error is that of the
/// float evaluation: within 2 ulp of the correctly rounded values (tests/math/sincos_test.cpp).
inline void sincos_quarter(float x, float* s, float* c) {
    const float x2 = x * x;
    *s = x * (1.f + x2 * (-1.f / 6.f +
                          x2 * (1.f / 120.f + x2 * (-1.f / 5040.f + x2 * (1.f / 362880.f)))));
    *c = 1.f +
         x2 * (-0.5f + x2 * (1.f / 24.f +
                             x2 * (-1.f / 720.f + x2 * (1.f / 40320.f + x2 * (-1.f / 3628800.f)))));
}

/// sin and cos of 2 pi u for u in [0, 1] (any real u, in fact): the quarter turn nearest to u
/// is taken out exactly and its rotation applied by swapping and negating.
inline void sincos_turns(float u, float* s, float* c) {
    const float q = std::floor(4.f * u + 0.5f);    // nearest multiple of a quarter turn
    const float r = (u - 0.25f * q) * (2.f * kPi); // |r| <= pi/4
    float sr, cr;
    sincos_quarter(r, &sr, &cr);
    switch (static_cast<int>(q) & 3) {
    case 0:
        *s = sr;
        *c = cr;
        break;
    case 1:
        *s = cr;
        *c = -sr;
        break;
    case 2:
        *s = -sr;
        *c = -cr;
        break;
    default:
        *s = -cr;
        *c = sr;
        break;
    }
}

} // namespace candela
