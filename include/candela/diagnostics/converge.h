#pragma once
// Error against run time: renders of one scene under several sampling configurations, timed and
// compared with a high-sample reference (`candela converge`). Errors are per pixel and channel
// of the mean radiance, averaged over the image:
//   MSE    = mean (x - r)^2                       (radiance^2)
//   relMSE = mean (x - r)^2 / (r^2 + kRelMseEps)  (dimensionless)
// each averaged over several seeds, with the standard error of that average.
#include "candela/render/film.h"
#include "candela/render/settings.h"
#include "candela/scene/scene.h"

#include <string>
#include <vector>

namespace candela {

/// The small constant in the relMSE denominator: keeps black pixels from dominating (the usual
/// 0.01 of the denoising and adaptive-sampling literature, for radiance of order 1).
constexpr double kRelMseEps = 0.01;

/// Error of `test` against `ref` (same size): MSE in radiance^2 and relMSE (dimensionless).
struct ImageError {
    double mse = 0.0;
    double rel_mse = 0.0;
};
ImageError image_error(const Film& test, const Film& ref);

/// The sums behind ImageError, one channel value at a time: image_error() and `candela compare`
/// add their channels through it, so the two give the same figures for the same values.
struct ErrorSums {
    double se = 0.0, rse = 0.0;
    double count = 0.0;
    void add(double test, double ref) {
        const double d = test - ref;
        se += d * d;
        rse += d * d / (ref * ref + kRelMseEps);
        count += 1.0;
    }
    ImageError error() const {
        return count > 0 ? ImageError{se / count, rse / count} : ImageError{};
    }
};

/// The reference's own expected error (same measures), estimated from its per-pixel variance of
/// the mean: E[(r - true)^2] = Var[r]. Needs the variance channel.
ImageError reference_error(const Film& ref);

/// One named sampling configuration; its spp (or time budget) is set by the sweep.
struct ConvergeConfig {
    std::string name;
    RenderSettings settings;
};

/// The configurations `candela converge` knows, each a variation of `base`: uniform (base),
/// nomis, hemisphere, sobol, light4, power, bvh, builtin, cs184, relative, and composites joined
/// by '+' (e.g. "relative+sobol"), whose parts are applied in order. Throws Error(Usage) on an
/// unknown or empty part, a part given twice, or two parts that set the same thing (cs184 and
/// relative both choose the adaptive sampling).
ConvergeConfig make_converge_config(const std::string& name, const RenderSettings& base);

/// The parts of a configuration name split at '+' ("relative+sobol" gives relative, sobol; a
/// plain name gives itself). Throws Error(Usage) on an empty part. Does not check the names.
std::vector<std::string> converge_config_parts(const std::string& name);

/// One point of the sweep: a configuration at one sample count (or time budget), over seeds.
struct ConvergeRow {
    std::string config;
    int spp = 0;                     ///< requested samples per pixel (the ladder rung)
    double mean_spp = 0.0;           ///< samples per pixel actually taken (adaptive, time budget)
    double seconds = 0.0;            ///< mean render time over seeds, by the chosen clock
    double seconds_std = 0.0;        ///< its standard error over the seeds (0 with one seed)
    double wall_seconds = 0.0;       ///< mean wall-clock render time (rendering only)
    double cpu_seconds = 0.0;        ///< mean CPU time of the process during the render
    double mse = 0.0, mse_std = 0.0; ///< mean over seeds and its standard error
    double rel_mse = 0.0, rel_mse_std = 0.0; ///< mean over seeds and its standard error
    /// 1 / (relMSE x seconds): higher is better; equal efficiency means equal error at equal
    /// time for estimators whose error falls as 1/time.
    double efficiency() const { return rel_mse > 0 && seconds > 0 ? 1.0 / (rel_mse * seconds) : 0; }
};

/// Renders `cfg` on `scene` once per seed (seeds 1..seeds) with `spp` samples per pixel, or with
/// cfg.settings.time_budget when that is set, and measures the error against `ref`. `seconds`
/// is CPU time when `cpu_clock` (robust on a machine shared with other work), else wall time.
ConvergeRow converge_point(const Scene& scene, const ConvergeConfig& cfg, int spp, int seeds,
                           const Film& ref, bool cpu_clock = false);

/// Renders the reference: base settings, `spp` samples, a seed no sweep render uses, with the
/// variance channel.
Film render_reference(const Scene& scene, const RenderSettings& base, int spp);

/// Least-squares slope of log(rel_mse or mse) against log(spp) over rows of one configuration.
double log_log_slope(const std::vector<ConvergeRow>& rows, bool use_mse);

/// Seconds at which configuration `config` reaches relMSE `target`, interpolated log-log
/// between its ladder points; a negative value when its ladder never reaches the target. When
/// `relative_std` is given it receives the relative standard error of that time, interpolated
/// the same way between the two points' render-time standard errors (0 with one seed).
double time_to_error(const std::vector<ConvergeRow>& rows, const std::string& config, double target,
                     double* relative_std = nullptr);

/// Renders shorter than this (seconds) are too short to time: starting the threads, the first
/// pass's cache misses and other processes' scheduler slices are a large share of them. 64x48
/// renders of a tenth of a second ranked one configuration at 2.52 and then 1.05 x uniform's
/// time a minute apart.
constexpr double kMinTimedRenderSeconds = 1.0;

/// A reference needs this many times the samples of the ladder's top rung: its variance is then
/// a sixteenth of the top rung's, and adds about 6 % to the relMSE measured there.
constexpr int kReferenceOverTopRung = 16;

/// Warning about the reference's sample count against the ladder (empty ladder: equal-time
/// mode, no warning): empty when ref_spp >= kReferenceOverTopRung x the top rung.
std::string reference_spp_warning(int ref_spp, const std::vector<int>& ladder);

/// Warning about renders shorter than kMinTimedRenderSeconds (empty when none is), naming the
/// shortest and how to make them longer.
std::string short_render_warning(const std::vector<ConvergeRow>& rows);

/// "+- 0.0012" for a standard error over `seeds` seeds; "(one seed: no spread)" for one seed,
/// where no spread was measured (a 0 there would read as an exact figure).
std::string spread_text(double std_err, int seeds);

/// CSV with header
/// `config,spp,mean_spp,seconds,wall_seconds,cpu_seconds,mse,mse_std,relmse,relmse_std,efficiency,
/// seconds_std` (efficiency from `seconds`).
/// Throws Error(Io).
void write_converge_csv(const std::string& path, const std::vector<ConvergeRow>& rows);

/// Log-log SVG plot of relMSE against seconds, one line per configuration, error bars of one
/// standard error, and a dashed line at the reference's own relMSE. Throws Error(Io).
void write_converge_svg(const std::string& path, const std::string& title,
                        const std::vector<ConvergeRow>& rows, double reference_rel_mse);

} // namespace candela
