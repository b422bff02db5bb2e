#pragma once
// Command-line options of `candela render` (CS184 short flags plus long forms), their
// validation and the CS184 camera settings file (-c). Kept in the library so tests can parse
// command lines without running a render.
#include "candela/render/settings.h"
#include "candela/scene/builder.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace candela {

struct RenderArgs {
    std::string scene;
    std::string output;      ///< -f; "" = <scene stem>.exr in the current directory
    std::string camera_file; ///< -c
    std::string camera_mode = "framed";
    std::string accel = "embree";
    std::string triangle = "mt";
    std::string embree_quality = "medium";
    std::string sampler = "independent";
    std::string integrator = "path";
    std::string light_paths = "all";
    std::string aov = "all";
    std::string adaptive_kind = "cs184";
    std::vector<int> resolution;         ///< -r W H
    std::vector<int> region;             ///< -p X Y DX DY (origin bottom-left, as in CS184)
    std::vector<double> adaptive;        ///< -a BATCH TOL
    int accumulate = 1;                  ///< -o
    std::optional<float> lens_radius;    ///< -b; unset keeps the camera's
    std::optional<float> focal_distance; ///< -d; unset keeps the camera's
    float exposure = 0.f;
    bool preview = false;               ///< --preview: PNG preview beside an EXR
    std::string max_memory;             ///< --max-memory SIZE; "" = 3/4 of physical memory
    std::uint64_t max_memory_bytes = 0; ///< parsed --max-memory (set by finalize_render_args)
    std::string resume;                 ///< --resume CHECKPOINT
    std::string checkpoint;             ///< --checkpoint PATH; "" = <output>.ckpt
    double checkpoint_every = 0.0;      ///< --checkpoint-every SECONDS; 0 = only on interrupt
    bool strict = false;
    bool no_mis = false;
    bool embree_robust = false;
    RenderSettings settings;
    BuildOptions build;
};

/// Declares every render option on `app`, writing into `args`.
void add_render_options(CLI::App& app, RenderArgs& args);

/// Checks ranges and combinations after parsing and fills args.settings / args.build from the
/// string options. Throws Error(Usage) naming the flag.
void finalize_render_args(RenderArgs& args);

/// Parses a complete `render` argument list (without the program and subcommand names), as a
/// test or a script would: add_render_options + parse + finalize_render_args.
RenderArgs parse_render_command_line(const std::vector<std::string>& argv);

class Scene;
/// Applies a CS184 camera settings file (spec §8.2) to the scene camera. Throws Error with
/// file:line on a malformed file.
void apply_camera_file(const std::string& path, Scene& scene);

/// Removes the options that do not change the image (threads, quiet, checkpointing, resume)
/// from a render argument list, so two lists can be compared for "same render".
std::vector<std::string> image_defining_args(const std::vector<std::string>& argv);

/// The default output path for a scene: its file name with the extension replaced by .exr.
std::string default_output_path(const std::string& scene_path);

} // namespace candela
