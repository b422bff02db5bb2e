// `candela converge SCENE` (or `--procedural SPEC`): error against run time for the sampling
// configurations, measured against a cached high-sample reference (diagnostics/converge.h).
#include "commands.h"
#include "output_paths.h"

#include "candela/app/cli.h"
#include "candela/diagnostics/converge.h"
#include "candela/io/collada.h"
#include "candela/render/checkpoint.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/strings.h"

#include "scene_source.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <utility>

namespace candela::app {

namespace {

struct ConvergeArgs {
    std::string scene;
    std::string procedural; ///< --procedural SPEC instead of a scene file
    std::vector<int> resolution{64, 48};
    std::vector<int> ladder{4, 16, 64, 256};
    int seeds = 3;
    int ref_spp = 4096;
    int max_depth = 8;
    int threads = 0;
    std::string configs = "uniform,nomis,hemisphere,sobol,light4,builtin,cs184,relative";
    std::string cache = ".candela-cache";
    std::string output = "converge";
    std::vector<double> time_budgets;
    std::string clock = "wall";
    bool quiet = false;
    LogArgs log;
};

std::vector<std::string> split_list(const std::string& list) {
    std::vector<std::string> out;
    for (std::string& item : split_string(list, ','))
        if (!item.empty()) out.push_back(std::move(item));
    return out;
}

/// 64-bit FNV-1a of a string (the cache key of a reference).
std::uint64_t hash_string(const std::string& s, std::uint64_t h) {
    for (unsigned char c : s) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

/// The scene as the summary names it: its file, or the procedural spec.
std::string scene_name(const ConvergeArgs& a) {
    return a.procedural.empty() ? a.scene : "procedural " + a.procedural;
}

/// The reference for (scene file, settings, spp): from the cache when present, else rendered
/// and stored.
Film cached_reference(const ConvergeArgs& a, const Scene& scene, const RenderSettings& base,
                      std::string& note) {
    namespace fs = std::filesystem;
    std::ostringstream key;
    key << "v2 " << base.width << "x" << base.height << " spp " << a.ref_spp << " m "
        << base.max_depth << " rr " << base.rr_min_depth << " l " << base.light_samples;
    // The scene's part of the key: its file's bytes, or the spec that builds it.
    const std::uint64_t scene_key = a.procedural.empty()
                                        ? file_hash(a.scene)
                                        : hash_string("procedural " + a.procedural,
                                                      0xcbf29ce484222325ull); // FNV offset basis
    std::uint64_t h = hash_string(key.str(), scene_key);
    fs::path path = fs::path(a.cache) / fmt::format("ref-{:016x}.film", h);
    if (fs::exists(path)) {
        std::ifstream in(path, std::ios::binary);
        Film f = Film::read(in);
        if (f.width() == base.width && f.height() == base.height && f.aovs().variance) {
            note = "reused " + path.string();
            return f;
        }
    }
    Film f = render_reference(scene, base, a.ref_spp);
    std::error_code ec;
    fs::create_directories(a.cache, ec);
    std::ofstream out(path, std::ios::binary);
    if (!out) throw Error(ErrorKind::Io, SourceLoc{path.string()}, "cannot write the cache");
    f.write(out);
    note = "rendered and cached in " + path.string();
    return f;
}

/// The render settings every configuration starts from, after checking the arguments (before
/// anything is loaded or rendered).
RenderSettings converge_base(const ConvergeArgs& a) {
    if (a.resolution.size() != 2 || a.resolution[0] < 1 || a.resolution[1] < 1)
        throw Error(ErrorKind::Usage, "-r/--resolution needs two sizes >= 1");
    if (a.seeds < 1) throw Error(ErrorKind::Usage, "--seeds must be >= 1");
    if (a.ref_spp < 1) throw Error(ErrorKind::Usage, "--ref-spp must be >= 1");
    for (int s : a.ladder)
        if (s < 1) throw Error(ErrorKind::Usage, "--ladder entries must be >= 1");
    for (double t : a.time_budgets)
        if (!(t > 0.0)) throw Error(ErrorKind::Usage, "--time-budget must be > 0");
    RenderSettings base;
    base.width = a.resolution[0];
    base.height = a.resolution[1];
    base.max_depth = a.max_depth;
    base.threads = a.threads;
    base.quiet = true;
    if (a.clock != "wall" && a.clock != "cpu")
        throw Error(ErrorKind::Usage, "--clock must be wall or cpu");
    return base;
}

/// The scene, the three outputs and the reference cache, checked before the scene is loaded and
/// before the (possibly long) reference render.
void check_converge_files(const ConvergeArgs& a) {
    if (a.procedural.empty()) check_scene_file(a.scene);
    std::vector<NamedPath> outputs;
    for (const char* suffix : {".csv", ".svg", "_summary.txt"})
        outputs.push_back({std::string("-o/--output's ") + suffix, a.output + suffix});
    std::vector<NamedPath> inputs;
    if (a.procedural.empty()) inputs.push_back({"the scene file", a.scene});
    check_distinct_files(inputs, outputs);
    for (const NamedPath& out : outputs)
        check_image_writable(out.path, OutputKind::Unsupported);
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(a.cache, ec) && !fs::is_directory(a.cache, ec))
        throw Error(ErrorKind::Io, SourceLoc{a.cache}, "--cache: not a directory");
}

/// Every configuration at every rung of the spp ladder (or time budget), sorted by
/// configuration in the order they were named.
std::vector<ConvergeRow> run_ladder(const ConvergeArgs& a, const Scene& scene,
                                    std::vector<ConvergeConfig>& cfgs,
                                    const std::vector<std::string>& names, const Film& ref) {
    const bool cpu_clock = a.clock == "cpu";
    // Configurations are interleaved rung by rung, so that a slow spell of a shared machine
    // falls on all of them alike; the rows are then sorted by configuration.
    std::vector<ConvergeRow> rows;
    // Equal time: the sample cap never binds, the budget does.
    constexpr int kEqualTimeSppCap = 1 << 20;
    const bool equal_time = !a.time_budgets.empty();
    const std::size_t rungs = equal_time ? a.time_budgets.size() : a.ladder.size();
    for (std::size_t k = 0; k < rungs; ++k)
        for (ConvergeConfig& cfg : cfgs) {
            int spp = equal_time ? kEqualTimeSppCap : a.ladder[k];
            if (equal_time) cfg.settings.time_budget = a.time_budgets[k];
            rows.push_back(converge_point(scene, cfg, spp, a.seeds, ref, cpu_clock));
            const ConvergeRow& r = rows.back();
            if (!a.quiet)
                fmt::print(stderr,
                           "converge: {:<10} {:8.1f} spp {:9.3f}s (wall {:.3f}s cpu {:.3f}s) "
                           "relMSE {:.4g} "
                           "{}\n",
                           cfg.name, r.mean_spp, r.seconds, r.wall_seconds, r.cpu_seconds,
                           r.rel_mse, spread_text(r.rel_mse_std, a.seeds));
        }
    std::stable_sort(rows.begin(), rows.end(), [&](const ConvergeRow& x, const ConvergeRow& y) {
        auto ix = std::find(names.begin(), names.end(), x.config) - names.begin();
        auto iy = std::find(names.begin(), names.end(), y.config) - names.begin();
        return ix < iy;
    });
    return rows;
}

/// The row of configuration `config` with the lowest relMSE (one exists).
const ConvergeRow* lowest_error(const std::vector<ConvergeRow>& rows, const std::string& config) {
    const ConvergeRow* low = nullptr;
    for (const ConvergeRow& r : rows)
        if (r.config == config && (!low || r.rel_mse < low->rel_mse)) low = &r;
    return low;
}

/// The sweep's sample ladder; empty in equal-time mode, which has none.
std::vector<int> sample_ladder(const ConvergeArgs& a) {
    return a.time_budgets.empty() ? a.ladder : std::vector<int>{};
}

/// A ratio of two render times with its standard error from the seeds' render times, or the
/// ratio and the time it is of with "one seed: no spread" when there is no second seed.
std::string time_ratio_text(double ratio, double relative_std, const std::string& baseline,
                            double baseline_seconds, int seeds) {
    if (seeds < 2)
        return fmt::format("{:.2f} x {}'s {:.3f}s (one seed: no spread)", ratio, baseline,
                           baseline_seconds);
    return fmt::format("{:.2f} {} x {}'s {:.3f}s", ratio, spread_text(ratio * relative_std, seeds),
                       baseline, baseline_seconds);
}

/// The summary text: the run's settings, its warnings, each configuration's last point and
/// efficiency, and the time-to-error comparisons.
std::string converge_summary(const ConvergeArgs& a, const RenderSettings& base,
                             const std::vector<std::string>& names,
                             const std::vector<ConvergeRow>& rows, const ImageError& ref_err) {
    std::ostringstream sum;
    sum << fmt::format("scene {}, {}x{}, max depth {}, {} seeds, {} clock\n"
                       "reference: {} spp; its estimated error MSE {:.4g}, relMSE {:.4g}\n",
                       scene_name(a), base.width, base.height, base.max_depth, a.seeds, a.clock,
                       a.ref_spp, ref_err.mse, ref_err.rel_mse);
    for (const std::string& w :
         {reference_spp_warning(a.ref_spp, sample_ladder(a)), short_render_warning(rows)})
        if (!w.empty()) sum << "warning: " << w << "\n";
    // The render times' standard error of each time ratio: relative errors add in quadrature.
    auto ratio_std = [](double rel_t, const ConvergeRow& b) {
        const double rel_b = b.seconds > 0.0 ? b.seconds_std / b.seconds : 0.0;
        return std::sqrt(rel_t * rel_t + rel_b * rel_b);
    };
    // Per configuration: its last point (largest spp or budget) and efficiency there.
    const ConvergeRow* best = nullptr;
    for (const std::string& n : names) {
        const ConvergeRow* last = nullptr;
        std::vector<ConvergeRow> mine;
        for (const auto& r : rows)
            if (r.config == n) {
                last = &r;
                mine.push_back(r);
            }
        if (!last) continue;
        double slope = 0.0;
        if (mine.size() >= 2 && a.time_budgets.empty()) slope = log_log_slope(mine, false);
        sum << fmt::format("{:<10} last point: {:8.1f} spp {:8.3f}s relMSE {:.4g} {}  efficiency "
                           "{:.4g}  slope(log relMSE / log spp) {:.3f}\n",
                           n, last->mean_spp, last->seconds, last->rel_mse,
                           spread_text(last->rel_mse_std, a.seeds), last->efficiency(), slope);
        if (!best || last->efficiency() > best->efficiency()) best = last;
    }
    if (best) sum << "most efficient at the last point: " << best->config << "\n";
    // Time-to-error: each configuration against uniform's error at uniform's largest rung, and
    // each composite against every configuration of the run that lacks exactly one of its
    // parts (relative+sobol against sobol and against relative).
    auto last_of = [&](const std::string& n) {
        const ConvergeRow* last = nullptr;
        for (const auto& r : rows)
            if (r.config == n) last = &r;
        return last;
    };
    auto compare = [&](const std::string& n, const std::string& baseline) {
        const ConvergeRow* b = last_of(baseline);
        if (!b || !last_of(n)) return;
        double rel_t = 0.0;
        double t = time_to_error(rows, n, b->rel_mse, &rel_t);
        if (t > 0)
            sum << fmt::format("{} reaches {}'s relMSE at {} spp ({:.4g}) in {:.3f}s = {}\n", n,
                               baseline, b->spp, b->rel_mse, t,
                               time_ratio_text(t / b->seconds, ratio_std(rel_t, *b), baseline,
                                               b->seconds, a.seeds));
        else if (const ConvergeRow* low = lowest_error(rows, n);
                 low->rel_mse - b->rel_mse <= std::max(low->rel_mse_std, b->rel_mse_std))
            // Within the estimates' standard errors: the same error, not a miss.
            sum << fmt::format("{} matches {}'s relMSE at {} spp ({:.4g}) at its lowest ({:.4g}, "
                               "within the standard error {:.2g}) in {:.3f}s = {}\n",
                               n, baseline, b->spp, b->rel_mse, low->rel_mse,
                               std::max(low->rel_mse_std, b->rel_mse_std), low->seconds,
                               time_ratio_text(low->seconds / b->seconds,
                                               ratio_std(low->seconds_std / low->seconds, *b),
                                               baseline, b->seconds, a.seeds));
        else
            sum << fmt::format("{} does not reach {}'s relMSE at {} spp ({:.4g}) on its ladder "
                               "(its lowest: {:.4g})\n",
                               n, baseline, b->spp, b->rel_mse, low->rel_mse);
    };
    if (a.time_budgets.empty())
        for (const std::string& n : names) {
            if (n == "uniform") continue;
            compare(n, "uniform");
            const std::vector<std::string> parts = converge_config_parts(n);
            if (parts.size() < 2) continue;
            for (const std::string& m : names) {
                if (m == "uniform" || m == n) continue;
                std::vector<std::string> sub = converge_config_parts(m);
                if (sub.size() + 1 != parts.size()) continue;
                bool subset = true;
                for (const std::string& p : sub)
                    subset &= std::find(parts.begin(), parts.end(), p) != parts.end();
                if (subset) compare(n, m);
            }
        }
    return sum.str();
}

int run_converge(ConvergeArgs& a) {
    set_log_level(log_level_of(a.log));
    a.quiet = log_level() < LogLevel::Info;
    const RenderSettings base = converge_base(a);
    const std::vector<std::string> names = split_list(a.configs);
    if (names.empty()) throw Error(ErrorKind::Usage, "--configs: no configuration given");
    std::vector<ConvergeConfig> cfgs;
    for (const std::string& n : names)
        cfgs.push_back(make_converge_config(n, base));
    check_converge_files(a);

    // Said before the reference render, which may be long.
    const std::string ref_warning = reference_spp_warning(a.ref_spp, sample_ladder(a));
    if (!ref_warning.empty()) print_warning(ref_warning, "converge");

    Scene scene = load_scene_or_procedural(a.scene, a.procedural, false);

    std::string note;
    Film ref = cached_reference(a, scene, base, note);
    ImageError ref_err = reference_error(ref);
    if (!a.quiet)
        fmt::print(stderr,
                   "converge: reference {} spp ({}); its own error: MSE {:.3g} relMSE {:.3g}\n",
                   a.ref_spp, note, ref_err.mse, ref_err.rel_mse);

    const std::vector<ConvergeRow> rows = run_ladder(a, scene, cfgs, names, ref);
    const std::string timing_warning = short_render_warning(rows);
    if (!timing_warning.empty()) print_warning(timing_warning, "converge");

    const std::string csv = a.output + ".csv", svg = a.output + ".svg",
                      txt = a.output + "_summary.txt";
    write_converge_csv(csv, rows);
    std::string title = (a.procedural.empty() ? std::filesystem::path(a.scene).filename().string()
                                              : scene_name(a)) +
                        " " + std::to_string(base.width) + "x" + std::to_string(base.height);
    write_converge_svg(svg, title, rows, ref_err.rel_mse);
    const std::string sum = converge_summary(a, base, names, rows, ref_err);
    std::ofstream out(txt);
    if (!out) throw Error(ErrorKind::Io, SourceLoc{txt}, "cannot write");
    out << sum;
    // The summary is the command's result, on stdout even under -q; the files written are a
    // note on stderr.
    std::fputs(sum.c_str(), stdout);
    if (!a.quiet) fmt::print(stderr, "converge: wrote {}, {}, {}\n", csv, svg, txt);
    return 0;
}

} // namespace

void add_converge_command(CLI::App& app, int* status) {
    auto a = std::make_shared<ConvergeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "converge", "Error against run time: render a cached high-sample reference, then a sweep "
                    "of sampling configurations over a sample ladder and several seeds; write "
                    "PREFIX.csv, PREFIX.svg (log-log relMSE vs seconds) and PREFIX_summary.txt");
    cmd->add_option("scene", a->scene, "COLLADA scene file (.dae)");
    cmd->add_option("--procedural", a->procedural,
                    "Generated scene instead (scene/procedural.h), e.g. nearwall:200 or "
                    "inpanel:60 (many-light scenes for the light tree)");
    cmd->add_option("-r,--resolution", a->resolution, "Image width and height")
        ->expected(2)
        ->capture_default_str();
    cmd->add_option("--ladder", a->ladder, "Samples per pixel of the sweep")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--seeds", a->seeds, "Renders per point (seeds 1..N)")->capture_default_str();
    cmd->add_option("--ref-spp", a->ref_spp, "Samples per pixel of the reference")
        ->capture_default_str();
    cmd->add_option("-m,--max-depth", a->max_depth, "Maximum scattering events")
        ->capture_default_str();
    cmd->add_option("-t,--threads", a->threads, "Worker threads; 0 = all cores")
        ->capture_default_str();
    cmd->add_option("--configs", a->configs,
                    "Comma list of configurations: uniform, nomis, hemisphere, sobol, light4, "
                    "power, bvh (--light-sampler), "
                    "builtin, cs184, relative, or composites joined by '+' that apply each "
                    "part in order (e.g. relative+sobol, cs184+sobol, uniform+builtin; two "
                    "parts may not set the same thing, as cs184+relative would)")
        ->capture_default_str();
    cmd->add_option("--cache", a->cache, "Directory of cached references")->capture_default_str();
    cmd->add_option("-o,--output", a->output,
                    "Output prefix: writes PREFIX.csv, PREFIX.svg and PREFIX_summary.txt")
        ->capture_default_str();
    cmd->add_option("--time-budget", a->time_budgets,
                    "Equal-time mode: render each configuration for these SECONDS (comma list) "
                    "instead of the sample ladder")
        ->delimiter(',');
    cmd->add_option("--clock", a->clock,
                    "Time each render by wall clock (wall) or by the process's CPU time (cpu: "
                    "robust when the machine is shared with other work)")
        ->capture_default_str();
    add_log_options(*cmd, a->log);
    cmd->callback([a, status] { *status = run_converge(*a); });
}

} // namespace candela::app
