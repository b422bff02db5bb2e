// Resuming, writing checkpoints and the second Ctrl-C's writer of `candela render`
// (checkpoints.h).
#include "checkpoints.h"

#include "candela/render/adaptive.h"
#include "candela/util/log.h"

#include <algorithm>
#include <cstdio>
#include <fmt/format.h>
#include <utility>

namespace candela::app {

namespace {

/// Sets option `name`'s one value in a canonical argument list, adding the option when absent.
void set_canonical_arg(std::vector<std::string>& args, const std::string& name,
                       const std::string& value) {
    const auto it = std::find(args.begin(), args.end(), name);
    if (it != args.end() && it + 1 != args.end()) {
        *(it + 1) = value;
        return;
    }
    args.push_back(name);
    args.push_back(value);
}

} // namespace

ResumeFrom prepare_resume(RenderArgs& args) {
    // This invocation's log options decide what the refusal messages look like.
    set_log_level(log_level_of(args.log));
    Checkpoint ck = read_checkpoint(args.resume);
    RenderArgs stored = parse_render_command_line(ck.args);
    check_resume_matches(args, stored, args.resume);
    // A refinement (a larger -s, a lower noise threshold) becomes the render's own setting.
    const RenderSettings before = stored.settings;
    const std::string& spp = setting_row(Setting::Spp).flag;
    const std::string& threshold = setting_row(Setting::NoiseThreshold).flag;
    const bool more_samples = args.given.count(spp) && args.settings.spp != before.spp;
    const bool lower_threshold =
        args.given.count(threshold) && args.noise_threshold != stored.noise_threshold;
    if (more_samples) set_canonical_arg(ck.args, spp, std::to_string(args.settings.spp));
    if (lower_threshold)
        set_canonical_arg(ck.args, threshold, fmt::format("{:.9g}", double(args.noise_threshold)));
    if (more_samples || lower_threshold)
        stored = parse_render_command_line(ck.args);
    else if (make_pass_policy(before)->finished(ck.state))
        throw Error(ErrorKind::Usage, SourceLoc{args.resume},
                    "nothing to refine: it holds a finished render; give a larger -s or a lower "
                    "--noise-threshold to refine it");
    // Runtime options come from this invocation.
    stored.settings.threads = args.settings.threads;
    stored.log = args.log;
    stored.strict = args.strict;
    stored.settings.progress = args.settings.progress;
    if (const auto it = args.unknown_choices.find(setting_row(Setting::Progress).flag);
        it != args.unknown_choices.end())
        stored.unknown_choices[it->first] = it->second;
    stored.max_memory = args.max_memory;
    stored.checkpoint = args.checkpoint.empty() ? args.resume : args.checkpoint;
    stored.checkpoint_every = args.checkpoint_every;
    stored.resume = args.resume;
    stored.keep_checkpoint = args.keep_checkpoint;
    stored.write_every = args.write_every;
    stored.display_server = args.display_server;
    finalize_render_args(stored);
    if (file_hash(stored.scene) != ck.scene_hash)
        throw Error(ErrorKind::Usage, SourceLoc{args.resume},
                    "refusing to resume: the scene file '" + stored.scene +
                        "' has changed since the checkpoint");
    if ((stored.env_map.empty() ? 0 : file_hash(stored.env_map)) != ck.env_hash)
        throw Error(ErrorKind::Usage, SourceLoc{args.resume},
                    "refusing to resume: the "
                    "environment map has changed since the "
                    "checkpoint");
    args = std::move(stored);
    ResumeFrom r;
    r.state = std::move(ck.state);
    r.seconds = ck.render_seconds;
    r.sessions = ck.sessions;
    r.commands = std::move(ck.commands);
    r.active = true;
    r.before = before;
    return r;
}

CheckpointWriter::CheckpointWriter(const RenderArgs& args, const DistributedContext& ctx,
                                   std::string path, double earlier_seconds, int sessions,
                                   const std::vector<std::string>& commands)
    : root_(ctx.root()), path_(std::move(path)), output_(args.output),
      earlier_seconds_(earlier_seconds) {
    // Only under --overwrite (check_render_files refuses the render otherwise).
    earlier_ = root_ && args.resume.empty() && looks_like_checkpoint(path_);
    if (earlier_) {
        try {
            earlier_samples_ = read_checkpoint(path_).state.film.total_samples();
        } catch (const Error&) {
            earlier_samples_ = 0; // a damaged checkpoint holds nothing to keep
        }
    }
    ck_.args = canonical_render_args(args);
    ck_.scene_hash = file_hash(args.scene);
    ck_.env_hash = args.env_map.empty() ? 0 : file_hash(args.env_map);
    ck_.sessions = sessions;
    ck_.commands = commands;
}

bool CheckpointWriter::outweighs_earlier(const RenderState& st) const {
    return !holds_earlier() || st.film.total_samples() > earlier_samples_;
}

std::string CheckpointWriter::earlier_kept_line(const RenderState& st) const {
    return "candela: kept the earlier render's checkpoint " + path_ + ": it holds " +
           std::to_string(earlier_samples_) + " samples, this render " +
           std::to_string(st.film.total_samples()) +
           " (continue that render with: candela render --resume " + path_ + ", which writes " +
           output_ + " again)";
}

bool CheckpointWriter::save(const RenderState& st, double seconds_so_far, bool periodic) {
    if (!root_) return true;
    if (!outweighs_earlier(st)) return true;
    ck_.state = st; // a copy: the render goes on with its own
    ck_.render_seconds = earlier_seconds_ + seconds_so_far;
    try {
        write_checkpoint(path_, ck_);
        wrote_ = true;
        return true;
    } catch (const Error& e) {
        // A periodic failure is a warning, once per distinct failure.
        if (periodic && (!failure_ || failure_->what() != std::string(e.what())) &&
            log_level() >= LogLevel::Warning)
            fmt::print(stderr, "{}\n", warning_line(e));
        failure_ = e;
        return false;
    }
}

std::function<void(const RenderState&)> pass_callback(PassWatch& watch, const RenderArgs& args,
                                                      const DistributedContext& ctx,
                                                      CheckpointWriter& checkpoints) {
    return [&watch, &args, &ctx, &checkpoints](const RenderState& st) {
        std::lock_guard<std::mutex> lock(watch.mutex);
        if (ctx.size() == 1) watch.snapshot = st;
        watch.any_pass = true;
        if (args.checkpoint_every <= 0.0) return;
        if (watch.since_checkpoint.seconds() < args.checkpoint_every ||
            make_pass_policy(args.settings)->finished(st))
            return;
        watch.since_checkpoint.restart();
        checkpoints.save(st, watch.render_time.seconds(), true);
    };
}

int write_last_pass(const ImageJob& job, PassWatch& watch, CheckpointWriter& checkpoints) {
    std::lock_guard<std::mutex> lock(watch.mutex);
    if (!watch.any_pass) {
        say_nothing_written(job.args);
        print_json_done(job.args, nullptr, watch.snapshot, nullptr, {},
                        static_cast<int>(ErrorKind::Interrupted), job.args.resume);
        return static_cast<int>(ErrorKind::Interrupted);
    }
    const double seconds = watch.render_time.seconds();
    std::vector<std::string> written;
    int status = static_cast<int>(ErrorKind::Interrupted);
    try {
        written = write_job_images(job, watch.snapshot.film, seconds, true);
    } catch (const Error& e) {
        fmt::print(stderr, "{}\n", error_line(e));
        status = static_cast<int>(e.kind());
    }
    if (!checkpoints.save(watch.snapshot, seconds, false)) {
        fmt::print(stderr, "{}\n", error_line(*checkpoints.failure()));
        status = static_cast<int>(ErrorKind::Io);
    }
    const std::string& ckpt_path = checkpoints.path();
    if (checkpoints.holds_earlier() && log_level() >= LogLevel::Warning)
        fmt::print(stderr, "{}\n", checkpoints.earlier_kept_line(watch.snapshot));
    if (!job.args.settings.quiet)
        fmt::print(stderr, "candela: stopped now; wrote {} with {}{}\n", join(written),
                   reached_text(job.args.settings, watch.snapshot),
                   checkpoints.wrote()
                       ? (" and checkpoint " + ckpt_path +
                          " (continue with: candela render --resume " + ckpt_path + ")")
                             .c_str()
                       : "");
    print_json_done(job.args, nullptr, watch.snapshot, nullptr, written, status,
                    checkpoints.wrote() ? ckpt_path : "");
    return status;
}

} // namespace candela::app
