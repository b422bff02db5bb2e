// Adaptive sampling decisions (error maps, per-pixel allocation) on statistics, apart from the
// renderer.
#include "candela/render/adaptive.h"

#include "candela/render/film.h"
#include "candela/sampling/rng.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

/// Pixels one task of the per-pixel loops below takes at least: a few microseconds of work,
/// so that a small image is not split into tasks that cost more to schedule than to run.
constexpr std::size_t kPixelGrain = 4096;

/// Runs body(begin, end) over [0, count) in parallel chunks. Every loop that uses it writes
/// each index's result from that index's inputs alone, so the results do not depend on the
/// split or the thread count; sums over pixels stay serial, in index order, for the same reason.
template <class Body> void for_pixels(std::size_t count, const Body& body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kPixelGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// for_pixels() over the rows of a w-wide image: body(y_begin, y_end).
template <class Body> void for_rows(int w, int h, const Body& body) {
    const std::size_t rows_per_task =
        std::max<std::size_t>(1, kPixelGrain / std::max<std::size_t>(1, std::size_t(w)));
    tbb::parallel_for(tbb::blocked_range<int>(0, h, rows_per_task),
                      [&](const tbb::blocked_range<int>& r) { body(r.begin(), r.end()); });
}

/// Sums of v over every pixel's (2 radius + 1)^2 window clipped at the frame, with or without
/// the pixel itself, into out (w x h, row-major). Rows first, then columns, each sum taken from
/// the values themselves: a running sum would subtract the value leaving the window, and with
/// the centre excluded its rounding would carry the pixel's own value into its window. `row`
/// and `row_others` are scratch of w x h values. For integer T the sums are exact.
template <class T>
void window_sums(const T* v, int w, int h, int radius, WindowCentre centre, T* out,
                 std::vector<T>& row, std::vector<T>& row_others) {
    const std::size_t P = std::size_t(w) * h;
    const bool exclude = centre == WindowCentre::Exclude;
    row.resize(P);
    if (exclude) row_others.resize(P);
    for_rows(w, h, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const T* in = v + std::size_t(y) * w;
            T* all = row.data() + std::size_t(y) * w;
            T* others = exclude ? row_others.data() + std::size_t(y) * w : nullptr;
            for (int x = 0; x < w; ++x) {
                T left = T(0), right = T(0);
                for (int xx = std::max(0, x - radius); xx < x; ++xx)
                    left += in[xx];
                for (int xx = x + 1; xx <= std::min(w - 1, x + radius); ++xx)
                    right += in[xx];
                all[x] = left + in[x] + right;
                if (exclude) others[x] = left + right;
            }
        }
    });
    for_rows(w, h, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
            const T* own_row = (exclude ? row_others.data() : row.data()) + std::size_t(y) * w;
            T* o = out + std::size_t(y) * w;
            for (int x = 0; x < w; ++x) {
                T sum = T(0);
                for (int yy = y0; yy <= y1; ++yy)
                    sum += yy == y ? own_row[x] : row[std::size_t(yy) * w + x];
                o[x] = sum;
            }
        }
    });
}

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
    CANDELA_CHECK(st.mean.size() == P && st.var.size() == P && st.n.size() == P,
                  "relative_error_map: statistics do not match the size");
    const bool rgb = st.mean_rgb.size() == 3 * P && st.var_rgb.size() == 3 * P;
    const int channels = rgb ? 3 : 1;
    // Each pixel's own relative variance first, then its average over the window. Averaging
    // the ratio (not the variance and the mean separately) keeps the estimate of a pixel next
    // to the bright light or the black background its own: a window mean pulled up by the light
    // would make its neighbours look noiseless, one pulled down by the background would make
    // them look noisy.
    std::vector<double> own(P, 0.0);
    std::vector<std::uint8_t> valid(P, 0);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
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
    });
    // A window of the pixel alone is its own value (0 where it has none): what window_mean()
    // gives, without its passes over the image.
    if (radius == 0 && centre == WindowCentre::Include) return own;
    return window_mean(own, valid, w, h, radius, centre);
}

std::vector<double> window_mean(const std::vector<double>& v,
                                const std::vector<std::uint8_t>& valid, int w, int h, int radius,
                                WindowCentre centre) {
    const std::size_t P = std::size_t(w) * h;
    CANDELA_CHECK(v.size() == P && valid.size() == P, "window_mean: values do not match the size");
    const bool exclude = centre == WindowCentre::Exclude;
    double all_sum = 0.0;
    std::size_t all_cnt = 0;
    for (std::size_t i = 0; i < P; ++i)
        if (valid[i]) {
            all_sum += v[i];
            ++all_cnt;
        }
    // The valid values (0 elsewhere, which adds nothing) and their counts, summed per window.
    std::vector<double> masked(P), sum(P), row, row_others;
    std::vector<std::uint32_t> ones(P), count(P), count_row, count_row_others;
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            masked[i] = valid[i] ? v[i] : 0.0;
            ones[i] = valid[i] ? 1u : 0u;
        }
    });
    window_sums(masked.data(), w, h, radius, centre, sum.data(), row, row_others);
    window_sums(ones.data(), w, h, radius, centre, count.data(), count_row, count_row_others);
    std::vector<double> out(P, 0.0);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            if (count[i] > 0) {
                out[i] = sum[i] / count[i];
            } else if (exclude) {
                // Every other valid pixel of the image, still without this one.
                const std::size_t others = all_cnt - (valid[i] ? 1 : 0);
                if (others > 0) out[i] = (all_sum - (valid[i] ? v[i] : 0.0)) / double(others);
            }
        }
    });
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
    CANDELA_CHECK(st.n.size() == P && cost.size() == P,
                  "cost_per_sample_map: costs do not match the size");
    double all_cost = 0.0, all_n = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        all_cost += double(cost[i]);
        all_n += double(st.n[i]);
    }
    CANDELA_CHECK(all_cost > 0.0 && all_n > 0.0, "cost_per_sample_map: no sample has been costed");
    const double mean_cost = all_cost / all_n;
    // Integer window sums: exact, so the same in any order.
    std::vector<std::uint64_t> samples(P), sc(P), sn(P), row, row_others;
    for (std::size_t i = 0; i < P; ++i)
        samples[i] = st.n[i];
    window_sums(cost.data(), w, h, radius, centre, sc.data(), row, row_others);
    window_sums(samples.data(), w, h, radius, centre, sn.data(), row, row_others);
    std::vector<double> c(P, mean_cost);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            if (sn[i] > 0 && sc[i] > 0) c[i] = double(sc[i]) / double(sn[i]);
    });
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
    CANDELA_CHECK(st.n.size() == P && cost.size() == P, "allocate_pass: maps do not match in size");
    std::vector<int> alloc(P, 0);
    if (P == 0 || !(budget > 0.0)) return alloc;
    for (std::size_t i = 0; i < P; ++i)
        CANDELA_CHECK(cost[i] > 0.0 && std::isfinite(cost[i]),
                      "allocate_pass: a sample cost is not positive");
    // n*_p = lambda sqrt(e_p / c_p) with lambda set by sum_p c_p n*_p = cost spent after the pass.
    // The per-pixel terms are computed in parallel, their sums serially in pixel order.
    std::vector<double> term(P);
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            term[i] = std::sqrt(e[i] * cost[i]);
    });
    double spent = 0.0, sum_sqrt_ec = 0.0;
    for (std::size_t i = 0; i < P; ++i) {
        spent += cost[i] * double(st.n[i]);
        sum_sqrt_ec += term[i];
    }
    if (!(sum_sqrt_ec > 0.0)) return alloc; // nothing has any variance: nothing to gain
    const double lambda = (spent + budget) / sum_sqrt_ec;
    std::vector<double>& deficit = term; // reused: one value per pixel again
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            double target = std::min(double(max_per_pixel), lambda * std::sqrt(e[i] / cost[i]));
            deficit[i] = std::max(0.0, target - double(st.n[i]));
        }
    });
    double deficit_cost = 0.0;
    for (std::size_t i = 0; i < P; ++i)
        deficit_cost += deficit[i] * cost[i];
    if (!(deficit_cost > 0.0)) return alloc;
    const double scale = std::min(1.0, budget / deficit_cost);
    // Unbiased rounding of each pixel on its own (see adaptive.h): floor(share + u), u uniform.
    for_pixels(P, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double u = double(hash_combine(rounding_seed, i) >> 11) * 0x1p-53;
            int k = int(std::floor(deficit[i] * scale + u));
            k = std::min(k, std::max(0, max_per_pixel - int(st.n[i])));
            alloc[i] = std::max(0, k);
        }
    });
    return alloc;
}

int relative_max_per_pixel(int spp) {
    return int(std::min<long long>((long long)spp * kRelativeMaxOversampling, kMaxSpp));
}

void fill_lum_stats(const Film& film, LumStatsMap& m) {
    m.width = film.width();
    m.height = film.height();
    const std::size_t P = film.pixel_count();
    m.mean.resize(P);
    m.var.resize(P);
    m.n.resize(P);
    const bool rgb = film.aovs().variance;
    m.mean_rgb.resize(rgb ? 3 * P : 0);
    m.var_rgb.resize(rgb ? 3 * P : 0);
    // Each pixel's statistics from its own sums: the same values for any split.
    for_rows(m.width, m.height, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y)
            for (int x = 0; x < m.width; ++x) {
                const std::size_t i = std::size_t(y) * m.width + x;
                std::uint32_t n;
                film.lum_stats(x, y, m.mean[i], m.var[i], n);
                m.n[i] = n + film.dropped(x, y);
                if (!rgb) continue;
                const Rgb mu = film.mean(x, y), vm = film.variance_of_mean(x, y);
                const double count = double(film.count(x, y));
                for (int c = 0; c < 3; ++c) {
                    m.mean_rgb[3 * i + c] = mu[c];
                    m.var_rgb[3 * i + c] = double(vm[c]) * count; // variance of one sample
                }
            }
    });
}

} // namespace candela
