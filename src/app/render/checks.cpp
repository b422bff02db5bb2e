// The checks of a render's options after parsing (ranges, combinations, the table of flags that
// have no effect) and of its files before the scene is loaded.
#include "../cli_support.h"
#include "../output_paths.h"
#include "candela/app/cli.h"

#include "candela/io/envmap_file.h"
#include "candela/render/adaptive.h"
#include "candela/render/checkpoint.h"
#include "candela/render/exr_layout.h"
#include "candela/render/memory_budget.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/strings.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace candela {

namespace {

namespace fs = std::filesystem;
using cli::usage;

/// A plain file (the checkpoint) can be created at `path`: its directory exists and is
/// writable, and `path` is not a directory.
void check_file_writable(const std::string& path, const std::string& what) {
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write the " + what + ": it is a directory");
    const fs::path parent = fs::path(path).parent_path();
    const std::string dir = parent.empty() ? std::string(".") : parent.string();
    if (!fs::is_directory(dir, ec))
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write the " + what + ": directory '" + dir + "' does not exist");
    const std::string probe = temp_path_for(path);
    std::FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f)
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write the " + what + " in directory '" + dir + std::string("': ") +
                        std::strerror(errno));
    std::fclose(f);
    std::remove(probe.c_str());
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

/// Throws "FLAG: VALUE is out of range [LO, HI]" unless LO <= VALUE <= HI.
void check_range(const char* flag, long long value, long long lo, long long hi) {
    if (value < lo || value > hi)
        usage(std::string(flag) + ": " + std::to_string(value) + " is out of range [" +
              std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// Every Int setting within its row's range, and every Index setting with a largest value
/// below it (render/setting_table.h).
void check_setting_ranges(RenderSettings& s) {
    for (const SettingRow& row : setting_table()) {
        if (row.type == SettingType::Int) {
            const int v = *static_cast<const int*>(row.field(s));
            if (row.max >= row.min)
                check_range(row.display.c_str(), v, row.min, row.max);
            else if (v < row.min)
                usage(row.display + " must be >= " + std::to_string(row.min));
        } else if (row.type == SettingType::Index && row.max > 0) {
            const std::uint64_t v = *static_cast<const std::uint64_t*>(row.field(s));
            if (v > std::uint64_t(row.max))
                usage(row.display + ": " + std::to_string(v) + " is out of range [0, " +
                      std::to_string(row.max) + "]");
        }
    }
}

/// The error of a choice setting whose value names none of its row's choices.
void check_setting_choices(const RenderArgs& a) {
    for (const SettingRow& row : setting_table()) {
        if (row.type != SettingType::Choice) continue;
        const auto it = a.unknown_choices.find(row.flag);
        if (it != a.unknown_choices.end()) throw_unknown_choice(row.flag, it->second, row.choices);
    }
}

/// The log level, the choices that concern any run, and the scene file's name.
void settle_log_and_scene(RenderArgs& a) {
    a.log_level = log_level_of(a.log);
    a.settings.quiet = a.log_level < LogLevel::Info;
    cli::check_choice(a, "--tonemap", kTonemaps);
    cli::check_choice(a, "--look", kLooks);
    if (a.look == Look::Cs184 && (a.given.count("--exposure") || a.given.count("--tonemap")))
        usage(std::string("--look cs184 sets the course's exposure and curve; it cannot be "
                          "combined with ") +
              (a.given.count("--exposure") ? "--exposure" : "--tonemap"));
    if (a.scene.empty() && a.resume.empty())
        usage("a scene file is required (or --resume CHECKPOINT)");
    if (!a.scene.empty()) {
        const std::string ext = path_extension(a.scene);
        if (!ext.empty() && ext != ".dae")
            throw Error(ErrorKind::Scene, SourceLoc{a.scene},
                        "only COLLADA (.dae) scenes are read");
    }
}

/// The numeric options, each within its range.
void check_ranges(RenderArgs& a) {
    RenderSettings& s = a.settings;
    a.max_memory_bytes = a.max_memory.empty() ? default_max_memory()
                                              : parse_memory_size(a.max_memory, "--max-memory");
    if (!(s.time_budget >= 0.0) || !std::isfinite(s.time_budget))
        usage("--time-budget must be a finite number of seconds >= 0");
    if (!(a.checkpoint_every >= 0.0) || !std::isfinite(a.checkpoint_every))
        usage("--checkpoint-every must be a finite number of seconds >= 0");
    check_setting_ranges(s);
    if (a.accumulate != 0 && a.accumulate != 1)
        usage("-o/--accumulate: " + std::to_string(a.accumulate) +
              " is not 0 or 1 (CS184 -o: 1 sums every scattering order, 0 keeps only order -m; "
              "the output file is -f)");
    s.accumulate = a.accumulate == 1;
    if (a.lens_radius && (!std::isfinite(*a.lens_radius) || *a.lens_radius < 0.f))
        usage("-b/--lens-radius must be a finite number >= 0");
    if (a.focal_distance && (!std::isfinite(*a.focal_distance) || *a.focal_distance <= 0.f))
        usage("-d/--focal-distance must be a finite number > 0");
    if (!std::isfinite(a.exposure)) usage("--exposure must be finite");
}

/// --framing, --look-from, --look-at and --fov into a.build and a.camera_overrides. The flags
/// alone are checked here (finite points, the field of view's range, and when both points are
/// given, that they differ and do not look along world +Y); a point given alone is checked
/// against the scene's camera when the scene is loaded (apply_camera_overrides).
void settle_view(RenderArgs& a) {
    cli::check_choice(a, "--framing", kFramings);
    CameraOverrides& o = a.camera_overrides;
    o = CameraOverrides{};
    const auto point = [](const char* flag, const std::vector<float>& v) {
        if (v.size() != 3 ||
            !std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); }))
            usage(std::string(flag) + " needs three finite numbers X Y Z");
        return Vec3(v[0], v[1], v[2]);
    };
    if (!a.look_from.empty()) o.from = point("--look-from", a.look_from);
    if (!a.look_at.empty()) o.at = point("--look-at", a.look_at);
    o.hfov_deg = a.fov;
    // The checks that need no scene, on a camera of no consequence.
    CameraOverrides alone = o;
    if (!(o.from && o.at)) alone.from = alone.at = std::nullopt;
    Camera probe;
    apply_camera_overrides(probe, alone);
}

/// -r and -p: the frame and the region of it rendered.
void settle_frame(RenderArgs& a) {
    RenderSettings& s = a.settings;
    if (!a.resolution.empty()) {
        s.width = a.resolution[0];
        s.height = a.resolution[1];
    }
    if (s.width < 1 || s.height < 1 || s.width > cli::kMaxImageEdge ||
        s.height > cli::kMaxImageEdge || (long long)s.width * s.height > cli::kMaxPixels)
        usage("-r/--resolution: " + std::to_string(s.width) + "x" + std::to_string(s.height) +
              " is out of range (each side 1.." + std::to_string(cli::kMaxImageEdge) +
              ", at most 2^28 pixels)");
    if (a.region.empty()) return;
    int x = a.region[0], y = a.region[1], dx = a.region[2], dy = a.region[3];
    if (x < 0 || y < 0 || dx < 1 || dy < 1 || x + dx > s.width || y + dy > s.height)
        usage("-p/--region: cell " + std::to_string(x) + " " + std::to_string(y) + " " +
              std::to_string(dx) + " " + std::to_string(dy) + " is not inside the " +
              std::to_string(s.width) + "x" + std::to_string(s.height) + " frame");
    // CS184 cells count rows from the bottom; the film counts from the top.
    s.region = Region{x, s.height - (y + dy), dx, dy};
}

/// What the relative sampler's noise threshold measures, for its range errors.
constexpr const char* kThresholdUnit =
    "is the estimated relative RMS error of the image at which sampling stops, a fraction (0.02 "
    "= 2 %; 0 = no target, spend the -s budget)";

/// A number as a user typed it ("2", "0.5").
std::string number_text(double v) {
    return fmt::format("{:g}", v);
}

/// Adaptive sampling: relative with the noise threshold by default; -a BATCH TOL selects the
/// CS184 criterion (or gives the relative sampler its batch and tolerance).
void settle_adaptive(RenderArgs& a) {
    RenderSettings& s = a.settings;
    cli::check_choice(a, setting_row(Setting::Adaptive).flag, kAdaptiveKinds);
    s.adaptive = a.adaptive_kind      ? *a.adaptive_kind
                 : a.adaptive.empty() ? AdaptiveKind::Relative
                                      : AdaptiveKind::Cs184;
    const std::unique_ptr<PassPolicy> sampler = make_pass_policy(s);
    if (!std::isfinite(a.noise_threshold) || a.noise_threshold < 0.f || a.noise_threshold >= 1.f)
        usage("--noise-threshold: " + number_text(a.noise_threshold) + " is not in [0, 1): it " +
              kThresholdUnit);
    if (!a.adaptive.empty()) {
        double batch = a.adaptive[0], tol = a.adaptive[1];
        if (batch < 1 || batch != std::floor(batch) || batch > kMaxSpp)
            usage("-a: the batch size must be a whole number >= 1");
        if (!std::isfinite(tol) || tol <= 0.0) usage("-a: the tolerance must be > 0");
        s.adaptive_batch = int(batch);
        // The tolerance is the cs184 per-pixel criterion's, or the relative sampler's threshold.
        if (sampler->reads_noise_threshold() && tol >= 1.0)
            usage("-a: the tolerance " + number_text(tol) +
                  " is the relative sampler's noise threshold here, and not below 1: it " +
                  kThresholdUnit);
        if (sampler->reads_noise_threshold())
            s.noise_threshold = float(tol);
        else
            s.adaptive_tol = float(tol);
    } else if (sampler->reads_tolerance()) {
        usage("--adaptive cs184 needs -a BATCH TOLERANCE");
    } else {
        s.adaptive_batch = kDefaultAdaptiveBatch;
        s.noise_threshold = a.noise_threshold;
    }
    // The last sample index a pixel can reach: the relative sampler may give one pixel several
    // times the budget's average.
    const int last = sampler->most_per_pixel();
    if (s.sample_offset + std::uint64_t(last) > std::uint64_t(cli::kMaxIndex))
        usage("--sample-offset: " + std::to_string(s.sample_offset) + " + " +
              (last > s.spp ? "the relative sampler's largest count per pixel, " : "-s ") +
              std::to_string(last) + ", exceeds " + std::to_string(cli::kMaxIndex));
}

/// The remaining choices and flags into the settings, and the output file and its kind.
void settle_engine_and_output(RenderArgs& a) {
    RenderSettings& s = a.settings;
    check_setting_choices(a);
    s.aovs = AovSet::parse(a.aov);
    parse_exr_options(a);
    cli::check_choice(a, "--camera", kCameraModes);
    if (a.output.empty()) a.output = default_output_path(a.scene);
    a.output_kind = output_kind(a.output);
    if (a.output_kind == OutputKind::Unsupported)
        usage("-f/--output: '" + a.output + "': no image format for this extension (use " +
              writable_extensions() + ")");
}

/// A flag that does nothing in some combination: "FLAG has no effect REASON".
struct NoEffect {
    std::vector<const char*> flags;           ///< each given one is named (long forms)
    bool first_only;                          ///< name only the first of `flags` given
    bool (*applies)(const RenderArgs&);       ///< the combination in which they do nothing
    std::string (*reason)(const RenderArgs&); ///< the words after "has no effect"
};

bool writes_8bit(const RenderArgs& a) {
    return a.output_kind == OutputKind::Ldr || !a.preview_path().empty();
}

/// Every flag that can do nothing, in the order the warnings are given (the first is the error
/// under --strict).
const std::vector<NoEffect>& no_effect_table() {
    using A = const RenderArgs&;
    const auto flag = [](Setting id) { return setting_row(id).flag.c_str(); };
    static const std::vector<NoEffect> table = {
        {{"--exposure", "--tonemap", "--look"},
         true,
         [](A a) { return !writes_8bit(a); },
         [](A) {
             return std::string(": no 8-bit image is written (add --preview, or -f with .png, "
                                ".jpg, .tif, ...)");
         }},
        {{"--preview"},
         false,
         [](A a) { return a.output_kind != OutputKind::Exr; },
         [](A) { return std::string(": it adds a PNG beside an .exr output"); }},
        {{flag(Setting::Aov)},
         false,
         [](A a) { return a.output_kind != OutputKind::Exr; },
         [](A) { return std::string(": auxiliary channels are written to .exr outputs only"); }},
        {{"--half", "--compression", "--background-depth"},
         false,
         [](A a) { return a.output_kind != OutputKind::Exr; },
         [](A) { return std::string(": it concerns .exr outputs only"); }},
        {{flag(Setting::Hemisphere), flag(Setting::LightSamples), flag(Setting::LightSampler),
          flag(Setting::Mis), flag(Setting::LightPaths), flag(Setting::MaxDepth),
          flag(Setting::Accumulate), flag(Setting::RrDepth), "--env"},
         false,
         [](A a) { return a.settings.integrator == IntegratorKind::Normals; },
         [](A) { return std::string(" with --integrator normals (it traces camera rays only)"); }},
        {{flag(Setting::RrDepth)},
         false,
         [](A a) { return a.settings.rr_min_depth > a.settings.max_depth; },
         [](A a) {
             return " with -m/--max-depth " + std::to_string(a.settings.max_depth) +
                    ": Russian roulette would start at bounce " +
                    std::to_string(a.settings.rr_min_depth) +
                    ", after every path has ended (paths are cut at -m)";
         }},
        {{flag(Setting::NoiseThreshold)},
         false,
         [](A a) { return !make_pass_policy(a.settings)->reads_noise_threshold(); },
         [](A a) {
             return std::string(" with --adaptive ") +
                    enum_name(kAdaptiveKinds, a.settings.adaptive);
         }},
        {{flag(Setting::NoiseThreshold)},
         false,
         [](A a) { return !a.adaptive.empty(); },
         [](A) { return std::string(" with -a (its TOLERANCE is the threshold)"); }},
        {{flag(Setting::AdaptiveBatch)},
         false,
         [](A a) { return !make_pass_policy(a.settings)->reads_batch(); },
         [](A) { return std::string(" with --adaptive none"); }},
        {{flag(Setting::PassSpp)},
         false,
         [](A a) { return !make_pass_policy(a.settings)->reads_pass_spp(); },
         [](A) {
             return std::string(" with adaptive sampling (a pass is one adaptive batch; "
                                "--adaptive none renders uniform passes)");
         }},
        {{flag(Setting::Triangle)},
         false,
         [](A a) { return a.settings.accel.kind == AccelKind::Embree; },
         [](A) {
             return std::string(
                 " with --accel embree (it selects the builtin and brute triangle test)");
         }},
        {{flag(Setting::EmbreeRobust), flag(Setting::EmbreeQuality)},
         false,
         [](A a) { return a.settings.accel.kind != AccelKind::Embree; },
         [](A a) {
             return std::string(" with --accel ") + accel_kind_name(a.settings.accel.kind);
         }},
        {{"--camera"},
         false,
         [](A a) { return !a.camera_file.empty(); },
         [](A) { return std::string(" with -c (the camera file sets the pose)"); }},
        {{"--framing"},
         false,
         [](A a) { return !a.camera_file.empty(); },
         [](A) {
             return std::string(" with -c (the camera file's field of view spans the image, "
                                "as in the course)");
         }},
    };
    return table;
}

/// The warnings of no_effect_table() for the options given.
std::vector<std::string> no_effect_warnings(const RenderArgs& a) {
    std::vector<std::string> w;
    for (const NoEffect& rule : no_effect_table()) {
        if (!rule.applies(a)) continue;
        for (const char* flag : rule.flags) {
            if (!a.given.count(flag)) continue;
            w.push_back(std::string(cli::find_spec(flag)->display) + " has no effect" +
                        rule.reason(a));
            if (rule.first_only) break;
        }
    }
    return w;
}

/// The files a render reads, as the output rule names them.
std::vector<NamedPath> render_inputs(const RenderArgs& a) {
    std::vector<NamedPath> in = {
        {"the scene file", a.scene}, {"-e/--env", a.env_map}, {"-c/--camera-file", a.camera_file}};
    // A resumed checkpoint is rewritten by the render it holds (its own output).
    if (!a.resume.empty() && !same_file_or_path(a.resume, a.checkpoint_path()))
        in.push_back({"--resume", a.resume});
    return in;
}

/// The files a render writes, as the output rule names them.
std::vector<NamedPath> render_outputs(const RenderArgs& a) {
    return {{"-f/--output", a.output},
            {"--preview's PNG", a.preview_path()},
            {"the sample-rate image", a.rate_path()},
            {a.checkpoint.empty() || a.checkpoint == a.resume ? "the checkpoint" : "--checkpoint",
             a.checkpoint_path()}};
}

/// A new render never starts silently over the checkpoint of an earlier one (nor over any other
/// file at the checkpoint's path): it is refused unless --overwrite is given.
void check_earlier_checkpoint(const RenderArgs& a, const std::string& ckpt) {
    std::error_code ec;
    if (!a.resume.empty() || a.overwrite || !fs::exists(ckpt, ec)) return;
    if (looks_like_checkpoint(ckpt))
        throw Error(ErrorKind::Usage, SourceLoc{ckpt},
                    "the checkpoint of an earlier render of " + a.output +
                        " is here; continue that render with: candela render --resume " + ckpt +
                        " (or start this one anyway with --overwrite: the checkpoint is kept "
                        "until this render holds more samples)");
    throw Error(ErrorKind::Usage, SourceLoc{ckpt},
                "a file that is not a candela checkpoint is at this render's checkpoint path; "
                "refusing to replace it (give --checkpoint another path, or --overwrite)");
}

} // namespace

void finalize_render_args(RenderArgs& a) {
    settle_log_and_scene(a);
    check_ranges(a);
    settle_view(a);
    settle_frame(a);
    settle_adaptive(a);
    settle_engine_and_output(a);
    // Flags that do nothing in this combination: a warning, an error under --strict.
    a.warnings = no_effect_warnings(a);
    if (a.strict && !a.warnings.empty()) usage(strict_text(a.warnings.front()));
}

void check_scene_file(const std::string& path) {
    const std::string ext = path_extension(path);
    if (!ext.empty() && ext != ".dae")
        throw Error(ErrorKind::Scene, SourceLoc{path}, "only COLLADA (.dae) scenes are read");
    const std::string why = file_read_failure(path);
    if (!why.empty()) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot open scene file: " + why);
    std::error_code ec;
    if (fs::is_regular_file(path, ec) && fs::file_size(path, ec) == 0 && !ec)
        throw Error(ErrorKind::Scene, SourceLoc{path}, "empty file");
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
            throw Error(ErrorKind::Io, SourceLoc{a.env_map}, "not a 2-D image");
    }
    // Outputs: none replaces an input or another output, each is writable.
    check_distinct_files(render_inputs(a), render_outputs(a));
    for (const RenderImage& o : render_images(a))
        check_image_location(o.path);
    check_image_module_found();
    const std::string ckpt = a.checkpoint_path();
    check_earlier_checkpoint(a, ckpt);
    check_file_writable(ckpt, "checkpoint");
}

} // namespace candela
