#pragma once
// Multiple importance sampling weights (Veach, "Robust Monte Carlo Methods for Light Transport
// Simulation", PhD thesis 1997, ch. 9).
#include <cmath>

namespace candela {

/// Power heuristic (beta = 2) weight of strategy f, with nf samples of density fpdf, against
/// strategy g with ng samples of density gpdf (densities in the same measure). Returns a weight
/// in [0, 1]: 1 when fpdf is infinite (a delta strategy dominates), 0 when only gpdf is infinite,
/// 0 when both densities are zero or either is NaN, 1/2 when both are infinite.
inline float power_heuristic(int nf, float fpdf, int ng, float gpdf) {
    float f = static_cast<float>(nf) * fpdf, g = static_cast<float>(ng) * gpdf;
    if (std::isnan(f) || std::isnan(g)) return 0.f;
    if (std::isinf(f) && std::isinf(g)) return 0.5f;
    if (std::isinf(f)) return 1.f;
    if (std::isinf(g)) return 0.f;
    if (f <= 0.f) return 0.f;
    if (g <= 0.f) return 1.f;
    // Ratio form: never squares a huge density, so never overflows.
    if (f >= g) {
        float r = g / f;
        return 1.f / (1.f + r * r);
    }
    float r = f / g;
    return r * r / (1.f + r * r);
}

/// Balance heuristic weight nf fpdf / (nf fpdf + ng gpdf), with the same limits as
/// power_heuristic.
inline float balance_heuristic(int nf, float fpdf, int ng, float gpdf) {
    float f = static_cast<float>(nf) * fpdf, g = static_cast<float>(ng) * gpdf;
    if (std::isnan(f) || std::isnan(g)) return 0.f;
    if (std::isinf(f) && std::isinf(g)) return 0.5f;
    if (std::isinf(f)) return 1.f;
    if (std::isinf(g)) return 0.f;
    if (f <= 0.f) return 0.f;
    if (g <= 0.f) return 1.f;
    return f >= g ? 1.f / (1.f + g / f) : (f / g) / (1.f + f / g);
}

} // namespace candela
