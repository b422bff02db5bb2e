#pragma once
// Command-line options of `candela render` (CS184 short flags plus long forms), their
// validation before any work, and what every subcommand shares: log options, error wording and
// suggestions. Part of the app library (not the renderer core) so tests can parse command lines
// without running a render.
#include "candela/io/camera_file.h"
#include "candela/io/image_io.h"
#include "candela/render/output.h"
#include "candela/render/setting_table.h"
#include "candela/scene/builder.h"
#include "candela/util/enum_table.h"
#include "candela/util/log.h"

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace CLI {
class App;
class ParseError;
} // namespace CLI

namespace candela {

/// `-q`, `-v` and `--log-level`, on every subcommand.
struct LogArgs {
    bool quiet = false;
    bool verbose = false;
    std::string level; ///< --log-level; "" = from -q / -v, else info
};
void add_log_options(CLI::App& app, LogArgs& args);
/// The level the options ask for (Error(Usage) when they contradict each other).
LogLevel log_level_of(const LogArgs& args);

/// The options of `candela render`. The render settings' options are declared by their rows in
/// render/setting_table.h and parsed straight into `settings` (those a row marks Custom pass
/// through the fields below first); the other choice options (--camera, --tonemap, ...) are
/// parsed into their enums by the tables beside each enum. A render starts from
/// command_line_settings(), the table's defaults.
struct RenderArgs {
    RenderArgs() : settings(command_line_settings()) {}

    std::string scene;
    std::string output;      ///< -f; "" = <scene stem>.exr in the current directory
    std::string camera_file; ///< -c
    std::string env_map;     ///< -e: lat-long environment map image
    std::string aov = "all"; ///< --aov: all, none or a list of channels (AovSet::parse)
    /// --adaptive; unset = relative, or cs184 when -a is given (the CS184 flag keeps its
    /// meaning).
    std::optional<AdaptiveKind> adaptive_kind;
    /// --noise-threshold: the relative sampler's stop, the estimated relative RMS error of the
    /// image; 0 = no target (the -s budget is spent).
    float noise_threshold = kDefaultNoiseThreshold;
    Tonemap tonemap = Tonemap::Clamp;    ///< --tonemap
    Look look = Look::Candela;           ///< --look
    std::vector<int> resolution;         ///< -r W H
    std::vector<int> region;             ///< -p X Y DX DY (origin bottom-left, as in CS184)
    std::vector<double> adaptive;        ///< -a BATCH TOL
    int accumulate = 1;                  ///< -o: 0 or 1
    std::optional<float> lens_radius;    ///< -b; unset keeps the camera's
    std::optional<float> focal_distance; ///< -d; unset keeps the camera's
    std::vector<float> look_from;        ///< --look-from X Y Z; empty keeps the camera's
    std::vector<float> look_at;          ///< --look-at X Y Z; empty keeps the camera's
    std::optional<float> fov;            ///< --fov DEGREES (horizontal); unset keeps the camera's
    CameraOverrides camera_overrides;    ///< the three above, checked by finalize_render_args
    float exposure = 0.f;
    bool preview = false;                 ///< --preview: PNG preview beside an EXR
    bool half = false;                    ///< --half: half-float colour channels in the EXR
    std::string compression = "zip";      ///< --compression: the EXR's compression
    std::string background_depth = "inf"; ///< --background-depth: Z where nothing was hit
    ExrOptions exr;                       ///< the three above, parsed by finalize_render_args
    std::string max_memory;               ///< --max-memory SIZE; "" = 3/4 of physical memory
    std::uint64_t max_memory_bytes = 0;   ///< parsed --max-memory (set by finalize_render_args)
    std::string resume;                   ///< --resume CHECKPOINT
    std::string checkpoint;               ///< --checkpoint PATH; "" = <output>.ckpt
    double checkpoint_every = 0.0;        ///< --checkpoint-every SECONDS; 0 = only on interrupt
    bool keep_checkpoint = false;         ///< --keep-checkpoint: a finished render keeps it too
    /// --overwrite: a new render may start where an earlier render's checkpoint is (it replaces
    /// that checkpoint only once it holds more samples).
    bool overwrite = false;
    double write_every = 0.0;   ///< --write-every SECONDS; 0 = the final image only
    std::string display_server; ///< --display-server HOST:PORT (tev); "" = none
    bool strict = false;
    LogArgs log;
    RenderSettings settings;
    BuildOptions build;
    /// Values of choice options that name none of the choices, by flag ("--accel" -> "optix"):
    /// finalize_render_args reports them, in the order it checks its options.
    std::map<std::string, std::string> unknown_choices;

    // Filled by record_given_options / finalize_render_args / check_render_files:
    std::set<std::string> given;       ///< options given explicitly ("--spp", "scene", ...)
    std::vector<std::string> warnings; ///< flags that do nothing in this combination
    OutputKind output_kind = OutputKind::Exr;
    LogLevel log_level = LogLevel::Info;
    std::optional<CameraFile> camera; ///< -c, read and checked before the scene is loaded

    /// The PNG preview written beside an EXR with --preview, "" when none.
    std::string preview_path() const;
    /// The sample-rate image (adaptive renders with an 8-bit image only), "" when none.
    std::string rate_path() const;
    /// The checkpoint file: --checkpoint, else <output>.ckpt.
    std::string checkpoint_path() const;
};

/// Declares every render option on `app`, writing into `args`.
void add_render_options(CLI::App& app, RenderArgs& args);

/// Records which options of `app` (parsed) were given, in args.given.
void record_given_options(const CLI::App& app, RenderArgs& args);

/// Checks ranges and combinations after parsing and fills args.settings / args.build from the
/// string options; touches no file. Flags that do nothing in the given combination go to
/// args.warnings, or throw Error(Usage) under --strict. Throws Error(Usage) naming the flag, or
/// Error(Scene) for a scene file that is not COLLADA.
void finalize_render_args(RenderArgs& args);

/// Parses a complete `render` argument list (without the program and subcommand names), as a
/// test or a script would: add_render_options + parse + record_given_options +
/// finalize_render_args.
RenderArgs parse_render_command_line(const std::vector<std::string>& argv);

/// Every file check a render needs before the scene is loaded: the scene file opens and is not
/// empty, the camera file (-c) parses, the environment map (-e) is a readable image, the image,
/// preview, sample-rate image and checkpoint can be created in their directories (and none
/// would overwrite the scene), and the image module's file is there. Throws Error(Io) with the
/// operating system's reason, or Error(Scene). Whether each image's format writes is the one
/// check left, check_image_format() on render_images(): it loads the image module, which a
/// render does on a thread of its own while the scene loads and renders.
void check_render_files(RenderArgs& args);

/// An image file a render writes, and its kind.
struct RenderImage {
    std::string path;
    OutputKind kind;
};
/// The image, the preview and the sample-rate image, those the settings write.
std::vector<RenderImage> render_images(const RenderArgs& args);

/// The scene file of any subcommand: a readable, non-empty .dae file. Throws Error(Io) with the
/// operating system's reason, or Error(Scene) ("only COLLADA (.dae) scenes are read", "empty
/// file").
void check_scene_file(const std::string& path);

/// The options of a render that define its image, as an argument list with absolute paths and
/// the output always given: what a checkpoint stores, so `--resume` works from any directory.
std::vector<std::string> canonical_render_args(const RenderArgs& args);

/// The options that may differ on `--resume` (they change how or where a render runs, never
/// its pixels), as "-t/--threads, -q/--quiet, ...".
std::string resume_runtime_options();

/// Refuses (Error(Usage)) an option given on the resuming command line whose value differs
/// from the checkpoint's, naming it, both values and the options that may change. A larger
/// -s and a lower --noise-threshold (relative sampler) are a refinement and pass; a smaller -s
/// or a higher threshold is refused with its own message.
void check_resume_matches(const RenderArgs& given, const RenderArgs& stored,
                          const std::string& checkpoint);

/// The default output path for a scene: its file name with the extension replaced by .exr.
std::string default_output_path(const std::string& scene_path);

/// A CLI11 parse error of `app` (the top-level app; the subcommand being parsed is found from
/// it) in candela's own words: the flag, what was wrong, the nearest valid name. A plain
/// message, as Error(Usage) carries it.
std::string describe_parse_error(const CLI::App& app, const CLI::ParseError& error);

/// The exit statuses, for the end of every --help.
const char* exit_status_help();

} // namespace candela
