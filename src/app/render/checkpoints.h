#pragma once
// Checkpoints of `candela render`: resuming from one, writing them (periodically, on interrupt,
// on the second Ctrl-C) and the state after the last finished pass that they are made of.
#include "report.h"

#include "candela/app/cli.h"
#include "candela/render/checkpoint.h"
#include "candela/render/distributed.h"
#include "candela/render/renderer.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace candela::app {

/// What a resume needs besides the settings: where the render stands and what it took so far.
struct ResumeFrom {
    RenderState state;
    double seconds = 0.0;
    int sessions = 0;
    std::vector<std::string> commands; ///< of the sessions so far (none from old checkpoints)
    bool active = false;
    RenderSettings before; ///< the checkpoint's settings, before a refinement changed them
};

/// Turns `--resume CKPT [options]` into the checkpoint's own settings (with this invocation's
/// runtime options) and its state; refuses changed settings or a changed scene file.
ResumeFrom prepare_resume(RenderArgs& args);

/// Writes the checkpoints of one render (on the root rank only). A checkpoint is insurance: a
/// failed one never costs the render or its image.
class CheckpointWriter {
  public:
    CheckpointWriter(const RenderArgs& args, const DistributedContext& ctx, std::string path,
                     double earlier_seconds, int sessions,
                     const std::vector<std::string>& commands);

    /// Writes a checkpoint of `st`, unless an earlier render's checkpoint at the path holds at
    /// least as many samples (holds_earlier(): nothing written, not a failure); a failure is a
    /// warning during the render (`periodic`) and left to the caller to report at the end
    /// (failure()).
    bool save(const RenderState& st, double seconds_so_far, bool periodic);

    const std::string& path() const { return path_; }
    bool wrote() const { return wrote_; }
    /// The checkpoint of an earlier render (--overwrite) is still at the path: this render has
    /// not yet held more samples than it, so save() left it in place.
    bool holds_earlier() const { return earlier_ && !wrote_; }
    /// The samples of that earlier checkpoint.
    std::uint64_t earlier_samples() const { return earlier_samples_; }
    /// Whether `st` holds more samples than the earlier checkpoint (true when there is none):
    /// only then may it replace or remove that checkpoint.
    bool outweighs_earlier(const RenderState& st) const;
    /// The line that says the earlier checkpoint stays, and why, against this render's `st`.
    std::string earlier_kept_line(const RenderState& st) const;
    /// The last failed write's error, reported once.
    const std::optional<Error>& failure() const { return failure_; }

  private:
    bool root_;
    std::string path_;
    std::string output_; ///< the render's image, for the messages
    double earlier_seconds_;
    Checkpoint ck_;
    bool wrote_ = false;
    bool earlier_ = false;
    std::uint64_t earlier_samples_ = 0;
    std::optional<Error> failure_;
};

/// The state after the last finished pass, for the second Ctrl-C (single process only: under
/// MPI the ranks must stop together at a pass boundary), and the periodic checkpoints.
struct PassWatch {
    explicit PassWatch(const RenderState& start) : snapshot(start) {}
    std::mutex mutex; ///< held while checkpointing too: the second Ctrl-C's writer uses it
    RenderState snapshot;
    bool any_pass = false;      ///< a pass of this session has finished (snapshot is new)
    Stopwatch render_time;      ///< since the render began
    Stopwatch since_checkpoint; ///< since the last periodic checkpoint
};

/// What to do after each pass: keep the snapshot and write the periodic checkpoint when due.
std::function<void(const RenderState&)> pass_callback(PassWatch& watch, const RenderArgs& args,
                                                      const DistributedContext& ctx,
                                                      CheckpointWriter& checkpoints);

/// The second Ctrl-C's writer: the image and checkpoint of the last finished pass, at once.
/// Returns the exit status.
int write_last_pass(const ImageJob& job, PassWatch& watch, CheckpointWriter& checkpoints);

} // namespace candela::app
