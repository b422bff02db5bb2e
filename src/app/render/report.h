#pragma once
// What `candela render` writes and says: the image files with their metadata, the line before
// the render, the summary after it and the JSON start and done events of --progress json.
#include "candela/app/cli.h"
#include "candela/render/distributed.h"
#include "candela/render/refine.h"
#include "candela/render/renderer.h"
#include "candela/scene/scene.h"

#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace candela::app {

/// The phases of a render command, back to back from the start of the process, so that they
/// add up to what the user waited: start-up (the executable's libraries, the command line, the
/// file checks), loading the scene, building the accelerator, rendering (with its set-up) and
/// writing the files (with any wait for the image module).
struct Timings {
    double startup = 0.0, load = 0.0, build = 0.0, render = 0.0, write = 0.0, total = 0.0;
};

/// Times consecutive phases from the start of the process (process_seconds()).
class PhaseClock {
  public:
    /// Seconds since the previous lap (the first: since the process started).
    double lap();
    /// Seconds from the process's start to the last lap.
    double total() const { return last_; }

  private:
    double last_ = 0.0;
};

/// What a render needs to write its images at any moment.
struct ImageJob {
    const RenderArgs& args;
    const Scene& scene;
    const DistributedContext& ctx;
    double earlier_seconds; ///< render time of the sessions before this one
    int sessions;           ///< including this one
    /// The command of every session known, this one last: the first reproduces the image.
    std::vector<std::string> commands;
    int rate_max; ///< samples per pixel at the red end of the sample-rate ramp
    /// A refinement's prediction of its render time (render/refine.h), for the stats block.
    std::optional<RefineForecast> forecast;
    /// A new render to the default output name (no -f): images already there are kept under
    /// numbered names (keep_numbered_backups) just before the first write.
    bool keep_earlier_images = false;
    mutable std::once_flag kept_earlier; ///< that happens once
};

/// Writes the image files of `film` (the output, the preview, the sample-rate image) with the
/// metadata of `job`; returns the paths written.
std::vector<std::string> write_job_images(const ImageJob& job, const Film& film, double seconds,
                                          bool interrupted);

/// "a, b, c".
std::string join(const std::vector<std::string>& v);

/// What -s means in this render, for the line before it: a budget, a cap or a count.
std::string sampling_text(const RenderSettings& s);
/// How far an interrupted render got, in the words of sampling_text().
std::string reached_text(const RenderSettings& s, const RenderState& state);

/// An interrupt before the first pass of this session finished: no file is written, so an image
/// (or checkpoint) already at the output path is left as it was rather than replaced by one with
/// no new samples.
void say_nothing_written(const RenderArgs& args);

/// The files written, the sample-rate image's legend (its ramp ends at `rate_max` samples per
/// pixel) when one was written, and the stats block.
void print_summary(const RenderArgs& args, const RenderStats& stats, const Film& film,
                   const Timings& t, const std::vector<std::string>& written,
                   const std::optional<RefineForecast>& forecast, int rate_max);

/// The first line of --progress json; after the signal handlers are in place, since a farm
/// manager may interrupt as soon as it reads it.
void print_json_start(const RenderArgs& args, const DistributedContext& ctx, bool resumed);

/// The last line of --progress json. Without `stats` and `t` (the second Ctrl-C's fast exit,
/// which has no counters of the pass it cut short) it leaves out the counters and times.
/// `checkpoint` is the checkpoint written, if any: the event names it and how to resume it.
/// A refinement's `forecast` adds its predicted render time.
void print_json_done(const RenderArgs& args, const RenderStats* stats, const RenderState& state,
                     const Timings* t, const std::vector<std::string>& written, int status,
                     const std::string& checkpoint,
                     const std::optional<RefineForecast>& forecast = std::nullopt);

} // namespace candela::app
