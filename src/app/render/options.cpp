// The declarations of `candela render`'s options (CS184 short flags plus long forms), in the
// order --help lists them, and the record of which were given.
#include "../cli_support.h"
#include "candela/app/cli.h"

#include "candela/io/tev_client.h"
#include "candela/render/setting_table.h"
#include "candela/util/check.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace candela {

namespace {

/// Declares the choice option `flag`, parsed by `table` into `target`; a value that names no
/// choice is kept in args.unknown_choices for finalize_render_args to report.
/// `target` is the enum itself or an optional of it.
template <typename E, std::size_t N, typename Target>
CLI::Option* add_choice(CLI::App& app, RenderArgs& a, const std::string& flag,
                        const EnumTable<E, N>& table, Target& target, const std::string& help) {
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
CLI::Option* add_index_option(CLI::App& app, const std::string& names, std::uint64_t& target,
                              const std::string& help) {
    const std::string flag = names.substr(names.rfind(',') + 1);
    return app
        .add_option_function<long long>(
            names,
            [&target, flag](const long long& v) {
                if (v < 0)
                    cli::usage(flag + ": " + std::to_string(v) + " is out of range [0, " +
                               std::to_string(cli::kMaxIndex) + "]");
                target = std::uint64_t(v);
            },
            help)
        ->default_str(std::to_string(target));
}

/// Declares the option of a render setting as its row (render/setting_table.h) says. A row the
/// command line settles itself (SettingType::Custom) is declared by hand, naming its row.
CLI::Option* add_setting(CLI::App& app, RenderArgs& a, Setting id) {
    const SettingRow& row = setting_row(id);
    RenderSettings& s = a.settings;
    switch (row.type) {
    case SettingType::Int:
        return app.add_option(row.names, *static_cast<int*>(row.field(s)), row.help)
            ->capture_default_str();
    case SettingType::Index:
        return add_index_option(app, row.names, *static_cast<std::uint64_t*>(row.field(s)),
                                row.help);
    case SettingType::Seconds:
        return app.add_option(row.names, *static_cast<double*>(row.field(s)), row.help)
            ->capture_default_str();
    case SettingType::Flag:
        if (row.flag_value)
            return app.add_flag(row.names, *static_cast<bool*>(row.field(s)), row.help);
        return app.add_flag_function(
            row.names,
            [&s, &row](std::int64_t) { *static_cast<bool*>(row.field(s)) = row.flag_value; },
            row.help);
    case SettingType::Choice:
        return app
            .add_option_function<std::string>(
                row.names,
                [&a, &row](const std::string& v) {
                    if (row.set_choice(a.settings, v))
                        a.unknown_choices.erase(row.flag);
                    else
                        a.unknown_choices[row.flag] = v;
                },
                row.help)
            ->default_str(row.text(s));
    case SettingType::Custom:
        break;
    }
    CANDELA_CHECK(false, row.flag + ": declared by hand");
    return nullptr;
}

/// The CS184 path tracer's flags (with long forms) and the scene argument.
void add_cs184_options(CLI::App& app, RenderArgs& a) {
    app.add_option("scene", a.scene, "COLLADA scene file (.dae)");
    app.add_option("-f,--output", a.output,
                   "Output image: .exr (HDR with alpha and auxiliary channels), an 8-bit "
                   "preview in any format OpenImageIO writes (.png, .jpg, .tif, ...; with "
                   "--tonemap and --exposure) or .hdr (linear RGB). Default: <scene name>.exr "
                   "in the current directory");
    add_setting(app, a, Setting::Spp);
    add_setting(app, a, Setting::LightSamples);
    add_setting(app, a, Setting::Threads);
    add_setting(app, a, Setting::MaxDepth);
    const SettingRow& accumulate = setting_row(Setting::Accumulate);
    app.add_option(accumulate.names, a.accumulate, accumulate.help)->capture_default_str();
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
                   "CS184 camera settings file: 30 numbers (docs/usage.md \"Camera files\")");
    const SettingRow& batch = setting_row(Setting::AdaptiveBatch);
    app.add_option(batch.names, a.adaptive, batch.help)->expected(2)->allow_extra_args(false);
    add_setting(app, a, Setting::Hemisphere);
}

/// Adaptive sampling and the time budget.
void add_sampling_options(CLI::App& app, RenderArgs& a) {
    const SettingRow& adaptive = setting_row(Setting::Adaptive);
    add_choice(app, a, adaptive.flag, kAdaptiveKinds, a.adaptive_kind, adaptive.help);
    const SettingRow& threshold = setting_row(Setting::NoiseThreshold);
    app.add_option(threshold.names, a.noise_threshold, threshold.help)->capture_default_str();
    add_setting(app, a, Setting::TimeBudget);
}

/// The camera, the accelerator and the estimator.
void add_engine_options(CLI::App& app, RenderArgs& a) {
    add_choice(app, a, "--camera", kCameraModes, a.build.camera_mode,
               enum_choices(kCameraModes, {"; ", "; ", ": ", ""}))
        ->default_str(enum_name(kCameraModes, a.build.camera_mode));
    add_choice(app, a, "--framing", kFramings, a.build.framing,
               "How -r meets the field of view: " + enum_choices(kFramings, {"; ", "; "}))
        ->default_str(enum_name(kFramings, a.build.framing));
    app.add_option("--look-from", a.look_from,
                   "Put the camera at X Y Z (world space; up is world +Y)")
        ->expected(3)
        ->allow_extra_args(false);
    app.add_option("--look-at", a.look_at, "Aim the camera at X Y Z (world space)")
        ->expected(3)
        ->allow_extra_args(false);
    app.add_option_function<float>(
        "--fov", [&a](const float& v) { a.fov = v; },
        "Horizontal field of view in degrees, in (0, 180) (with --framing cs184: the 800x600 "
        "view's)");
    for (Setting id :
         {Setting::Accel, Setting::Triangle, Setting::EmbreeRobust, Setting::EmbreeQuality,
          Setting::Seed, Setting::SampleOffset, Setting::Sampler, Setting::LightSampler,
          Setting::Integrator, Setting::LightPaths, Setting::Mis, Setting::RrDepth})
        add_setting(app, a, id);
}

/// What the image files hold: EXR channels and 8-bit tone mapping.
void add_image_options(CLI::App& app, RenderArgs& a) {
    const SettingRow& aov = setting_row(Setting::Aov);
    app.add_option(aov.names, a.aov, aov.help)->capture_default_str();
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
}

/// How the render runs: strictness, passes, checkpoints, memory and log.
void add_run_options(CLI::App& app, RenderArgs& a) {
    app.add_flag("--strict", a.strict, "Treat scene warnings and flags that do nothing as errors");
    add_setting(app, a, Setting::PassSpp);
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
    app.add_flag("--overwrite", a.overwrite,
                 "Start a new render although the checkpoint of an earlier one is at its "
                 "checkpoint path (it is replaced once this render holds more samples; without "
                 "this flag the render is refused: --resume continues the earlier one)");
    add_setting(app, a, Setting::Progress);
    add_log_options(app, a.log);
}

/// Watching a render while it runs: its image written now and then, or streamed to a viewer.
void add_watch_options(CLI::App& app, RenderArgs& a) {
    app.add_option_function<double>(
        "--write-every",
        [&a](const double& v) {
            if (!(v > 0.0) || !std::isfinite(v))
                cli::usage("--write-every must be a finite number of seconds > 0");
            a.write_every = v;
        },
        "While the render runs, write its image so far (and the preview and sample-rate "
        "image where asked) every SECONDS at most, at pass boundaries");
    app.add_option_function<std::string>(
           "--display-server",
           [&a](const std::string& v) {
               if (!parse_tev_address(v))
                   cli::usage("--display-server: '" + v +
                              "' is not HOST:PORT (tev listens on 127.0.0.1:14158)");
               a.display_server = v;
           },
           "Stream the image to the tev viewer at HOST:PORT after each pass (at most twice a "
           "second) and at the end, as pbrt-v4's --display-server does")
        ->type_name("HOST:PORT");
}

} // namespace

void add_render_options(CLI::App& app, RenderArgs& a) {
    add_cs184_options(app, a);
    add_sampling_options(app, a);
    add_engine_options(app, a);
    add_image_options(app, a);
    add_run_options(app, a);
    add_watch_options(app, a);
}

void record_given_options(const CLI::App& app, RenderArgs& a) {
    for (const CLI::Option* o : app.get_options()) {
        if (o->count() == 0) continue;
        const std::vector<std::string>& l = o->get_lnames();
        a.given.insert(l.empty() ? o->get_name() : "--" + l.front());
    }
}

} // namespace candela
