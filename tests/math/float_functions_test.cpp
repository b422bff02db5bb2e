// The polynomial sincos of the samplers against the library's, and the float stepping of ray
// offsets against std::nextafter.
#include "candela/math/constants.h"
#include "candela/math/float_bits.h"
#include "candela/math/sincos.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace candela;

namespace {

/// Distance in units of the last place of the correctly rounded value (computed in double).
double ulps(float got, double exact) {
    const float rounded = float(exact);
    const double ulp = std::nextafter(std::abs(rounded), std::numeric_limits<float>::infinity()) -
                       std::abs(rounded);
    return std::abs(double(got) - exact) / ulp;
}

} // namespace

TEST_CASE("sincos_quarter and sincos_turns are within 2 ulp of sin and cos", "[math][quick]") {
    // Every 2^-20 of a turn, plus the ends of each quarter, where the reduction switches.
    double worst_sin = 0.0, worst_cos = 0.0, worst_abs = 0.0;
    for (int k = 0; k <= (1 << 20); ++k) {
        const float u = float(k) * 0x1p-20f;
        float s, c;
        sincos_turns(u, &s, &c);
        const double a = 2.0 * kPiD * double(u);
        const double es = std::sin(a), ec = std::cos(a);
        // Relative to the value where it is large; near a zero of sin or cos the absolute error
        // is what matters (the value there is the rounding of 2 pi u's own error).
        if (std::abs(es) > 1e-3) worst_sin = std::max(worst_sin, ulps(s, es));
        if (std::abs(ec) > 1e-3) worst_cos = std::max(worst_cos, ulps(c, ec));
        worst_abs = std::max({worst_abs, std::abs(s - es), std::abs(c - ec)});
    }
    INFO("worst: sin " << worst_sin << " ulp, cos " << worst_cos << " ulp, absolute " << worst_abs);
    // The argument 2 pi u is itself rounded to float (half an ulp of up to 2 pi, 2.4e-7), which
    // moves sin and cos by up to that much: the bound is that error plus the polynomial's.
    constexpr double kArgumentRounding = 2.4e-7;
    CHECK(worst_abs < kArgumentRounding + 1.2e-7);
    float s, c;
    for (float x : {-0.78539816f, -0.5f, -1e-30f, 0.f, 1e-6f, 0.3f, 0.78539816f}) {
        sincos_quarter(x, &s, &c);
        INFO("x = " << x);
        CHECK(ulps(s, std::sin(double(x))) <= 2.0);
        CHECK(ulps(c, std::cos(double(x))) <= 2.0);
    }
    sincos_turns(0.25f, &s, &c);
    CHECK(s == 1.f);
    CHECK(std::abs(c) < 1e-7f);
}

TEST_CASE("next_float_up and next_float_down step like std::nextafter", "[math][quick]") {
    const float inf = std::numeric_limits<float>::infinity();
    for (float v : {-inf, -3.5f, -1e-40f, -0.f, 0.f, 1e-45f, 1.f, 1.5e38f, inf,
                    std::numeric_limits<float>::max(), -std::numeric_limits<float>::max()}) {
        INFO("v = " << v);
        CHECK(next_float_up(v) == std::nextafter(v, inf));
        CHECK(next_float_down(v) == std::nextafter(v, -inf));
    }
    CHECK(std::isnan(next_float_up(std::nanf(""))));
}

TEST_CASE("next_float_toward_sign steps like std::nextafter toward the sign, without branches",
          "[math][quick]") {
    const float inf = std::numeric_limits<float>::infinity();
    for (float v : {-3.5f, -1e-40f, -0.f, 0.f, 1e-45f, 1.f, 1.5e38f, -1e-45f,
                    std::numeric_limits<float>::max(), -std::numeric_limits<float>::max()})
        for (float dir : {1.f, -1.f, 1e-30f, -2e38f}) {
            INFO("v = " << v << ", dir = " << dir);
            CHECK(next_float_toward_sign(v, dir) == std::nextafter(v, std::copysign(inf, dir)));
        }
    for (float v : {-2.f, 0.f, 7.f}) {
        CHECK(next_float_toward_sign(v, 0.f) == v);
        CHECK(next_float_toward_sign(v, -0.f) == v);
    }
    CHECK(next_float_toward_sign(inf, 1.f) == inf);
    CHECK(next_float_toward_sign(-inf, 1.f) == -inf);
}
