#pragma once
// Adaptive sampling decisions, separate from the renderer so they can be tested on synthetic
// statistics.
//
// cs184: spec §5.4, a pixel stops when its own 95% confidence half-width on luminance falls
// below tol times its mean.
//
// relative: a global budget (the cost of spp x pixels uniform samples) is spent in passes. The
// first pass gives every pixel the same batch; each later pass hands its share of the budget to the
// pixels in proportion to how far they are below their optimal sample count. The per-pixel error
// estimate is the relative variance of one sample, var / (mu^2 + floor), of each pixel, averaged
// over a (2r+1)^2 neighbourhood: the floor keeps dark pixels from being starved (their relative
// error is not taken as infinite) and the smoothing keeps one pixel's own unlucky samples from
// deciding its budget. Minimising sum_p e_p / n_p subject to sum_p n_p = N gives n_p proportional
// to sqrt(e_p). Samples do not all cost the same, though: a camera ray into the black background is
// one cheap query, a path through a closed box takes about ten times as long. With c_p the cost of
// one sample of pixel p, minimising sum_p e_p / n_p subject to sum_p c_p n_p = C gives n_p = C
// sqrt(e_p / c_p) / sum_q sqrt(e_q c_q), and the budget is counted in cost units. The render stops
// when the estimated relative RMS error of the image is below tol or the budget is spent.
#include <cstdint>
#include <vector>

namespace candela {

/// Per-pixel luminance statistics of a film, row-major.
struct LumStatsMap {
    int width = 0, height = 0;
    std::vector<double> mean;     ///< sample mean of luminance
    std::vector<double> var;      ///< sample variance of luminance (n-1 denominator)
    std::vector<std::uint32_t> n; ///< samples taken (finite or dropped: indices used)
    /// Optional per-channel statistics (3 per pixel: R, G, B), when the film keeps sums of
    /// squares. With them the relative error is that of each channel, averaged, which is what
    /// relMSE measures: a coloured surface's dark channels are relatively noisier than its
    /// luminance.
    std::vector<double> mean_rgb, var_rgb;
};

/// The CS184 criterion (spec §5.4): true when 1.96 sigma / sqrt(n) <= tol * mu. Needs n >= 2.
bool cs184_converged(double mean, double var, std::uint32_t n, double tol);

class Film;
/// cs184_converged() on pixel (x, y) of a film with lum_stats.
bool adaptive_pixel_converged(const Film& film, int x, int y, double tol);

/// Relative variance of one sample per pixel (dimensionless), var / (mu^2 + floor) with the dark
/// floor of adaptive.cpp, of luminance or averaged over R, G, B when the map has per-channel
/// statistics; each pixel's value is then averaged over the pixels of its (2 radius + 1)^2
/// neighbourhood that have at least two samples.
std::vector<double> relative_error_map(const LumStatsMap& stats, int radius);

/// Mean of the values of the valid pixels in each pixel's (2 radius + 1)^2 neighbourhood,
/// clipped at the frame; 0 where the neighbourhood has no valid pixel. Row-major, w x h.
std::vector<double> window_mean(const std::vector<double>& values,
                                const std::vector<std::uint8_t>& valid, int w, int h, int radius);

/// Estimated relative RMS error of the image's pixel means: sqrt(mean_p e_p / n_p).
double estimated_relative_rms(const LumStatsMap& stats, const std::vector<double>& error_map);

/// Cost of one sample per pixel (cost units per sample), smoothed over the same
/// (2 radius + 1)^2 neighbourhood as relative_error_map(): the window's total cost divided by
/// its total samples. `cost` holds each pixel's total cost so far (RenderState::cost). Pixels
/// whose window has no sample get the image's mean cost per sample. Throws Error(Internal) when
/// the sizes disagree or no sample has any cost.
std::vector<double> cost_per_sample_map(const LumStatsMap& stats,
                                        const std::vector<std::uint64_t>& cost, int radius);

/// Samples per pixel for the next pass of the relative sampler, with every sample costing the
/// same: allocate_pass() with unit costs and a budget of `budget` samples.
std::vector<int> allocate_pass(const LumStatsMap& stats, const std::vector<double>& error_map,
                               std::uint64_t budget, int max_per_pixel);

/// Samples per pixel for the next pass of the relative sampler, cost-aware. `cost_map` is the
/// cost of one sample of each pixel (cost units, > 0); `budget` is the pass's budget in cost
/// units. The optimal allocation of all the cost spent once this pass is done (the cost of the
/// samples already taken, sum_p c_p n_p, plus `budget`) is n*_p proportional to
/// sqrt(e_p / c_p), capped at max_per_pixel; the pass gives each pixel samples in proportion to
/// its deficit n*_p - n_p, scaled so that their cost, sum_p c_p a_p, is at most `budget`.
/// Counts are rounded down with the remainder carried in row-major order. Deterministic
/// (depends only on the inputs). Returns one count per pixel.
std::vector<int> allocate_pass(const LumStatsMap& stats, const std::vector<double>& error_map,
                               const std::vector<double>& cost_map, double budget,
                               int max_per_pixel);

} // namespace candela
