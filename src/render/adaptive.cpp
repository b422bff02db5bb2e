#include "candela/render/adaptive.h"

#include "candela/render/film.h"
#include "candela/sampling/rng.h"
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

std::vector<double> relative_error_map(const LumStatsMap& st, int radius, WindowCentre centre) {
    const int w = st.width, h = st.height;
    const std::size_t P = std::size_t(w) * h;
    if (st.mean.size() != P || st.var.size() != P || st.n.size() != P)
        throw Error(ErrorKind::Internal, "relative_error_map: statistics do not match the size");
    const bool rgb = st.mean_rgb.size() == 3 * P && st.var_rgb.size() == 3 * P;
    const int channels = rgb ? 3 : 1;
    // Each pixel's own relative variance first, then its average over the window. Averaging
    // the ratio (not the variance and the mean separately) keeps the estimate of a pixel next
    // to the bright light or the black background its own: a window mean pulled up by the light
    // would make its neighbours look noiseless, one pulled down by the background would make
    // them look noisy.
    std::vector<double> own(P, 0.0);
    std::vector<std::uint8_t> valid(P, 0);
    for (std::size_t i = 0; i < P; ++i) {
        if (st.n[i] < 2) continue;
        double sum = 0.0;
        for (int c = 0; c < channels; ++c) {
            const double m = rgb ? st.mean_rgb[3 * i + c] : st.mean[i];
            const double v = std::max(0.0, rgb ? st.var_rgb[3 * i + c] : st.var[i]);
            sum += v / (m * m + kDarkFloor);
        }
        own[i] = sum / channels;
        valid[i] = 1;
    }
    return window_mean(own, valid, w, h, radius, centre);
}

std::vector<double> window_mean(const std::vector<double>& v,
                                const std::vector<std::uint8_t>& valid, int w, int h, int radius,
                                WindowCentre centre) {
    const std::size_t P = std::size_t(w) * h;
    if (v.size() != P || valid.size() != P)
        throw Error(ErrorKind::Internal, "window_mean: values do not match the size");
    const bool exclude = centre == WindowCentre::Exclude;
    double all_sum = 0.0;
    std::size_t all_cnt = 0;
    for (std::size_t i = 0; i < P; ++i)
        if (valid[i]) {
            all_sum += v[i];
            ++all_cnt;
        }
    std::vector<double> out(P, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * w + x;
            double sum = 0.0;
            int cnt = 0;
            for (int yy = std::max(0, y - radius); yy <= std::min(h - 1, y + radius); ++yy)
                for (int xx = std::max(0, x - radius); xx <= std::min(w - 1, x + radius); ++xx) {
                    std::size_t j = std::size_t(yy) * w + xx;
                    if (!valid[j] || (exclude && j == i)) continue;
                    sum += v[j];
                    ++cnt;
                }
            if (cnt > 0) {
                out[i] = sum / cnt;
            } else if (exclude) {
                // Every other valid pixel of the image, still without this one.
                const std::size_t others = all_cnt - (valid[i] ? 1 : 0);
                if (others > 0) out[i] = (all_sum - (valid[i] ? v[i] : 0.0)) / double(others);
            }
        }
    return out;
}

double estimated_relative_rms(const LumStatsMap& st, const std::vector<double>& e) {
    const std::size_t P = e.size();
    if (P == 0) return 0.0;
    double sum = 0.0;
    for (std::size_t i = 0; i < P; ++i)
        if (st.n[i] > 0) sum += e[i] / double(st.n[i]);
    return std::sqrt(sum / double(P));
}

std::vector<double> cost_per_sample_map(const LumStatsMap& st,
                                        const std::vector<std::uint64_t>& cost, int radius,
                                        WindowCentre centre) {
    const int w = st.width, h = st.height;
    const std::size_t P = std::size_t(w) * h;
    if (st.n.size() != P || cost.size() != P)
        throw Error(ErrorKind::Internal, "cost_per_sample_map: costs do not match the size");
    double all_cost = 0.0, all_n = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        all_cost += double(cost[i]);
        all_n += double(st.n[i]);
    }
    if (!(all_cost > 0.0) || !(all_n > 0.0))
        throw Error(ErrorKind::Internal, "cost_per_sample_map: no sample has been costed");
    const double mean_cost = all_cost / all_n;
    std::vector<double> c(P, mean_cost);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sc = 0.0, sn = 0.0;
            for (int yy = std::max(0, y - radius); yy <= std::min(h - 1, y + radius); ++yy)
                for (int xx = std::max(0, x - radius); xx <= std::min(w - 1, x + radius); ++xx) {
                    std::size_t j = std::size_t(yy) * w + xx;
                    if (centre == WindowCentre::Exclude && yy == y && xx == x) continue;
                    sc += double(cost[j]);
                    sn += double(st.n[j]);
                }
            if (sn > 0.0 && sc > 0.0) c[std::size_t(y) * w + x] = sc / sn;
        }
    return c;
}

std::vector<int> allocate_pass(const LumStatsMap& st, const std::vector<double>& e,
                               std::uint64_t budget, int max_per_pixel,
                               std::uint64_t rounding_seed) {
    return allocate_pass(st, e, std::vector<double>(e.size(), 1.0), double(budget), max_per_pixel,
                         rounding_seed);
}

std::vector<int> allocate_pass(const LumStatsMap& st, const std::vector<double>& e,
                               const std::vector<double>& cost, double budget, int max_per_pixel,
                               std::uint64_t rounding_seed) {
    const std::size_t P = e.size();
    if (st.n.size() != P || cost.size() != P)
        throw Error(ErrorKind::Internal, "allocate_pass: maps do not match in size");
    std::vector<int> alloc(P, 0);
    if (P == 0 || !(budget > 0.0)) return alloc;
    for (std::size_t i = 0; i < P; ++i)
        if (!(cost[i] > 0.0) || !std::isfinite(cost[i]))
            throw Error(ErrorKind::Internal, "allocate_pass: a sample cost is not positive");
    // n*_p = lambda sqrt(e_p / c_p) with lambda set by sum_p c_p n*_p = cost spent after the pass.
    double spent = 0.0, sum_sqrt_ec = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        spent += cost[i] * double(st.n[i]);
        sum_sqrt_ec += std::sqrt(e[i] * cost[i]);
    }
    if (!(sum_sqrt_ec > 0.0)) return alloc; // nothing has any variance: nothing to gain
    const double lambda = (spent + budget) / sum_sqrt_ec;
    std::vector<double> deficit(P, 0.0);
    double deficit_cost = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        double target = std::min(double(max_per_pixel), lambda * std::sqrt(e[i] / cost[i]));
        deficit[i] = std::max(0.0, target - double(st.n[i]));
        deficit_cost += deficit[i] * cost[i];
    }
    if (!(deficit_cost > 0.0)) return alloc;
    const double scale = std::min(1.0, budget / deficit_cost);
    // Unbiased rounding of each pixel on its own (see adaptive.h): floor(share + u), u uniform.
    for (std::size_t i = 0; i < P; ++i) {
        const double u = double(hash_combine(rounding_seed, i) >> 11) * 0x1p-53;
        int k = int(std::floor(deficit[i] * scale + u));
        k = std::min(k, std::max(0, max_per_pixel - int(st.n[i])));
        alloc[i] = std::max(0, k);
    }
    return alloc;
}

} // namespace candela
