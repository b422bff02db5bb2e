// The declarations of `candela render`'s options (CS184 short flags plus long forms), in the
// order --help lists them, and the record of which were given.
#include "../cli_support.h"
#include "candela/app/cli.h"

#include "candela/io/tev_client.h"

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
CLI::Option* add_index_option(CLI::App& app, const std::string& flag, std::uint64_t& target,
                              const std::string& help) {
    return app
        .add_option_function<long long>(
            flag,
            [&target, flag](const long long& v) {
                if (v < 0)
                    cli::usage(flag + ": " + std::to_string(v) + " is out of range [0, " +
                               std::to_string(cli::kMaxIndex) + "]");
                target = std::uint64_t(v);
            },
            help)
        ->default_str(std::to_string(target));
}

/// The CS184 path tracer's flags (with long forms) and the scene argument.
void add_cs184_options(CLI::App& app, RenderArgs& a) {
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
                   "CS184 camera settings file: 30 numbers (docs/usage.md \"Camera files\")");
    app.add_option("-a,--adaptive-sampling", a.adaptive,
                   "Adaptive sampling: BATCH TOLERANCE (CS184: batch 32, tolerance 0.05)")
        ->expected(2)
        ->allow_extra_args(false);
    app.add_flag("-H,--hemisphere", s.hemisphere,
                 "Direct light by uniform hemisphere sampling instead of light sampling");
}

/// Adaptive sampling and the time budget.
void add_sampling_options(CLI::App& app, RenderArgs& a) {
    RenderSettings& s = a.settings;
    add_choice(app, a, "--adaptive", kAdaptiveKinds, a.adaptive_kind,
               "Adaptive sampling: " + enum_choices(kAdaptiveKinds));
    app.add_option("--noise-threshold", a.noise_threshold,
                   "Relative sampler: stop when the estimated relative RMS error of the image "
                   "falls to this (0 = spend the whole -s budget); -a's TOLERANCE replaces it")
        ->capture_default_str();
    app.add_option("--time-budget", s.time_budget,
                   "Stop starting passes after SECONDS of rendering (whole passes; -s stays the "
                   "maximum); 0 = no limit")
        ->capture_default_str();
}

/// The camera, the accelerator and the estimator.
void add_engine_options(CLI::App& app, RenderArgs& a) {
    RenderSettings& s = a.settings;
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
}

/// What the image files hold: EXR channels and 8-bit tone mapping.
void add_image_options(CLI::App& app, RenderArgs& a) {
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
}

/// How the render runs: strictness, passes, checkpoints, memory and log.
void add_run_options(CLI::App& app, RenderArgs& a) {
    RenderSettings& s = a.settings;
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
    app.add_flag("--overwrite", a.overwrite,
                 "Start a new render although the checkpoint of an earlier one is at its "
                 "checkpoint path (it is replaced once this render holds more samples; without "
                 "this flag the render is refused: --resume continues the earlier one)");
    add_choice(app, a, "--progress", kProgressModes, s.progress, enum_choices(kProgressModes))
        ->default_str(progress_mode_name(s.progress));
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
