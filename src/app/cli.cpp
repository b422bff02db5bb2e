#include "candela/app/cli.h"

#include "candela/io/envmap_file.h"
#include "candela/render/checkpoint.h"
#include "candela/render/exr_layout.h"
#include "candela/render/memory_budget.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <sstream>

namespace candela {

namespace {

namespace fs = std::filesystem;

/// Largest accepted image edge: far above any real frame, far below sizes whose film (about
/// 100 bytes per pixel with every channel) would not fit in memory.
constexpr int kMaxImageEdge = 32768;
/// Largest accepted pixel count (256 Mpixel).
constexpr long long kMaxPixels = 1ll << 28;
constexpr int kMaxThreads = 4096;
constexpr int kMaxDepth = 1 << 16;
/// Seeds and sample indices are written to the EXR as int attributes (typed, README "EXR
/// metadata"), so they stay below 2^31.
constexpr long long kMaxIndex = INT_MAX;

[[noreturn]] void usage(const std::string& what) {
    throw Error(ErrorKind::Usage, "error: " + what);
}

std::string absolute_path(const std::string& p) {
    if (p.empty()) return p;
    std::error_code ec;
    fs::path a = fs::absolute(p, ec);
    if (ec) return p;
    return a.lexically_normal().string();
}

/// One render option as the checkpoint and the resume check see it: its values in canonical
/// form, and whether it may change on --resume.
struct OptionSpec {
    const char* name;    ///< CLI11 name: the long form, or "scene"
    const char* display; ///< as messages show it, e.g. "-s/--spp"
    bool runtime;        ///< changes how or where the render runs, never its pixels
    std::function<std::vector<std::string>(const RenderArgs&)> values;
};

/// A choice option's value as given: its name, or the unknown value finalize_render_args reports.
template <typename E, std::size_t N>
std::vector<std::string> choice(const RenderArgs& a, const std::string& flag,
                                const EnumTable<E, N>& table, E value) {
    const auto it = a.unknown_choices.find(flag);
    return {it != a.unknown_choices.end() ? it->second : std::string(enum_name(table, value))};
}

/// Throws the error of a choice option whose value names none of its choices.
template <typename E, std::size_t N>
void check_choice(const RenderArgs& a, const std::string& flag, const EnumTable<E, N>& table) {
    const auto it = a.unknown_choices.find(flag);
    if (it != a.unknown_choices.end()) throw_unknown_choice(flag, it->second, enum_names(table));
}

/// Declares the choice option `flag`, parsed by `table` into `target`; a value that names no
/// choice is kept in args.unknown_choices for finalize_render_args to report.
template <typename E, std::size_t N>
CLI::Option* add_choice(CLI::App& app, RenderArgs& a, const std::string& flag,
                        const EnumTable<E, N>& table, E& target, const std::string& help) {
    return app.add_option_function<std::string>(
        flag,
        [&a, &table, &target, flag](const std::string& v) {
            if (const std::optional<E> e = find_enum(table, v)) {
                target = *e;
                a.unknown_choices.erase(flag);
            } else {
                a.unknown_choices[flag] = v;
            }
        },
        help);
}

/// Declares an option holding a seed or a sample index: a whole number >= 0, read as a signed
/// number so that a negative one is named as given (not wrapped around to 2^64 - 1).
CLI::Option* add_index_option(CLI::App& app, const std::string& flag, std::uint64_t& target,
                              const std::string& help) {
    return app
        .add_option_function<long long>(
            flag,
            [&target, flag](const long long& v) {
                if (v < 0)
                    usage(flag + ": " + std::to_string(v) + " is out of range [0, " +
                          std::to_string(kMaxIndex) + "]");
                target = std::uint64_t(v);
            },
            help)
        ->default_str(std::to_string(target));
}

template <typename T> std::vector<std::string> one(const T& v) {
    if constexpr (std::is_same_v<T, std::string>)
        return {v};
    else if constexpr (std::is_floating_point_v<T>)
        return {fmt::format("{:.9g}", double(v))};
    else
        return {std::to_string(v)};
}

const std::vector<OptionSpec>& option_specs() {
    using V = std::vector<std::string>;
    using A = const RenderArgs&;
    static const std::vector<OptionSpec> specs = {
        {"scene", "SCENE", false, [](A a) { return V{absolute_path(a.scene)}; }},
        {"--output", "-f/--output", false, [](A a) { return V{absolute_path(a.output)}; }},
        {"--spp", "-s/--spp", false, [](A a) { return one(a.settings.spp); }},
        {"--light-samples", "-l/--light-samples", false,
         [](A a) { return one(a.settings.light_samples); }},
        {"--threads", "-t/--threads", true, [](A a) { return one(a.settings.threads); }},
        {"--max-depth", "-m/--max-depth", false, [](A a) { return one(a.settings.max_depth); }},
        {"--accumulate", "-o/--accumulate", false, [](A a) { return one(a.accumulate); }},
        {"--env", "-e/--env", false, [](A a) { return V{absolute_path(a.env_map)}; }},
        {"--lens-radius", "-b/--lens-radius", false,
         [](A a) { return a.lens_radius ? one(*a.lens_radius) : V{""}; }},
        {"--focal-distance", "-d/--focal-distance", false,
         [](A a) { return a.focal_distance ? one(*a.focal_distance) : V{""}; }},
        {"--resolution", "-r/--resolution", false,
         [](A a) {
             return a.resolution.size() == 2
                        ? V{std::to_string(a.resolution[0]), std::to_string(a.resolution[1])}
                        : V{"800", "600"};
         }},
        {"--region", "-p/--region", false,
         [](A a) {
             V v;
             for (int x : a.region)
                 v.push_back(std::to_string(x));
             return v;
         }},
        {"--camera-file", "-c/--camera-file", false,
         [](A a) { return V{absolute_path(a.camera_file)}; }},
        {"--adaptive-sampling", "-a/--adaptive-sampling", false,
         [](A a) {
             V v;
             for (double x : a.adaptive)
                 v.push_back(fmt::format("{:.9g}", x));
             return v;
         }},
        {"--hemisphere", "-H/--hemisphere", false,
         [](A a) { return a.settings.hemisphere ? V{} : V{"off"}; }},
        {"--adaptive", "--adaptive", false,
         [](A a) {
             return a.adaptive_kind ? choice(a, "--adaptive", kAdaptiveKinds, *a.adaptive_kind)
                                    : choice(a, "--adaptive", kAdaptiveKinds, AdaptiveKind::None);
         }},
        {"--noise-threshold", "--noise-threshold", false,
         [](A a) { return one(a.noise_threshold); }},
        {"--time-budget", "--time-budget", false, [](A a) { return one(a.settings.time_budget); }},
        {"--camera", "--camera", false,
         [](A a) { return choice(a, "--camera", kCameraModes, a.build.camera_mode); }},
        {"--accel", "--accel", false,
         [](A a) { return choice(a, "--accel", kAccelKinds, a.settings.accel.kind); }},
        {"--triangle", "--triangle", false,
         [](A a) { return choice(a, "--triangle", kTriangleTests, a.settings.accel.triangle); }},
        {"--embree-robust", "--embree-robust", false,
         [](A a) { return a.embree_robust ? V{} : V{"off"}; }},
        {"--embree-quality", "--embree-quality", false,
         [](A a) {
             return choice(a, "--embree-quality", kEmbreeQualities, a.settings.accel.quality);
         }},
        {"--seed", "--seed", false, [](A a) { return one(a.settings.seed); }},
        {"--sample-offset", "--sample-offset", false,
         [](A a) { return one(a.settings.sample_offset); }},
        {"--sampler", "--sampler", false,
         [](A a) { return choice(a, "--sampler", kSamplerKinds, a.settings.sampler); }},
        {"--light-sampler", "--light-sampler", false,
         [](A a) {
             return choice(a, "--light-sampler", kLightSamplerKinds, a.settings.light_sampler);
         }},
        {"--integrator", "--integrator", false,
         [](A a) { return choice(a, "--integrator", kIntegratorKinds, a.settings.integrator); }},
        {"--light-paths", "--light-paths", false,
         [](A a) { return choice(a, "--light-paths", kLightPaths, a.settings.light_paths); }},
        {"--no-mis", "--no-mis", false, [](A a) { return a.no_mis ? V{} : V{"off"}; }},
        {"--rr-depth", "--rr-depth", false, [](A a) { return one(a.settings.rr_min_depth); }},
        {"--aov", "--aov", false, [](A a) { return one(a.aov); }},
        {"--half", "--half", false, [](A a) { return a.half ? V{} : V{"off"}; }},
        {"--compression", "--compression", false, [](A a) { return one(a.compression); }},
        {"--background-depth", "--background-depth", false,
         [](A a) { return one(a.background_depth); }},
        {"--preview", "--preview", false, [](A a) { return a.preview ? V{} : V{"off"}; }},
        {"--tonemap", "--tonemap", false,
         [](A a) { return choice(a, "--tonemap", kTonemaps, a.tonemap); }},
        {"--exposure", "--exposure", false, [](A a) { return one(a.exposure); }},
        {"--look", "--look", false, [](A a) { return choice(a, "--look", kLooks, a.look); }},
        {"--pass-spp", "--pass-spp", false, [](A a) { return one(a.settings.pass_spp); }},
        {"--strict", "--strict", true, [](A a) { return a.strict ? V{} : V{"off"}; }},
        {"--quiet", "-q/--quiet", true, [](A) { return V{}; }},
        {"--verbose", "-v/--verbose", true, [](A) { return V{}; }},
        {"--log-level", "--log-level", true, [](A a) { return one(a.log.level); }},
        {"--progress", "--progress", true,
         [](A a) { return choice(a, "--progress", kProgressModes, a.settings.progress); }},
        {"--checkpoint", "--checkpoint", true, [](A a) { return V{absolute_path(a.checkpoint)}; }},
        {"--checkpoint-every", "--checkpoint-every", true,
         [](A a) { return one(a.checkpoint_every); }},
        {"--max-memory", "--max-memory", true, [](A a) { return one(a.max_memory); }},
        {"--resume", "--resume", true, [](A a) { return V{absolute_path(a.resume)}; }},
        {"--keep-checkpoint", "--keep-checkpoint", true,
         [](A a) { return a.keep_checkpoint ? V{} : V{"off"}; }},
    };
    return specs;
}

const OptionSpec* find_spec(const std::string& name) {
    for (const OptionSpec& s : option_specs())
        if (name == s.name) return &s;
    return nullptr;
}

/// Flags without a value in the canonical list (their value vector is empty when set).
bool is_flag(const std::string& name) {
    return name == "--hemisphere" || name == "--embree-robust" || name == "--no-mis" ||
           name == "--half" || name == "--preview" || name == "--strict" || name == "--quiet" ||
           name == "--verbose" || name == "--keep-checkpoint";
}

std::string quoted_list(const std::vector<std::string>& v) {
    if (v.empty()) return "on";
    std::string s;
    for (const std::string& x : v)
        s += (s.empty() ? "" : " ") + (x.empty() ? std::string("(unset)") : x);
    return s;
}

/// A plain file (the checkpoint) can be created at `path`: its directory exists and is
/// writable, and `path` is not a directory.
void check_file_writable(const std::string& path, const std::string& what) {
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw Error(ErrorKind::Io,
                    path + ": error: cannot write the " + what + ": it is a directory");
    const fs::path parent = fs::path(path).parent_path();
    const std::string dir = parent.empty() ? std::string(".") : parent.string();
    if (!fs::is_directory(dir, ec))
        throw Error(ErrorKind::Io, path + ": error: cannot write the " + what + ": directory '" +
                                       dir + "' does not exist");
    const std::string probe = temp_path_for(path);
    std::FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f)
        throw Error(ErrorKind::Io, path + ": error: cannot write the " + what + " in directory '" +
                                       dir + "': " + std::strerror(errno));
    std::fclose(f);
    std::remove(probe.c_str());
}

bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

/// --half, --compression and --background-depth into a.exr.
void parse_exr_options(RenderArgs& a) {
    const std::vector<std::string>& names = exr_compressions();
    if (std::find(names.begin(), names.end(), a.compression) == names.end())
        throw_unknown_choice("--compression", a.compression, names);
    a.exr = ExrOptions{};
    a.exr.compression = a.compression;
    if (a.half)
        a.exr.half_channels.assign(std::begin(exr::kHalfChannels), std::end(exr::kHalfChannels));
    if (a.background_depth != "inf") {
        char* end = nullptr;
        const double d = std::strtod(a.background_depth.c_str(), &end);
        if (a.background_depth.empty() || *end != '\0' || !(d > 0.0) ||
            !(d <= double(std::numeric_limits<float>::max())))
            usage("--background-depth: '" + a.background_depth +
                  "' is not inf or a finite distance > 0");
        a.exr.background_depth = float(d);
    }
}

} // namespace

// ---------------------------------------------------------------------------------------------
// Shared by every subcommand
// ---------------------------------------------------------------------------------------------

void add_log_options(CLI::App& app, LogArgs& a) {
    app.add_flag("-q,--quiet", a.quiet,
                 "Only errors and warnings on stderr (no progress, summary or notes)");
    app.add_flag("-v,--verbose", a.verbose,
                 "Also notes about the scene and what a render leaves out");
    app.add_option("--log-level", a.level,
                   "error, warning, info (the default: progress, summary, files written) or "
                   "verbose; -q is warning, -v is verbose");
}

LogLevel log_level_of(const LogArgs& a) {
    const int given = (a.quiet ? 1 : 0) + (a.verbose ? 1 : 0) + (a.level.empty() ? 0 : 1);
    if (given > 1) usage("give only one of -q/--quiet, -v/--verbose and --log-level");
    if (!a.level.empty()) return parse_log_level(a.level);
    if (a.quiet) return LogLevel::Warning;
    if (a.verbose) return LogLevel::Verbose;
    return LogLevel::Info;
}

const char* exit_status_help() {
    return "Exit status:\n"
           "  0   success\n"
           "  2   usage error (bad flag, value or combination), refused before any work\n"
           "  3   the scene or camera file is malformed or unsupported\n"
           "  4   a file could not be read or written\n"
           "  5   interrupted (SIGINT/SIGTERM); the image holds the finished samples\n"
           "  70  internal error";
}

std::string describe_parse_error(const CLI::App& top, const CLI::ParseError& e) {
    const CLI::App* app = &top;
    while (!app->get_subcommands().empty())
        app = app->get_subcommands().front();
    const std::string what = e.what();
    // The dispatcher (candela itself) has subcommands; a command's own app has none.
    const bool dispatcher =
        app == &top && !top.get_subcommands([](const CLI::App*) { return true; }).empty();
    // "render: " in front of what concerns a subcommand as a whole.
    const std::string cmd = app->get_name().empty() ? std::string() : app->get_name() + ": ";

    auto option_names = [&](const CLI::App* a) {
        std::vector<std::string> names;
        for (const CLI::Option* o : a->get_options()) {
            for (const std::string& l : o->get_lnames())
                names.push_back("--" + l);
            for (const std::string& s : o->get_snames())
                names.push_back("-" + s);
        }
        return names;
    };
    auto display = [](const CLI::Option* o) {
        if (o->get_lnames().empty() && o->get_snames().empty()) {
            std::string n = o->get_name();
            std::transform(n.begin(), n.end(), n.begin(),
                           [](unsigned char c) { return char(std::toupper(c)); });
            return n;
        }
        std::string s;
        for (const std::string& n : o->get_snames())
            s += (s.empty() ? "-" : "/-") + n;
        for (const std::string& n : o->get_lnames())
            s += (s.empty() ? "--" : "/--") + n;
        return s;
    };
    // The option an error message names (the longest name found in it).
    auto option_in_message = [&]() -> const CLI::Option* {
        const CLI::Option* best = nullptr;
        std::size_t best_len = 0;
        for (const CLI::Option* o : app->get_options()) {
            std::vector<std::string> names;
            for (const std::string& l : o->get_lnames())
                names.push_back("--" + l);
            for (const std::string& s : o->get_snames())
                names.push_back("-" + s);
            if (o->get_lnames().empty() && o->get_snames().empty()) names.push_back(o->get_name());
            for (const std::string& n : names)
                if (n.size() > best_len && what.find(n) != std::string::npos) {
                    best = o;
                    best_len = n.size();
                }
        }
        return best;
    };
    auto type_phrase = [](const CLI::Option* o, bool plural) {
        std::string t = o->get_type_name();
        t = t.substr(0, t.find(' '));
        if (t == "INT") return std::string(plural ? "whole numbers" : "a whole number");
        if (t == "UINT")
            return std::string(plural ? "non-negative whole numbers"
                                      : "a non-negative whole number");
        if (t == "FLOAT") return std::string(plural ? "numbers" : "a number");
        return std::string(plural ? "values" : "a value");
    };

    if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
        const std::vector<std::string> extra = app->remaining();
        for (const std::string& arg : extra)
            if (arg.size() > 1 && arg[0] == '-') {
                const std::string name = arg.substr(0, arg.find('='));
                // The CS184 habit: -f names the output file; merge and converge call it -o.
                if (name == "-f")
                    for (const CLI::Option* o : app->get_options())
                        if (o->check_lname("output") && o->check_sname("o"))
                            return "error: " + cmd +
                                   "unknown option '-f'; the output file is "
                                   "'-o' here";
                const std::string near = nearest_name(name, option_names(app));
                return "error: " + cmd + "unknown option '" + name + "'" +
                       (near.empty() ? "" : "; did you mean '" + near + "'?");
            }
        if (!extra.empty()) {
            if (dispatcher) {
                std::vector<std::string> subs;
                for (const CLI::App* s : top.get_subcommands([](const CLI::App*) { return true; }))
                    subs.push_back(s->get_name());
                const std::string near = nearest_name(extra.front(), subs);
                return "error: unknown command '" + extra.front() + "'" +
                       (near.empty() ? "" : "; did you mean '" + near + "'?");
            }
            return "error: " + cmd + "unexpected argument '" + extra.front() + "'";
        }
    }
    if (dynamic_cast<const CLI::RequiredError*>(&e)) {
        if (dispatcher)
            return "error: no command given (render, info, check, bench, converge or merge)";
        for (const CLI::Option* o : app->get_options())
            if (o->get_required() && o->count() == 0)
                return "error: " + cmd + display(o) + " is missing";
    }
    if (dynamic_cast<const CLI::ConversionError*>(&e) ||
        dynamic_cast<const CLI::ArgumentMismatch*>(&e)) {
        if (const CLI::Option* o = option_in_message()) {
            const int expected = o->get_expected_max();
            const std::vector<std::string> got = o->results();
            std::string values;
            for (const std::string& v : got)
                values += (values.empty() ? "'" : " '") + v + "'";
            if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) && expected == 1 && got.size() > 1)
                return "error: " + display(o) + " was given " + std::to_string(got.size()) +
                       " times; give it once";
            // A list option's maximum is CLI11's internal "any number" (2^29), never shown.
            constexpr int kLongestFixedList = 16;
            if (expected > kLongestFixedList)
                return "error: " + display(o) + " takes one or more " + type_phrase(o, true) +
                       (values.empty() ? "" : "; got " + values);
            if (expected > 1)
                return "error: " + display(o) + " takes " + std::to_string(expected) + " " +
                       type_phrase(o, true) + (values.empty() ? "" : "; got " + values);
            if (dynamic_cast<const CLI::ArgumentMismatch*>(&e))
                return "error: " + display(o) + " needs " + type_phrase(o, false);
            // CS184's -o is the accumulate flag; a file name there means -f was meant.
            const std::string hint = o->check_lname("accumulate")
                                         ? " (CS184's -o is 0 or 1; the output file is -f)"
                                         : "";
            // A whole number CLI11 could not convert is beyond the option's type, not malformed.
            const std::string type = o->get_type_name().substr(0, o->get_type_name().find(' '));
            const bool integral_type = type == "INT" || type == "UINT";
            const bool whole =
                !got.empty() && std::all_of(got.begin(), got.end(), [](const std::string& v) {
                    const std::size_t first = v.size() > 1 && (v[0] == '-' || v[0] == '+') ? 1 : 0;
                    return v.size() > first &&
                           v.find_first_not_of("0123456789", first) == std::string::npos;
                });
            if (integral_type && whole)
                return "error: " + display(o) + ": " + values + " is out of range";
            return "error: " + display(o) + ": " + (values.empty() ? "the value" : values) +
                   " is not " + type_phrase(o, false) + hint;
        }
    }
    return "error: " + cmd + what;
}

// ---------------------------------------------------------------------------------------------
// render
// ---------------------------------------------------------------------------------------------

std::string default_output_path(const std::string& scene_path) {
    std::size_t slash = scene_path.find_last_of('/');
    std::string base = slash == std::string::npos ? scene_path : scene_path.substr(slash + 1);
    std::size_t dot = base.find_last_of('.');
    if (dot != std::string::npos && dot > 0) base = base.substr(0, dot);
    return base + ".exr";
}

std::string RenderArgs::preview_path() const {
    if (!preview || output_kind != OutputKind::Exr) return "";
    return output.substr(0, output.size() - path_extension(output).size()) + ".png";
}

std::string RenderArgs::rate_path() const {
    if (settings.adaptive == AdaptiveKind::None) return "";
    if (output_kind == OutputKind::Ldr) return rate_image_path(output);
    const std::string p = preview_path();
    return p.empty() ? "" : rate_image_path(p);
}

std::string RenderArgs::checkpoint_path() const {
    return checkpoint.empty() ? checkpoint_path_for(output) : checkpoint;
}

void add_render_options(CLI::App& app, RenderArgs& a) {
    RenderSettings& s = a.settings;
    app.add_option("scene", a.scene, "COLLADA scene file (.dae)");
    app.add_option("-f,--output", a.output,
                   "Output image: .exr (HDR with alpha and auxiliary channels), an 8-bit "
                   "preview in any format OpenImageIO writes (.png, .jpg, .tif, ...; with "
                   "--tonemap and --exposure) or .hdr (linear RGB). Default: <scene name>.exr "
                   "in the current directory");
    app.add_option("-s,--spp", s.spp,
                   "Samples per pixel. With the default adaptive sampling the cap: the render "
                   "spends at most what this many uniform samples per pixel cost; with "
                   "-a/cs184 the most one pixel takes")
        ->capture_default_str();
    app.add_option("-l,--light-samples", s.light_samples,
                   "Light samples per shading point (per non-delta light for --integrator=direct)"
                   "; also the -H budget")
        ->capture_default_str();
    app.add_option("-t,--threads", s.threads, "Worker threads; 0 = all cores")
        ->capture_default_str();
    app.add_option("-m,--max-depth", s.max_depth, "Maximum number of scattering events per path")
        ->capture_default_str();
    app.add_option("-o,--accumulate", a.accumulate,
                   "CS184 -o (not an output file): 1 sums light scattered 0..m times; 0 keeps "
                   "only light scattered exactly m times")
        ->capture_default_str();
    app.add_option("-e,--env", a.env_map, "Lat-long environment map (EXR or any image)");
    app.add_option_function<float>(
        "-b,--lens-radius", [&a](const float& v) { a.lens_radius = v; },
        "Thin-lens aperture radius; 0 = pinhole (default: the camera file's, else 0)");
    app.add_option_function<float>(
        "-d,--focal-distance", [&a](const float& v) { a.focal_distance = v; },
        "Distance to the plane in focus (default: the camera file's, else 4.7)");
    app.add_option("-r,--resolution", a.resolution, "Image width and height (default 800 600)")
        ->expected(2)
        ->allow_extra_args(false);
    app.add_option("-p,--region", a.region,
                   "Render only the cell X Y DX DY (origin bottom-left, as in CS184); the EXR's "
                   "data window is the cell inside the full display window")
        ->expected(4)
        ->allow_extra_args(false);
    app.add_option("-c,--camera-file", a.camera_file,
                   "CS184 camera settings file: 30 numbers (README \"Camera files\")");
    app.add_option("-a,--adaptive-sampling", a.adaptive,
                   "Adaptive sampling: BATCH TOLERANCE (CS184: batch 32, tolerance 0.05)")
        ->expected(2)
        ->allow_extra_args(false);
    app.add_flag("-H,--hemisphere", s.hemisphere,
                 "Direct light by uniform hemisphere sampling instead of light sampling");
    app.add_option_function<std::string>(
        "--adaptive",
        [&a](const std::string& v) {
            if (const std::optional<AdaptiveKind> k = find_enum(kAdaptiveKinds, v)) {
                a.adaptive_kind = *k;
                a.unknown_choices.erase("--adaptive");
            } else {
                a.unknown_choices["--adaptive"] = v;
            }
        },
        "Adaptive sampling: " + enum_choices(kAdaptiveKinds));
    app.add_option("--noise-threshold", a.noise_threshold,
                   "Relative sampler: stop when the estimated relative RMS error of the image "
                   "falls to this (0 = spend the whole -s budget); -a's TOLERANCE replaces it")
        ->capture_default_str();
    app.add_option("--time-budget", s.time_budget,
                   "Stop starting passes after SECONDS of rendering (whole passes; -s stays the "
                   "maximum); 0 = no limit")
        ->capture_default_str();
    add_choice(app, a, "--camera", kCameraModes, a.build.camera_mode,
               enum_choices(kCameraModes, {"; ", "; ", ": ", ""}))
        ->default_str(enum_name(kCameraModes, a.build.camera_mode));
    add_choice(app, a, "--accel", kAccelKinds, s.accel.kind,
               "Ray traversal backend: " + enum_choices(kAccelKinds))
        ->default_str(accel_kind_name(s.accel.kind));
    add_choice(app, a, "--triangle", kTriangleTests, s.accel.triangle,
               "Triangle test of builtin/brute: " + enum_choices(kTriangleTests))
        ->default_str(enum_name(kTriangleTests, s.accel.triangle));
    app.add_flag("--embree-robust", a.embree_robust, "Embree robust (watertight) traversal");
    add_choice(app, a, "--embree-quality", kEmbreeQualities, s.accel.quality,
               "Embree build quality: " + enum_choices(kEmbreeQualities, {", ", ", "}))
        ->default_str(enum_name(kEmbreeQualities, s.accel.quality));
    add_index_option(app, "--seed", s.seed, "Random seed (0 to 2^31-1)");
    add_index_option(app, "--sample-offset", s.sample_offset,
                     "First sample index (renders of disjoint ranges merge exactly)");
    add_choice(app, a, "--sampler", kSamplerKinds, s.sampler, enum_choices(kSamplerKinds))
        ->default_str(enum_name(kSamplerKinds, s.sampler));
    add_choice(app, a, "--light-sampler", kLightSamplerKinds, s.light_sampler,
               "Light choice for next-event estimation: " +
                   enum_choices(kLightSamplerKinds, {"; ", "; "}))
        ->default_str(enum_name(kLightSamplerKinds, s.light_sampler));
    add_choice(app, a, "--integrator", kIntegratorKinds, s.integrator,
               enum_choices(kIntegratorKinds))
        ->default_str(enum_name(kIntegratorKinds, s.integrator));
    add_choice(app, a, "--light-paths", kLightPaths, s.light_paths,
               enum_choices(kLightPaths, {"; ", "; "}))
        ->default_str(enum_name(kLightPaths, s.light_paths));
    app.add_flag("--no-mis", a.no_mis, "Disable multiple importance sampling");
    app.add_option("--rr-depth", s.rr_min_depth,
                   "Russian roulette starts after this many scattering events")
        ->capture_default_str();
    app.add_option("--aov", a.aov,
                   "EXR auxiliary channels: all, none, or a list of albedo,normal,depth,variance")
        ->capture_default_str();
    app.add_flag("--half", a.half,
                 "EXR: store R, G, B, A, albedo and N as 16-bit half floats (Z, variance and "
                 "samples stay 32-bit)");
    app.add_option("--compression", a.compression,
                   "EXR compression: zip, zips, piz, rle, none (lossless), pxr24, b44, b44a, "
                   "dwaa, dwab (lossy)")
        ->capture_default_str();
    app.add_option("--background-depth", a.background_depth,
                   "EXR: Z where no sample hit a surface: inf, or a distance > 0 for tools that "
                   "turn +inf into NaN (e.g. 1e10)")
        ->capture_default_str();
    app.add_flag("--preview", a.preview,
                 "With an .exr output, also write an sRGB PNG preview beside it (and the "
                 "sample-rate image for adaptive renders)");
    add_choice(app, a, "--tonemap", kTonemaps, a.tonemap,
               "8-bit images: " + enum_choices(kTonemaps))
        ->default_str(tonemap_name(a.tonemap));
    app.add_option("--exposure", a.exposure, "8-bit images: exposure in stops, before --tonemap")
        ->capture_default_str();
    add_choice(app, a, "--look", kLooks, a.look,
               "8-bit images: " + enum_choices(kLooks) +
                   "; cs184 changes only the tone curve, not the physics "
                   "(docs/cs184-differences.md)")
        ->default_str(enum_name(kLooks, a.look));
    app.add_flag("--strict", a.strict, "Treat scene warnings and flags that do nothing as errors");
    app.add_option("--pass-spp", s.pass_spp,
                   "Samples per pixel per pass (the granularity of interrupts and checkpoints); "
                   "0 = automatic")
        ->capture_default_str();
    app.add_option("--checkpoint", a.checkpoint,
                   "Checkpoint file written on SIGINT/SIGTERM and with --checkpoint-every "
                   "(default: <output>.ckpt)");
    app.add_option("--checkpoint-every", a.checkpoint_every,
                   "Also write a checkpoint every SECONDS during the render (0 = only when "
                   "interrupted)")
        ->capture_default_str();
    app.add_option("--max-memory", a.max_memory,
                   "Refuse renders estimated to need more memory than this (e.g. 8G, 512M; "
                   "default: three quarters of physical memory)");
    app.add_option("--resume", a.resume,
                   "Continue an interrupted render from its checkpoint (from any directory); "
                   "the result is bit-identical to an uninterrupted render. Other image "
                   "settings may be omitted; if given they must match the checkpoint's, except "
                   "that a larger -s or a lower --noise-threshold refines the render (a "
                   "finished one too, see --keep-checkpoint) to what those settings give");
    app.add_flag("--keep-checkpoint", a.keep_checkpoint,
                 "Keep the checkpoint when the render finishes, so that --resume can refine it "
                 "later");
    add_choice(app, a, "--progress", kProgressModes, s.progress, enum_choices(kProgressModes))
        ->default_str(progress_mode_name(s.progress));
    add_log_options(app, a.log);
}

void record_given_options(const CLI::App& app, RenderArgs& a) {
    for (const CLI::Option* o : app.get_options()) {
        if (o->count() == 0) continue;
        const std::vector<std::string>& l = o->get_lnames();
        a.given.insert(l.empty() ? o->get_name() : "--" + l.front());
    }
}

void finalize_render_args(RenderArgs& a) {
    RenderSettings& s = a.settings;
    const auto given = [&a](const char* name) { return a.given.count(name) > 0; };
    a.log_level = log_level_of(a.log);
    s.quiet = a.log_level < LogLevel::Info;
    check_choice(a, "--progress", kProgressModes);
    check_choice(a, "--tonemap", kTonemaps);
    check_choice(a, "--look", kLooks);
    if (a.look == Look::Cs184 && (given("--exposure") || given("--tonemap")))
        usage(std::string("--look cs184 sets the course's exposure and curve; it cannot be "
                          "combined with ") +
              (given("--exposure") ? "--exposure" : "--tonemap"));
    if (a.scene.empty() && a.resume.empty())
        usage("a scene file is required (or --resume CHECKPOINT)");
    if (!a.scene.empty()) {
        const std::string ext = path_extension(a.scene);
        if (!ext.empty() && ext != ".dae")
            throw Error(ErrorKind::Scene, a.scene + ": error: only COLLADA (.dae) scenes are read");
    }
    if (s.pass_spp < 0) usage("--pass-spp must be >= 0");
    a.max_memory_bytes =
        a.max_memory.empty() ? default_max_memory() : parse_memory_size(a.max_memory);
    if (!(s.time_budget >= 0.0) || !std::isfinite(s.time_budget))
        usage("--time-budget must be a finite number of seconds >= 0");
    if (!(a.checkpoint_every >= 0.0) || !std::isfinite(a.checkpoint_every))
        usage("--checkpoint-every must be a finite number of seconds >= 0");
    if (s.spp < 1 || s.spp > kMaxSpp)
        usage("-s/--spp: " + std::to_string(s.spp) + " is out of range [1, " +
              std::to_string(kMaxSpp) + "]");
    if (s.light_samples < 1 || s.light_samples > 65536)
        usage("-l/--light-samples: " + std::to_string(s.light_samples) +
              " is out of range [1, 65536]");
    if (s.threads < 0 || s.threads > kMaxThreads)
        usage("-t/--threads: " + std::to_string(s.threads) + " is out of range [0, " +
              std::to_string(kMaxThreads) + "]");
    if (s.max_depth < 0 || s.max_depth > kMaxDepth)
        usage("-m/--max-depth: " + std::to_string(s.max_depth) + " is out of range [0, " +
              std::to_string(kMaxDepth) + "]");
    if (s.rr_min_depth < 0) usage("--rr-depth must be >= 0");
    if (a.accumulate != 0 && a.accumulate != 1)
        usage("-o/--accumulate: " + std::to_string(a.accumulate) +
              " is not 0 or 1 (CS184 -o: 1 sums every scattering order, 0 keeps only order -m; "
              "the output file is -f)");
    s.accumulate = a.accumulate == 1;
    if (s.seed > std::uint64_t(kMaxIndex))
        usage("--seed: " + std::to_string(s.seed) + " is out of range [0, " +
              std::to_string(kMaxIndex) + "]");
    if (s.sample_offset + std::uint64_t(s.spp) > std::uint64_t(kMaxIndex))
        usage("--sample-offset: " + std::to_string(s.sample_offset) + " + -s " +
              std::to_string(s.spp) + " exceeds " + std::to_string(kMaxIndex));
    if (a.lens_radius && (!std::isfinite(*a.lens_radius) || *a.lens_radius < 0.f))
        usage("-b/--lens-radius must be a finite number >= 0");
    if (a.focal_distance && (!std::isfinite(*a.focal_distance) || *a.focal_distance <= 0.f))
        usage("-d/--focal-distance must be a finite number > 0");
    if (!std::isfinite(a.exposure)) usage("--exposure must be finite");
    if (!a.resolution.empty()) {
        s.width = a.resolution[0];
        s.height = a.resolution[1];
    }
    if (s.width < 1 || s.height < 1 || s.width > kMaxImageEdge || s.height > kMaxImageEdge ||
        (long long)s.width * s.height > kMaxPixels)
        usage("-r/--resolution: " + std::to_string(s.width) + "x" + std::to_string(s.height) +
              " is out of range (each side 1.." + std::to_string(kMaxImageEdge) +
              ", at most 2^28 pixels)");
    if (!a.region.empty()) {
        int x = a.region[0], y = a.region[1], dx = a.region[2], dy = a.region[3];
        if (x < 0 || y < 0 || dx < 1 || dy < 1 || x + dx > s.width || y + dy > s.height)
            usage("-p/--region: cell " + std::to_string(x) + " " + std::to_string(y) + " " +
                  std::to_string(dx) + " " + std::to_string(dy) + " is not inside the " +
                  std::to_string(s.width) + "x" + std::to_string(s.height) + " frame");
        // CS184 cells count rows from the bottom; the film counts from the top.
        s.region = Region{x, s.height - (y + dy), dx, dy};
    }
    // Adaptive sampling: relative with the noise threshold by default; -a BATCH TOL selects the
    // CS184 criterion (or gives the relative sampler its batch and tolerance).
    check_choice(a, "--adaptive", kAdaptiveKinds);
    s.adaptive = a.adaptive_kind      ? *a.adaptive_kind
                 : a.adaptive.empty() ? AdaptiveKind::Relative
                                      : AdaptiveKind::Cs184;
    if (!std::isfinite(a.noise_threshold) || a.noise_threshold < 0.f)
        usage("--noise-threshold must be a number >= 0");
    if (!a.adaptive.empty()) {
        double batch = a.adaptive[0], tol = a.adaptive[1];
        if (batch < 1 || batch != std::floor(batch) || batch > kMaxSpp)
            usage("-a: the batch size must be a whole number >= 1");
        if (!std::isfinite(tol) || tol <= 0.0) usage("-a: the tolerance must be > 0");
        s.adaptive_batch = int(batch);
        // The tolerance is the cs184 per-pixel criterion's, or the relative sampler's threshold.
        if (s.adaptive == AdaptiveKind::Relative)
            s.noise_threshold = float(tol);
        else
            s.adaptive_tol = float(tol);
    } else if (s.adaptive == AdaptiveKind::Cs184) {
        usage("--adaptive cs184 needs -a BATCH TOLERANCE");
    } else {
        s.adaptive_batch = kDefaultAdaptiveBatch;
        s.noise_threshold = a.noise_threshold;
    }
    check_choice(a, "--accel", kAccelKinds);
    check_choice(a, "--triangle", kTriangleTests);
    s.accel.embree_robust = a.embree_robust;
    check_choice(a, "--embree-quality", kEmbreeQualities);
    check_choice(a, "--sampler", kSamplerKinds);
    check_choice(a, "--light-sampler", kLightSamplerKinds);
    check_choice(a, "--integrator", kIntegratorKinds);
    check_choice(a, "--light-paths", kLightPaths);
    s.mis = !a.no_mis;
    s.aovs = AovSet::parse(a.aov);
    parse_exr_options(a);
    check_choice(a, "--camera", kCameraModes);
    if (a.output.empty()) a.output = default_output_path(a.scene);
    a.output_kind = output_kind(a.output);
    if (a.output_kind == OutputKind::Unsupported)
        usage("-f/--output: '" + a.output + "': no image format for this extension (use " +
              writable_extensions() + ")");

    // Flags that do nothing in this combination: a warning, an error under --strict.
    std::vector<std::string>& w = a.warnings;
    w.clear();
    const bool writes_8bit = a.output_kind == OutputKind::Ldr || !a.preview_path().empty();
    if (!writes_8bit && (given("--exposure") || given("--tonemap") || given("--look")))
        w.push_back(std::string(given("--exposure")  ? "--exposure"
                                : given("--tonemap") ? "--tonemap"
                                                     : "--look") +
                    " has no effect: no 8-bit image is written (add --preview, or -f with .png, "
                    ".jpg, .tif, ...)");
    if (given("--preview") && a.output_kind != OutputKind::Exr)
        w.push_back("--preview has no effect: it adds a PNG beside an .exr output");
    if (given("--aov") && a.output_kind != OutputKind::Exr)
        w.push_back("--aov has no effect: auxiliary channels are written to .exr outputs only");
    for (const char* f : {"--half", "--compression", "--background-depth"})
        if (given(f) && a.output_kind != OutputKind::Exr)
            w.push_back(std::string(f) + " has no effect: it concerns .exr outputs only");
    if (s.integrator == IntegratorKind::Normals) {
        for (const char* f : {"--hemisphere", "--light-samples", "--no-mis", "--light-paths",
                              "--max-depth", "--accumulate", "--rr-depth", "--env"})
            if (given(f))
                w.push_back(std::string(find_spec(f)->display) +
                            " has no effect with --integrator normals (it traces camera rays "
                            "only)");
    }
    if (given("--noise-threshold") && s.adaptive != AdaptiveKind::Relative)
        w.push_back(std::string("--noise-threshold has no effect with --adaptive ") +
                    enum_name(kAdaptiveKinds, s.adaptive));
    if (given("--noise-threshold") && !a.adaptive.empty())
        w.push_back("--noise-threshold has no effect with -a (its TOLERANCE is the threshold)");
    if (!a.adaptive.empty() && s.adaptive == AdaptiveKind::None)
        w.push_back("-a/--adaptive-sampling has no effect with --adaptive none");
    if (given("--pass-spp") && s.adaptive != AdaptiveKind::None)
        w.push_back("--pass-spp has no effect with adaptive sampling (a pass is one adaptive "
                    "batch; --adaptive none renders uniform passes)");
    if (given("--triangle") && s.accel.kind == AccelKind::Embree)
        w.push_back("--triangle has no effect with --accel embree (it selects the builtin and "
                    "brute triangle test)");
    for (const char* f : {"--embree-robust", "--embree-quality"})
        if (given(f) && s.accel.kind != AccelKind::Embree)
            w.push_back(std::string(f) + " has no effect with --accel " +
                        accel_kind_name(s.accel.kind));
    if (given("--camera") && !a.camera_file.empty())
        w.push_back("--camera has no effect with -c (the camera file sets the pose)");
    if (a.strict && !w.empty()) usage(w.front() + " (--strict)");
}

RenderArgs parse_render_command_line(const std::vector<std::string>& argv) {
    RenderArgs args;
    CLI::App app{"render"};
    add_render_options(app, args);
    std::vector<std::string> reversed(argv.rbegin(), argv.rend());
    try {
        app.parse(reversed);
    } catch (const CLI::ParseError& e) {
        throw Error(ErrorKind::Usage, describe_parse_error(app, e));
    }
    record_given_options(app, args);
    finalize_render_args(args);
    return args;
}

void check_scene_file(const std::string& path) {
    const std::string ext = path_extension(path);
    if (!ext.empty() && ext != ".dae")
        throw Error(ErrorKind::Scene, path + ": error: only COLLADA (.dae) scenes are read");
    const std::string why = file_read_failure(path);
    if (!why.empty()) throw Error(ErrorKind::Io, path + ": error: cannot open scene file: " + why);
    std::error_code ec;
    if (fs::is_regular_file(path, ec) && fs::file_size(path, ec) == 0 && !ec)
        throw Error(ErrorKind::Scene, path + ": error: empty file");
}

std::vector<RenderImage> render_images(const RenderArgs& a) {
    std::vector<RenderImage> images = {{a.output, a.output_kind}};
    if (!a.preview_path().empty()) images.push_back({a.preview_path(), OutputKind::Ldr});
    if (!a.rate_path().empty()) images.push_back({a.rate_path(), OutputKind::Ldr});
    return images;
}

void check_render_files(RenderArgs& a) {
    check_scene_file(a.scene);
    if (!a.camera_file.empty()) a.camera = read_camera_file(a.camera_file);
    if (!a.env_map.empty()) {
        const ImageHeader h = read_envmap_header(a.env_map);
        if (h.width < 1 || h.height < 1)
            throw Error(ErrorKind::Io, a.env_map + ": error: not a 2-D image");
    }
    // Outputs: none may replace the scene, each must be writable.
    for (const RenderImage& o : render_images(a)) {
        if (same_file(o.path, a.scene))
            throw Error(ErrorKind::Usage,
                        o.path + ": error: refusing to overwrite the input scene");
        check_image_location(o.path);
    }
    check_image_module_found();
    const std::string ckpt = a.checkpoint_path();
    if (same_file(ckpt, a.scene))
        throw Error(ErrorKind::Usage, ckpt + ": error: refusing to overwrite the input scene");
    check_file_writable(ckpt, "checkpoint");
}

std::vector<std::string> canonical_render_args(const RenderArgs& a) {
    std::vector<std::string> out;
    for (const OptionSpec& spec : option_specs()) {
        if (spec.runtime) continue;
        const std::string name = spec.name;
        // The scene and the output are always stored, as absolute paths: the default output
        // lies in the directory the render started from.
        const bool always = name == "scene" || name == "--output";
        if (!always && !a.given.count(name)) continue;
        std::vector<std::string> v = spec.values(a);
        if (name == "scene") {
            out.push_back(v.front());
            continue;
        }
        if (is_flag(name)) {
            if (v.empty()) out.push_back(name);
            continue;
        }
        if (name == "--lens-radius" || name == "--focal-distance" || name == "--camera-file" ||
            name == "--env") {
            if (v.front().empty()) continue;
        }
        out.push_back(name);
        out.insert(out.end(), v.begin(), v.end());
    }
    return out;
}

std::string resume_runtime_options() {
    std::string s;
    for (const OptionSpec& spec : option_specs())
        if (spec.runtime && std::string(spec.name) != "--resume")
            s += (s.empty() ? "" : ", ") + std::string(spec.display);
    return s;
}

namespace {

/// A resume that refines (render/refine.h) may raise -s and lower the relative sampler's noise
/// threshold (0 = none, the strictest). Returns whether `name` changes that way; throws the
/// refusal, naming the setting, when it changes the other way.
bool refines(const std::string& name, const RenderArgs& given, const RenderArgs& stored,
             const std::string& checkpoint, const std::vector<std::string>& here,
             const std::vector<std::string>& there) {
    const std::string refused = checkpoint + ": error: refusing to refine: ";
    if (name == "--spp") {
        if (given.settings.spp > stored.settings.spp) return true;
        throw Error(ErrorKind::Usage, refused + "-s/--spp is " + here.front() + " here but " +
                                          there.front() +
                                          " in the checkpoint; a refinement may only raise it");
    }
    if (name == "--noise-threshold") {
        const std::string t_here = fmt::format("{:g}", given.noise_threshold);
        const std::string t_there = fmt::format("{:g}", stored.noise_threshold);
        if (stored.settings.adaptive != AdaptiveKind::Relative || !stored.adaptive.empty())
            throw Error(ErrorKind::Usage,
                        refused + "--noise-threshold is " + t_here +
                            " here, but the checkpoint's render does not stop at a noise "
                            "threshold (it uses " +
                            (stored.adaptive.empty()
                                 ? "--adaptive " + std::string(enum_name(kAdaptiveKinds,
                                                                         stored.settings.adaptive))
                                 : std::string("-a")) +
                            ")");
        const float t = given.noise_threshold, old = stored.noise_threshold;
        if ((t == 0.f && old > 0.f) || t < old) return true;
        throw Error(ErrorKind::Usage,
                    refused + "--noise-threshold is " + t_here + " here but " + t_there +
                        " in the checkpoint; a refinement may only lower it (0 = no threshold)");
    }
    return false;
}

} // namespace

void check_resume_matches(const RenderArgs& given, const RenderArgs& stored,
                          const std::string& checkpoint) {
    for (const std::string& name : given.given) {
        const OptionSpec* spec = find_spec(name);
        if (!spec) throw Error(ErrorKind::Internal, "no resume rule for option " + name);
        if (spec->runtime) continue;
        std::vector<std::string> here = spec->values(given), there = spec->values(stored);
        if (here != there && refines(name, given, stored, checkpoint, here, there)) continue;
        if (name == "scene" || name == "--output" || name == "--env" || name == "--camera-file") {
            // The same file under another name is the same setting.
            if (!here.front().empty() && !there.front().empty() &&
                (same_file(here.front(), there.front()) || here == there))
                continue;
        }
        if (here == there) continue;
        throw Error(ErrorKind::Usage,
                    checkpoint + ": error: refusing to resume: " + spec->display + " is " +
                        quoted_list(here) + " here but " + quoted_list(there) +
                        " in the checkpoint. Give --resume alone; only these options may "
                        "change: " +
                        resume_runtime_options() +
                        " (and, to refine the render, a larger -s/--spp or a lower "
                        "--noise-threshold)");
    }
}

} // namespace candela
