// `candela render`, step by step: settle the options, check the files, load the scene and
// build the accelerator, run the passes, write the outputs.
#include "../commands.h"
#include "../scene_source.h"
#include "checkpoints.h"
#include "image_format_check.h"
#include "live.h"
#include "report.h"
#include "signals.h"

#include "candela/accel/accel.h"
#include "candela/app/cli.h"
#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/io/image_io.h"
#include "candela/render/adaptive.h"
#include "candela/render/distributed.h"
#include "candela/render/memory_budget.h"
#include "candela/render/renderer.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/strings.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <atomic>
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

namespace candela::app {

namespace {

/// Settles the options (from the checkpoint on --resume), the log level of this rank and the
/// warnings about flags that do nothing; returns where a resumed render stands.
ResumeFrom settle_options(RenderArgs& args, const DistributedContext& ctx) {
    ResumeFrom resume;
    if (!args.resume.empty())
        resume = prepare_resume(args);
    else
        finalize_render_args(args);
    RenderSettings& s = args.settings;
    set_log_level(ctx.root() ? args.log_level : LogLevel::Error);
    if (!ctx.root()) {
        s.quiet = true;
        s.progress = ProgressMode::None;
    }
    for (const std::string& w : args.warnings)
        print_warning(w);
    return resume;
}

/// The scene with its camera options applied, and its accelerator.
struct LoadedScene {
    Scene scene;
    std::unique_ptr<Accel> accel;
};

/// The framed camera (CS184 placement) stands outside the scene's bounds; when the scene's own
/// camera is enclosed by geometry, the framed one sees only the outside of a closed room.
void warn_framed_outside_room(const RenderArgs& args, const Scene& scene, const Accel& accel) {
    if (!args.camera_file.empty() || !scene.file_camera_pos ||
        !enclosed_point(accel, *scene.file_camera_pos))
        return;
    const std::string what = args.scene + ": the framed camera is outside the closed room; this "
                                          "scene's camera: --camera file";
    warn_or_refuse(what, args.strict, ErrorKind::Scene);
}

/// Checks every file (the root rank; the image formats on a thread of their own, in
/// `formats`), loads the scene and builds the accelerator (timed in `t`). Loading can fail on
/// one rank only (a file missing on one node): the ranks agree on the outcome before the first
/// collective operation of the render, so none waits forever.
LoadedScene load_scene_and_accel(RenderArgs& args, const DistributedContext& ctx, Timings& t,
                                 PhaseClock& clock, std::unique_ptr<ImageFormatCheck>& formats) {
    LoadedScene loaded;
    std::exception_ptr failure;
    try {
        // Every input and output is checked before anything is loaded.
        if (ctx.root()) {
            check_render_files(args);
            formats = std::make_unique<ImageFormatCheck>(render_images(args));
        }
        t.startup = clock.lap();
        loaded.scene = load_render_scene(args);
        const Scene& scene = loaded.scene;
        t.load = clock.lap();

        // Before anything large (accelerator, film) is allocated.
        check_memory_budget(estimate_render_memory(scene, args.settings), args.max_memory_bytes);
        loaded.accel = make_accel(scene, args.settings.accel);
        t.build = clock.lap();
        warn_framed_outside_room(args, scene, *loaded.accel);
    } catch (...) {
        failure = std::current_exception();
    }
    if (ctx.any(failure != nullptr)) {
        if (failure) std::rethrow_exception(failure);
        throw Error(ErrorKind::Usage, "another MPI rank failed to load the "
                                      "scene (see its message)");
    }
    return loaded;
}

/// The notes and the one-line description of the render before it starts.
void print_render_intro(const RenderArgs& args, const DistributedContext& ctx, const Scene& scene,
                        const Accel& accel, bool resumed) {
    const RenderSettings& s = args.settings;
    if (!s.quiet && ctx.size() > 1)
        fmt::print(stderr,
                   "candela: distributed render on {} MPI ranks (every rank loads the scene "
                   "and builds its own accelerator)\n",
                   ctx.size());
    if (log_level() >= LogLevel::Info && s.hemisphere && s.integrator != IntegratorKind::Normals &&
        (scene.features.has(LightKind::Point) || scene.features.has(LightKind::Spot) ||
         scene.features.has(LightKind::Directional)))
        fmt::print(stderr, "candela: note: -H samples the point, spot and directional lights "
                           "directly: hemisphere sampling cannot find a delta light\n");
    if (s.integrator == IntegratorKind::Path && !s.hemisphere)
        for (const std::string& w : negligible_light_warnings(scene))
            print_warning(w);
    if (log_level() >= LogLevel::Verbose && s.integrator == IntegratorKind::Path)
        fmt::print(stderr, "candela: note: light selection {}\n",
                   describe_light_selection(scene, s.light_sampler));
    if (!s.quiet) {
        const auto count = count_of;
        fmt::print(stderr, "candela: {}: {}, {}, {}; {}x{}, {}, max depth {}, {}, accel {}{}\n",
                   args.scene, count(scene.triangle_count(), "triangle"),
                   count(scene.spheres.size(), "sphere"), count(scene.lights.size(), "light"),
                   s.width, s.height, sampling_text(s), s.max_depth,
                   enum_name(kIntegratorKinds, s.integrator), accel.name(),
                   resumed ? " (resumed)" : "");
    }
    if (log_level() >= LogLevel::Verbose) {
        std::string skips;
        for (const std::string& f : skipped_features(scene))
            skips += (skips.empty() ? "" : "; ") + f;
        if (!skips.empty()) fmt::print(stderr, "candela: note: left out: {}\n", skips);
    }
}

/// Runs the passes; a failure on one of several ranks ends the whole job.
RenderStats run_passes(const Scene& scene, const Accel& accel, const RenderSettings& s,
                       RenderState& state, const std::function<void(const RenderState&)>& on_pass,
                       const DistributedContext& ctx) {
    RenderStats stats;
    try {
        Renderer(scene, accel, s).run(state, stats, &render_stop_flag(), on_pass, ctx);
    } catch (const Error& e) {
        if (ctx.size() > 1) {
            fmt::print(stderr, "{}\n", error_line(e));
            ctx.abort_job(static_cast<int>(e.kind()));
        }
        throw;
    }
    return stats;
}

/// On the root rank after the passes: the images, the checkpoint of an interrupted render (or
/// the removal of a stale one), the summary and the final JSON line. Returns the exit status.
int finish_render(const ImageJob& job, const RenderStats& stats, const RenderState& state,
                  CheckpointWriter& checkpoints, bool resumed, Timings& t, PhaseClock& clock) {
    const RenderArgs& args = job.args;
    const RenderSettings& s = args.settings;
    const std::string& ckpt_path = checkpoints.path();
    const Film& film = state.film;
    if (stats.interrupted && stats.passes == 0) {
        // Stopped before the first pass: the image would hold no new samples.
        say_nothing_written(args);
        t.write = clock.lap();
        t.total = clock.total();
        print_json_done(args, &stats, state, &t, {}, static_cast<int>(ErrorKind::Interrupted),
                        args.resume);
        return static_cast<int>(ErrorKind::Interrupted);
    }
    const std::vector<std::string> written =
        write_job_images(job, film, stats.seconds, stats.interrupted);
    int status = stats.interrupted ? static_cast<int>(ErrorKind::Interrupted) : 0;
    bool checkpoint_ok = true;
    if (stats.interrupted) {
        checkpoint_ok = checkpoints.save(state, stats.seconds, false);
        if (!checkpoint_ok) status = static_cast<int>(ErrorKind::Io);
    }
    // An earlier render's checkpoint (--overwrite) with at least this render's samples stays.
    const bool earlier_stays = checkpoints.holds_earlier() && !checkpoints.outweighs_earlier(state);
    // A finished render keeps its checkpoint when asked (to refine it later); otherwise the
    // checkpoint is stale, and an earlier render's too.
    bool kept = false;
    if (!stats.interrupted && args.keep_checkpoint) {
        kept = checkpoints.save(state, stats.seconds, false) && !earlier_stays;
        if (!kept && !earlier_stays) {
            fmt::print(stderr, "{}\n", error_line(*checkpoints.failure()));
            status = static_cast<int>(ErrorKind::Io);
        }
    }
    const bool earlier = checkpoints.holds_earlier();
    bool removed = false;
    if (!stats.interrupted && !kept && !earlier_stays &&
        (checkpoints.wrote() || resumed || earlier))
        removed = std::remove(ckpt_path.c_str()) == 0;
    t.write = clock.lap();
    t.total = clock.total();

    print_summary(args, stats, film, t, written, job.forecast, job.rate_max);
    if (earlier_stays && log_level() >= LogLevel::Warning)
        fmt::print(stderr, "{}\n", checkpoints.earlier_kept_line(state));
    if (removed && !s.quiet && (resumed || earlier))
        fmt::print(stderr, "candela: removed {}: {}\n",
                   (resumed ? "the checkpoint " : "the earlier render's checkpoint ") + ckpt_path,
                   resumed ? "the render is finished (--keep-checkpoint keeps it, to refine the "
                             "render later)"
                           : "this render holds more samples");
    if (kept && !s.quiet)
        fmt::print(stderr,
                   "candela: kept checkpoint {} (refine with: candela render --resume {} and a "
                   "larger -s or a lower --noise-threshold)\n",
                   ckpt_path, ckpt_path);
    if (stats.interrupted && !s.quiet && !earlier_stays) {
        if (checkpoint_ok)
            fmt::print(stderr,
                       "candela: interrupted at {}; checkpoint {} (continue with: candela "
                       "render --resume {})\n",
                       reached_text(s, state), ckpt_path, ckpt_path);
    }
    if (stats.interrupted && !checkpoint_ok)
        fmt::print(stderr, "{}; the image holds the finished passes: {}\n",
                   error_line(*checkpoints.failure()), reached_text(s, state));
    print_json_done(args, &stats, state, &t, written, status,
                    ((stats.interrupted && checkpoint_ok) || kept) && !earlier_stays ? ckpt_path
                                                                                     : "",
                    job.forecast);
    return status;
}

/// On --resume with a larger -s or a lower noise threshold (render/refine.h): reopens the
/// render, predicts and reports what the refinement takes. Nothing for a plain resume of an
/// interrupted render. Throws Error(Usage) when there is nothing to refine.
std::optional<RefineForecast> start_refinement(const RenderArgs& args, const ResumeFrom& resume,
                                               RenderState& state) {
    if (!resume.active) return std::nullopt;
    const RenderSettings& s = args.settings;
    const RenderSettings& before = resume.before;
    const bool changed = s.spp != before.spp || s.noise_threshold != before.noise_threshold;
    if (!changed) return std::nullopt; // a finished render was refused by prepare_resume
    const std::string nothing = "nothing to refine: ";
    reopen_for_refinement(before, s, state);
    const std::unique_ptr<PassPolicy> policy = make_pass_policy(s);
    if (policy->finished(state))
        throw Error(ErrorKind::Usage, SourceLoc{args.resume}, nothing + policy->finished_text());
    const RefineForecast f = forecast_refinement(s, state, resume.seconds);
    // A render to this threshold would have stopped where this one did.
    if (f.noise >= 0.0 && s.noise_threshold > 0.f && f.noise <= double(s.noise_threshold)) {
        throw Error(ErrorKind::Usage, SourceLoc{args.resume},
                    nothing + fmt::format("the estimated noise {:.4g} already meets the threshold "
                                          "{:g}; give a lower one",
                                          f.noise, double(s.noise_threshold)));
    }
    if (!s.quiet) {
        const std::string noise = f.noise >= 0.0
                                      ? fmt::format("estimated noise {:.4g}, threshold {:g}; ",
                                                    f.noise, double(s.noise_threshold))
                                      : std::string();
        fmt::print(stderr,
                   "candela: refining {}: {}about {:.3g} more samples, predicted {:.2f} s of "
                   "rendering (at the {:.2f} s the render took so far)\n",
                   args.output, noise, f.samples, f.seconds, resume.seconds);
    }
    return f;
}

int run_render(RenderArgs& args) {
    // Under mpirun every rank runs this function; rank 0 alone writes files and reports.
    DistributedContext ctx;
    PhaseClock clock;
    ResumeFrom resume = settle_options(args, ctx);
    const RenderSettings& s = args.settings;
    const std::string ckpt_path = args.checkpoint_path();

    Timings t;
    std::unique_ptr<ImageFormatCheck> formats; // the root's
    const LoadedScene loaded = load_scene_and_accel(args, ctx, t, clock, formats);
    const Scene& scene = loaded.scene;
    const Accel& accel = *loaded.accel;
    print_render_intro(args, ctx, scene, accel, resume.active);

    Renderer renderer(scene, accel, s);
    RenderState state = resume.active ? std::move(resume.state) : renderer.start();
    if (state.film.width() != renderer.film_width() ||
        state.film.height() != renderer.film_height())
        throw Error(ErrorKind::Io, SourceLoc{args.resume},
                    "checkpoint does not match its settings");
    // The relative sampler may give a pixel more than -s samples: scale the ramp to the most a
    // pixel can get, so red still means "the most samples".
    std::vector<std::string> commands = std::move(resume.commands);
    commands.push_back(command_line_text());
    const ImageJob job{args,
                       scene,
                       ctx,
                       resume.seconds,
                       resume.sessions + 1,
                       std::move(commands),
                       make_pass_policy(s)->most_per_pixel(),
                       start_refinement(args, resume, state),
                       // A new render to the default name keeps what is there.
                       args.resume.empty() && !args.given.count("--output"),
                       {}};
    CheckpointWriter checkpoints(args, ctx, ckpt_path, resume.seconds, job.sessions, job.commands);

    PassWatch watch(state);
    LiveView live(job);
    // After the first pass every thread of the render runs: the image formats' check (and the
    // image module's load) may begin.
    const std::function<void(const RenderState&)> on_pass =
        [&formats, &live,
         checkpoint_pass = pass_callback(watch, args, ctx, checkpoints)](const RenderState& st) {
            if (formats) formats->start();
            checkpoint_pass(st);
            live.on_pass(st);
        };
    SignalScope signals;
    if (formats) formats->stop_on_failure(render_stop_flag());
    std::unique_ptr<FastExit> fast_exit;
    if (ctx.size() == 1 && ctx.root())
        fast_exit = std::make_unique<FastExit>([&job, &watch, &checkpoints, &formats, &live] {
            live.halt();     // no image of an earlier pass written after the last one's
            formats->wait(); // its temporary files gone before the process ends
            return write_last_pass(job, watch, checkpoints);
        });
    set_json_signal_events(s.progress == ProgressMode::Json && ctx.root());
    print_json_start(args, ctx, resume.active);

    const RenderStats stats = run_passes(scene, accel, s, state, on_pass, ctx);
    if (fast_exit) fast_exit->disarm();
    t.render = clock.lap();
    if (!ctx.root()) return stats.interrupted ? static_cast<int>(ErrorKind::Interrupted) : 0;
    live.finish(stats.passes > 0 ? &state.film : nullptr);
    // A format that cannot be written stopped the render: its error, and no file.
    formats->finish();
    return finish_render(job, stats, state, checkpoints, resume.active, t, clock);
}

} // namespace

namespace {
std::vector<std::string> g_argv;
}

void set_command_line(int argc, char** argv) {
    g_argv.assign(argv, argv + argc);
}

std::string command_line_text() {
    std::string s = "candela";
    for (const std::string& a : command_args(""))
        s += " " + shell_quote(a);
    return s;
}

std::vector<std::string> command_args(const std::string& subcommand) {
    if (subcommand.empty())
        return g_argv.empty() ? std::vector<std::string>{}
                              : std::vector<std::string>(g_argv.begin() + 1, g_argv.end());
    for (std::size_t i = 1; i < g_argv.size(); ++i)
        if (g_argv[i] == subcommand) return {g_argv.begin() + long(i) + 1, g_argv.end()};
    return {};
}

void add_render_command(CLI::App& app, int* status) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand(
        "render", "Render a scene to an HDR EXR (or an 8-bit preview). Flags follow the CS184 "
                  "path tracer (-s -l -t -m -o -e -b -d -f -r -p -c -a -H) with long forms");
    add_render_options(*cmd, *args);
    group_render_options(*cmd);
    cmd->callback([args, cmd, status] {
        record_given_options(*cmd, *args);
        *status = run_render(*args);
    });
}

} // namespace candela::app
