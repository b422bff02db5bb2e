#pragma once
// Comparison of two EXR renders of the same sample indices whose film sums were added in a
// different order (distributed renders, merged partial renders). The bounds follow from float
// rounding of the stored means; see docs/distributed.md.
#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace candela::test {

/// Unit roundoff of float: every mean in an EXR was rounded to float once.
constexpr double kFloatUnitRoundoff = 1.0 / (1 << 24);

struct CompareResult {
    double max_rgb_rel = 0.0;    ///< largest |a - b| / max(|a|, |b|) over R, G, B
    double max_ratio = 0.0;      ///< largest error / bound over all channels (<= 1 passes)
    std::size_t count_diffs = 0; ///< pixels whose `samples` differ (must be 0)
};

/// Compares every channel of two renders of the same sample set:
///  - samples, A (hit count / sample count) and Z (the nearest hit, a minimum: the same in any
///    order; +inf where no sample hit) exactly;
///  - R, G, B (double sums, float means): |a - b| <= 4 u max(|a|, |b|): each side rounds its
///    mean to float once, a merged side also sums float-rounded input means (one more u), and
///    the double summation order adds ~1e-16, far below u = 2^-24;
///  - albedo, N (float sums of n terms, order changed): |a - b| <= (n + 4) u scale, where
///    scale bounds the mean of |terms| (1 for unit normals, the mean itself for non-negative
///    albedo);
///  - variance (recomputed from sums S1, S2 = v n (n - 1) + m^2 n with float m, v):
///    |a - b| <= 8 u (v + 2 m^2 / (n - 1)) + 2 u v.
inline CompareResult compare_renders(const ImageData& a, const ImageData& b) {
    REQUIRE(a.width == b.width);
    REQUIRE(a.height == b.height);
    REQUIRE(a.channel_names == b.channel_names);
    const int sc = a.channel_index("samples");
    REQUIRE(sc >= 0);
    const double u = kFloatUnitRoundoff;
    CompareResult r;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const double n = a.at(x, y, sc);
            if (n != b.at(x, y, sc)) ++r.count_diffs;
            for (int c = 0; c < a.channels(); ++c) {
                const std::string& name = a.channel_names[c];
                const double va = a.at(x, y, c), vb = b.at(x, y, c);
                if (name == "Z") {
                    if (va != vb) {
                        INFO("Z at pixel (" << x << ", " << y << "): " << va << " vs " << vb);
                        CHECK(va == vb);
                    }
                    continue;
                }
                REQUIRE(std::isfinite(va));
                REQUIRE(std::isfinite(vb));
                const double diff = std::abs(va - vb);
                const double mag = std::max(std::abs(va), std::abs(vb));
                double bound = 0.0;
                if (name == "samples" || name == "A") {
                    bound = 0.0;
                } else if (name == "R" || name == "G" || name == "B") {
                    bound = 4.0 * u * mag;
                    if (mag > 0.0) r.max_rgb_rel = std::max(r.max_rgb_rel, diff / mag);
                } else if (name.rfind("N.", 0) == 0) {
                    bound = (n + 4.0) * u * 1.0;
                } else if (name.rfind("albedo.", 0) == 0) {
                    bound = (n + 4.0) * u * mag;
                } else if (name.rfind("variance.", 0) == 0) {
                    const double m = a.at(x, y, a.channel_index(name.substr(9)));
                    bound =
                        n >= 2.0 ? 8.0 * u * (mag + 2.0 * m * m / (n - 1.0)) + 2.0 * u * mag : 0.0;
                } else {
                    FAIL("unexpected channel " << name);
                }
                if (diff > bound) {
                    INFO("channel " << name << " pixel (" << x << ", " << y << "): " << va << " vs "
                                    << vb << ", bound " << bound);
                    CHECK(diff <= bound);
                }
                if (bound > 0.0) r.max_ratio = std::max(r.max_ratio, diff / bound);
            }
        }
    return r;
}

} // namespace candela::test
