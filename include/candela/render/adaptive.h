#pragma once
// Adaptive sampling decisions, separate from the renderer so they can be tested on synthetic
// statistics.
//
// cs184: spec §5.4, a pixel stops when its own 95% confidence half-width on luminance falls
// below tol times its mean.
//
// relative: a global budget (spp x pixels) is spent in passes. The first pass gives every pixel
// the same batch; each later pass hands its share of the budget to the pixels in proportion to
// how far they are below their optimal sample count. The per-pixel error estimate is the relative
// variance of luminance, var / (mu^2 + floor), where variance and mean are averaged over a
// (2r+1)^2 neighbourhood: the floor keeps dark pixels from being starved (their relative error is
// not taken as infinite) and the smoothing keeps one pixel's own unlucky samples from deciding
// its budget. Minimising sum_p e_p / n_p subject to sum_p n_p = N gives n_p proportional to
// sqrt(e_p). The render stops when the estimated relative RMS error of the image is below tol or
// the budget is spent.
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

/// Relative variance of one sample per pixel (dimensionless), smoothed over a
/// (2 radius + 1)^2 neighbourhood, with the dark floor of adaptive.cpp in the denominator: of
/// luminance, or averaged over R, G, B when the map has per-channel statistics.
std::vector<double> relative_error_map(const LumStatsMap& stats, int radius);

/// Estimated relative RMS error of the image's pixel means: sqrt(mean_p e_p / n_p).
double estimated_relative_rms(const LumStatsMap& stats, const std::vector<double>& error_map);

/// Samples per pixel for the next pass of the relative sampler: at most `budget` in total and
/// at most `max_per_pixel - n_p` for pixel p, in proportion to each pixel's deficit against
/// the optimal allocation n_p proportional to sqrt(e_p) of the samples taken after this pass.
/// Deterministic (depends only on the inputs). Returns one count per pixel.
std::vector<int> allocate_pass(const LumStatsMap& stats, const std::vector<double>& error_map,
                               std::uint64_t budget, int max_per_pixel);

} // namespace candela
