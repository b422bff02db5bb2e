#include "candela/render/adaptive.h"

#include "candela/render/film.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>

namespace candela {

namespace {

/// z-value of the CS184 criterion: a 95% confidence half-width (spec §5.4).
constexpr double kConfidenceZ = 1.96;
/// Added to mu^2 in the relative error: the same constant as in the relMSE metric of
/// `candela converge` (converge.h), so the sampler minimises the error that is measured, and a
/// black or very dark pixel has a finite (not infinite) relative error.
constexpr double kDarkFloor = 0.01;

} // namespace

bool cs184_converged(double mean, double var, std::uint32_t n, double tol) {
    if (n < 2) return false;
    const double half_width = kConfidenceZ * std::sqrt(std::max(0.0, var) / double(n));
    return half_width <= tol * mean;
}

bool adaptive_pixel_converged(const Film& film, int x, int y, double tol) {
    double mean, var;
    std::uint32_t n;
    film.lum_stats(x, y, mean, var, n);
    return cs184_converged(mean, var, n, tol);
}

std::vector<double> relative_error_map(const LumStatsMap& st, int radius) {
    const int w = st.width, h = st.height;
    const std::size_t P = std::size_t(w) * h;
    if (st.mean.size() != P || st.var.size() != P || st.n.size() != P)
        throw Error(ErrorKind::Internal, "relative_error_map: statistics do not match the size");
    const bool rgb = st.mean_rgb.size() == 3 * P && st.var_rgb.size() == 3 * P;
    const int channels = rgb ? 3 : 1;
    std::vector<double> e(P, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sm[3] = {0, 0, 0}, sv[3] = {0, 0, 0};
            int cnt = 0;
            for (int yy = std::max(0, y - radius); yy <= std::min(h - 1, y + radius); ++yy)
                for (int xx = std::max(0, x - radius); xx <= std::min(w - 1, x + radius); ++xx) {
                    std::size_t j = std::size_t(yy) * w + xx;
                    if (st.n[j] < 2) continue;
                    for (int c = 0; c < channels; ++c) {
                        sm[c] += rgb ? st.mean_rgb[3 * j + c] : st.mean[j];
                        sv[c] += std::max(0.0, rgb ? st.var_rgb[3 * j + c] : st.var[j]);
                    }
                    ++cnt;
                }
            if (cnt == 0) continue;
            double sum = 0.0;
            for (int c = 0; c < channels; ++c) {
                double m = sm[c] / cnt, v = sv[c] / cnt;
                sum += v / (m * m + kDarkFloor);
            }
            e[std::size_t(y) * w + x] = sum / channels;
        }
    return e;
}

double estimated_relative_rms(const LumStatsMap& st, const std::vector<double>& e) {
    const std::size_t P = e.size();
    if (P == 0) return 0.0;
    double sum = 0.0;
    for (std::size_t i = 0; i < P; ++i)
        if (st.n[i] > 0) sum += e[i] / double(st.n[i]);
    return std::sqrt(sum / double(P));
}

std::vector<int> allocate_pass(const LumStatsMap& st, const std::vector<double>& e,
                               std::uint64_t budget, int max_per_pixel) {
    const std::size_t P = e.size();
    std::vector<int> alloc(P, 0);
    if (P == 0 || budget == 0) return alloc;
    double taken = 0.0, sum_sqrt = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        taken += double(st.n[i]);
        sum_sqrt += std::sqrt(e[i]);
    }
    if (!(sum_sqrt > 0.0)) return alloc; // nothing has any variance: nothing to gain
    const double c = (taken + double(budget)) / sum_sqrt;
    std::vector<double> deficit(P, 0.0);
    double sum_deficit = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        double target = std::min(double(max_per_pixel), c * std::sqrt(e[i]));
        deficit[i] = std::max(0.0, target - double(st.n[i]));
        sum_deficit += deficit[i];
    }
    if (!(sum_deficit > 0.0)) return alloc;
    const double scale = std::min(1.0, double(budget) / sum_deficit);
    // Rounding with the remainder carried along the row-major order: the counts sum to the
    // rounded total exactly and depend on nothing but the inputs.
    double carry = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        double want = deficit[i] * scale + carry;
        int k = int(std::floor(want));
        k = std::min(k, std::max(0, max_per_pixel - int(st.n[i])));
        alloc[i] = std::max(0, k);
        carry = want - double(alloc[i]);
        carry = std::min(carry, 1.0); // a capped pixel does not push its excess onward
    }
    return alloc;
}

} // namespace candela
