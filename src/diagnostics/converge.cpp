// Error against run time for sampling configurations, against a high-sample reference.
#include "candela/diagnostics/converge.h"

#include "candela/accel/accel.h"
#include "candela/render/adaptive.h"
#include "candela/render/renderer.h"
#include "candela/util/check.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

namespace candela {

namespace {

/// Seed of the reference render: far from the sweep's seeds 1..seeds, so the reference is
/// independent of every measured render.
constexpr std::uint64_t kReferenceSeed = 0x5eed'0000'0000ull;
/// Samples per batch of the adaptive configurations (the CS184 default batch).
constexpr int kAdaptiveBatch = 32;
/// Tolerance of the cs184 configuration (the CS184 default).
constexpr float kCs184Tol = 0.05f;
/// Tolerance of the relative configuration: far below any error a sweep reaches, so the
/// sampler spends its whole budget and is compared at the same sample count as uniform.
constexpr float kRelativeTol = 1e-6f;

double mean_of(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v)
        s += x;
    return v.empty() ? 0.0 : s / double(v.size());
}

/// Standard error of the mean of v (0 with fewer than two values).
double std_err_of(const std::vector<double>& v) {
    if (v.size() < 2) return 0.0;
    double m = mean_of(v), s = 0.0;
    for (double x : v)
        s += (x - m) * (x - m);
    return std::sqrt(s / double(v.size() - 1) / double(v.size()));
}

} // namespace

ImageError image_error(const Film& t, const Film& r) {
    CANDELA_CHECK(t.width() == r.width() && t.height() == r.height(),
                  "image_error: films differ in size");
    ErrorSums sums;
    for (int y = 0; y < r.height(); ++y)
        for (int x = 0; x < r.width(); ++x) {
            Rgb a = t.mean(x, y), b = r.mean(x, y);
            for (int c = 0; c < 3; ++c)
                sums.add(double(a[c]), double(b[c]));
        }
    return sums.error();
}

ImageError reference_error(const Film& r) {
    CANDELA_CHECK(r.aovs().variance, "reference_error: the film has no variance channel");
    double se = 0.0, rse = 0.0;
    for (int y = 0; y < r.height(); ++y)
        for (int x = 0; x < r.width(); ++x) {
            Rgb v = r.variance_of_mean(x, y), b = r.mean(x, y);
            for (int c = 0; c < 3; ++c) {
                se += v[c];
                rse += v[c] / (double(b[c]) * b[c] + kRelMseEps);
            }
        }
    const double n = 3.0 * double(r.width()) * r.height();
    return {se / n, rse / n};
}

namespace {

/// Which setting a configuration part changes: two parts of one composite may not change the
/// same one.
enum class ConfigAxis {
    None,
    Mis,
    DirectLight,
    Sampler,
    LightSamples,
    LightChoice,
    Accel,
    Adaptive
};

const char* axis_name(ConfigAxis a) {
    switch (a) {
    case ConfigAxis::None:
        return "nothing";
    case ConfigAxis::Mis:
        return "MIS";
    case ConfigAxis::DirectLight:
        return "the direct-light strategy";
    case ConfigAxis::Sampler:
        return "the sampler";
    case ConfigAxis::LightSamples:
        return "the light samples";
    case ConfigAxis::LightChoice:
        return "the light choice";
    case ConfigAxis::Accel:
        return "the accelerator";
    case ConfigAxis::Adaptive:
        return "the adaptive sampling";
    }
    return "?";
}

constexpr const char* kConfigNames =
    "uniform, nomis, hemisphere, sobol, light4, power, bvh, builtin, cs184, relative, or several "
    "joined by '+'";

/// Applies one named part to `s` and returns the setting it changes; throws Error(Usage) on an
/// unknown name.
ConfigAxis apply_config_part(const std::string& name, const std::string& whole, RenderSettings& s) {
    if (name == "uniform") return ConfigAxis::None;
    if (name == "nomis") {
        s.mis = false;
        return ConfigAxis::Mis;
    }
    if (name == "hemisphere") {
        s.hemisphere = true;
        return ConfigAxis::DirectLight;
    }
    if (name == "sobol") {
        s.sampler = SamplerKind::Sobol;
        return ConfigAxis::Sampler;
    }
    if (name == "light4") {
        s.light_samples = 4;
        return ConfigAxis::LightSamples;
    }
    if (name == "power" || name == "bvh") {
        s.light_sampler = name == "power" ? LightSamplerKind::Power : LightSamplerKind::Bvh;
        return ConfigAxis::LightChoice;
    }
    if (name == "builtin") {
        s.accel.kind = AccelKind::Builtin;
        return ConfigAxis::Accel;
    }
    if (name == "cs184") {
        use_cs184_sampler(s, kAdaptiveBatch, kCs184Tol);
        return ConfigAxis::Adaptive;
    }
    if (name == "relative") {
        use_relative_sampler(s, kAdaptiveBatch, kRelativeTol);
        s.aovs = AovSet::parse("variance"); // per-channel error estimates (adaptive.h)
        return ConfigAxis::Adaptive;
    }
    throw Error(ErrorKind::Usage, "--configs: unknown configuration '" + name +
                                      (name == whole ? "" : "' in '" + whole) + "' (expected " +
                                      kConfigNames + ")");
}

} // namespace

std::vector<std::string> converge_config_parts(const std::string& name) {
    std::vector<std::string> parts = split_string(name, '+');
    for (const std::string& part : parts)
        if (part.empty())
            throw Error(ErrorKind::Usage, "--configs: empty part in configuration '" + name + "'");
    return parts;
}

ConvergeConfig make_converge_config(const std::string& name, const RenderSettings& base) {
    ConvergeConfig c{name, base};
    RenderSettings& s = c.settings;
    s.aovs = AovSet::parse("none");
    s.quiet = true;
    const std::vector<std::string> parts = converge_config_parts(name);
    std::vector<std::pair<std::string, ConfigAxis>> applied;
    for (const std::string& part : parts) {
        const ConfigAxis axis = apply_config_part(part, name, s);
        for (const auto& [prev, prev_axis] : applied) {
            if (prev == part)
                throw Error(ErrorKind::Usage,
                            "--configs: '" + part + "' appears twice in '" + name + "'");
            if (axis != ConfigAxis::None && prev_axis == axis)
                throw Error(ErrorKind::Usage, "--configs: '" + prev + "' and '" + part + "' in '" +
                                                  name + "' both set " + axis_name(axis) +
                                                  "; use one of them");
        }
        applied.emplace_back(part, axis);
    }
    return c;
}

Film render_reference(const Scene& scene, const RenderSettings& base, int spp) {
    RenderSettings s = base;
    s.spp = spp;
    s.seed = kReferenceSeed;
    s.aovs = AovSet::parse("variance");
    use_uniform_sampler(s);
    s.time_budget = 0.0;
    s.quiet = true;
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    Renderer r(scene, *accel, s);
    RenderStats stats;
    return r.render(stats);
}

ConvergeRow converge_point(const Scene& scene, const ConvergeConfig& cfg, int spp, int seeds,
                           const Film& ref, bool cpu_clock) {
    if (seeds < 1) throw Error(ErrorKind::Usage, "--seeds must be >= 1");
    std::unique_ptr<Accel> accel = make_accel(scene, cfg.settings.accel);
    std::vector<double> mse, rel, secs, cpu, taken;
    for (int seed = 1; seed <= seeds; ++seed) {
        RenderSettings s = cfg.settings;
        s.spp = spp;
        s.seed = std::uint64_t(seed);
        Renderer r(scene, *accel, s);
        RenderStats stats;
        const std::clock_t c0 = std::clock();
        Film f = r.render(stats);
        cpu.push_back(double(std::clock() - c0) / CLOCKS_PER_SEC);
        ImageError e = image_error(f, ref);
        mse.push_back(e.mse);
        rel.push_back(e.rel_mse);
        secs.push_back(stats.seconds);
        taken.push_back(double(f.total_samples() + f.total_dropped()) / double(f.pixel_count()));
    }
    ConvergeRow row;
    row.config = cfg.name;
    row.spp = spp;
    row.mean_spp = mean_of(taken);
    row.wall_seconds = mean_of(secs);
    row.cpu_seconds = mean_of(cpu);
    row.seconds = cpu_clock ? row.cpu_seconds : row.wall_seconds;
    row.seconds_std = std_err_of(cpu_clock ? cpu : secs);
    row.mse = mean_of(mse);
    row.mse_std = std_err_of(mse);
    row.rel_mse = mean_of(rel);
    row.rel_mse_std = std_err_of(rel);
    return row;
}

double log_log_slope(const std::vector<ConvergeRow>& rows, bool use_mse) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (const auto& r : rows) {
        double e = use_mse ? r.mse : r.rel_mse;
        if (!(e > 0.0) || r.spp < 1) continue;
        double x = std::log(double(r.spp)), y = std::log(e);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
        ++n;
    }
    CANDELA_CHECK(n >= 2, "log_log_slope: fewer than two points");
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

double time_to_error(const std::vector<ConvergeRow>& rows, const std::string& config, double target,
                     double* relative_std) {
    std::vector<const ConvergeRow*> pts;
    for (const auto& r : rows)
        if (r.config == config && r.rel_mse > 0 && r.seconds > 0) pts.push_back(&r);
    std::sort(pts.begin(), pts.end(),
              [](const ConvergeRow* a, const ConvergeRow* b) { return a->seconds < b->seconds; });
    auto rel = [](const ConvergeRow* p) { return p->seconds_std / p->seconds; };
    if (relative_std) *relative_std = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (pts[i]->rel_mse > target) continue;
        if (i == 0) { // already below at its cheapest point
            if (relative_std) *relative_std = rel(pts[0]);
            return pts[0]->seconds;
        }
        // Linear in log-log between the last point above and the first at or below.
        double x0 = std::log(pts[i - 1]->seconds), x1 = std::log(pts[i]->seconds);
        double y0 = std::log(pts[i - 1]->rel_mse), y1 = std::log(pts[i]->rel_mse);
        double t = (std::log(target) - y0) / (y1 - y0);
        if (relative_std) *relative_std = (1.0 - t) * rel(pts[i - 1]) + t * rel(pts[i]);
        return std::exp(x0 + t * (x1 - x0));
    }
    return -1.0;
}

std::string reference_spp_warning(int ref_spp, const std::vector<int>& ladder) {
    if (ladder.empty()) return "";
    const int top = *std::max_element(ladder.begin(), ladder.end());
    if (double(ref_spp) >= double(kReferenceOverTopRung) * double(top)) return "";
    return fmt::format("--ref-spp {} {} the ladder's top rung ({} spp): the reference is about "
                       "as noisy as the renders it judges there, so their relMSE measures the "
                       "reference's noise too; give --ref-spp {} or more ({} x the top rung)",
                       ref_spp,
                       ref_spp == top  ? "equals"
                       : ref_spp < top ? "is below"
                                       : "is not far above",
                       top, kReferenceOverTopRung * top, kReferenceOverTopRung);
}

std::string short_render_warning(const std::vector<ConvergeRow>& rows) {
    const ConvergeRow* shortest = nullptr;
    std::size_t short_rows = 0;
    for (const ConvergeRow& r : rows) {
        if (r.seconds >= kMinTimedRenderSeconds) continue;
        ++short_rows;
        if (!shortest || r.seconds < shortest->seconds) shortest = &r;
    }
    if (!shortest) return "";
    return fmt::format(
        "{} of {} points render in under {:.0f} s (the shortest: {} at {} spp, {:.3g} s), too "
        "short to time: their seconds, efficiencies and 'x uniform's time' ratios are mostly "
        "start-up and other processes' time; make the renders longer with a larger -r (e.g. -r "
        "256 192), a ladder of more samples (e.g. --ladder 64,256,1024) or --time-budget of "
        "{:.0f} s or more",
        short_rows, rows.size(), kMinTimedRenderSeconds, shortest->config, shortest->spp,
        shortest->seconds, kMinTimedRenderSeconds);
}

std::string spread_text(double std_err, int seeds) {
    if (seeds < 2) return "(one seed: no spread)";
    return fmt::format("+- {:.2g}", std_err);
}

void write_converge_csv(const std::string& path, const std::vector<ConvergeRow>& rows) {
    std::ofstream out(path);
    if (!out) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write");
    out << "config,spp,mean_spp,seconds,wall_seconds,cpu_seconds,mse,mse_std,relmse,relmse_std,"
           "efficiency,seconds_std\n";
    for (const auto& r : rows)
        out << fmt::format("{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},"
                           "{:.6g}\n",
                           r.config, r.spp, r.mean_spp, r.seconds, r.wall_seconds, r.cpu_seconds,
                           r.mse, r.mse_std, r.rel_mse, r.rel_mse_std, r.efficiency(),
                           r.seconds_std);
    if (!out) throw Error(ErrorKind::Io, SourceLoc{path}, "write failed");
}

void write_converge_svg(const std::string& path, const std::string& title,
                        const std::vector<ConvergeRow>& rows, double reference_rel_mse) {
    // Plot area in SVG user units.
    const double W = 720, H = 480, left = 80, right = 170, top = 40, bottom = 60;
    const double pw = W - left - right, ph = H - top - bottom;
    double tmin = 1e300, tmax = -1e300, emin = 1e300, emax = -1e300;
    for (const auto& r : rows) {
        if (!(r.seconds > 0) || !(r.rel_mse > 0)) continue;
        tmin = std::min(tmin, r.seconds);
        tmax = std::max(tmax, r.seconds);
        emin = std::min(emin, std::max(r.rel_mse - r.rel_mse_std, r.rel_mse * 0.5));
        emax = std::max(emax, r.rel_mse + r.rel_mse_std);
    }
    if (reference_rel_mse > 0) emin = std::min(emin, reference_rel_mse);
    CANDELA_CHECK(tmin <= tmax, "write_converge_svg: no data to plot");
    // Whole decades around the data.
    const double lx0 = std::floor(std::log10(tmin)), lx1 = std::ceil(std::log10(tmax) + 1e-9);
    const double ly0 = std::floor(std::log10(emin)), ly1 = std::ceil(std::log10(emax) + 1e-9);
    auto X = [&](double t) { return left + pw * (std::log10(t) - lx0) / std::max(1.0, lx1 - lx0); };
    auto Y = [&](double e) {
        return top + ph * (1.0 - (std::log10(e) - ly0) / std::max(1.0, ly1 - ly0));
    };
    static const char* const colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                          "#9467bd", "#8c564b", "#e377c2", "#17becf"};
    std::ostringstream s;
    s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << left + pw / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">"
      << title << "</text>\n";
    for (double d = lx0; d <= lx1 + 1e-9; d += 1) {
        double x = X(std::pow(10.0, d));
        s << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + ph
          << "\" stroke=\"#ddd\"/><text x=\"" << x << "\" y=\"" << top + ph + 16
          << "\" text-anchor=\"middle\">1e" << int(d) << "</text>\n";
    }
    for (double d = ly0; d <= ly1 + 1e-9; d += 1) {
        double y = Y(std::pow(10.0, d));
        s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + pw << "\" y2=\"" << y
          << "\" stroke=\"#ddd\"/><text x=\"" << left - 6 << "\" y=\"" << y + 4
          << "\" text-anchor=\"end\">1e" << int(d) << "</text>\n";
    }
    s << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << pw << "\" height=\"" << ph
      << "\" fill=\"none\" stroke=\"black\"/>\n"
      << "<text x=\"" << left + pw / 2 << "\" y=\"" << H - 15
      << "\" text-anchor=\"middle\">render time (s)</text>\n"
      << "<text transform=\"translate(20," << top + ph / 2
      << ") rotate(-90)\" text-anchor=\"middle\">relMSE</text>\n";
    if (reference_rel_mse > 0) {
        double y = Y(reference_rel_mse);
        s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + pw << "\" y2=\"" << y
          << "\" stroke=\"black\" stroke-dasharray=\"6,4\"/><text x=\"" << left + pw + 6
          << "\" y=\"" << y + 4 << "\">reference</text>\n";
    }
    std::vector<std::string> names;
    for (const auto& r : rows)
        if (std::find(names.begin(), names.end(), r.config) == names.end())
            names.push_back(r.config);
    for (std::size_t k = 0; k < names.size(); ++k) {
        const char* col = colours[k % (sizeof colours / sizeof *colours)];
        std::vector<const ConvergeRow*> pts;
        for (const auto& r : rows)
            if (r.config == names[k] && r.seconds > 0 && r.rel_mse > 0) pts.push_back(&r);
        std::sort(pts.begin(), pts.end(), [](const ConvergeRow* a, const ConvergeRow* b) {
            return a->seconds < b->seconds;
        });
        s << "<polyline fill=\"none\" stroke=\"" << col << "\" stroke-width=\"1.5\" points=\"";
        for (const auto* p : pts)
            s << X(p->seconds) << "," << Y(p->rel_mse) << " ";
        s << "\"/>\n";
        for (const auto* p : pts) {
            double x = X(p->seconds);
            double lo = std::max(p->rel_mse - p->rel_mse_std, p->rel_mse * 0.5);
            s << "<circle cx=\"" << x << "\" cy=\"" << Y(p->rel_mse) << "\" r=\"3\" fill=\"" << col
              << "\"/><line x1=\"" << x << "\" y1=\"" << Y(lo) << "\" x2=\"" << x << "\" y2=\""
              << Y(p->rel_mse + p->rel_mse_std) << "\" stroke=\"" << col << "\"/>\n";
        }
        double ly = top + 10 + 18 * double(k);
        s << "<line x1=\"" << left + pw + 10 << "\" y1=\"" << ly << "\" x2=\"" << left + pw + 34
          << "\" y2=\"" << ly << "\" stroke=\"" << col << "\" stroke-width=\"2\"/><text x=\""
          << left + pw + 40 << "\" y=\"" << ly + 4 << "\">" << names[k] << "</text>\n";
    }
    s << "</svg>\n";
    std::ofstream out(path);
    if (!out) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write");
    out << s.str();
    if (!out) throw Error(ErrorKind::Io, SourceLoc{path}, "write failed");
}

} // namespace candela
