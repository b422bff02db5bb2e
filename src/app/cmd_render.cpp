#include "commands.h"
#include "scene_source.h"

#include "candela/accel/accel.h"
#include "candela/app/cli.h"
#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/io/image_io.h"
#include "candela/render/checkpoint.h"
#include "candela/render/distributed.h"
#include "candela/render/exr_layout.h"
#include "candela/render/memory_budget.h"
#include "candela/render/output.h"
#include "candela/render/progress.h"
#include "candela/render/refine.h"
#include "candela/render/region_grid.h"
#include "candela/render/renderer.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/process_clock.h"
#include "candela/util/stopwatch.h"
#include "candela/util/strings.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <sys/resource.h>
#include <thread>
#include <unistd.h>

namespace candela::app {

namespace {

// --- Interrupts ------------------------------------------------------------------------------
// The first SIGINT/SIGTERM asks the render to stop at the next pass boundary; the second writes
// the image of the last finished pass (and its checkpoint) at once and ends the process. The
// handler only touches lock-free atomics and write(2), which are async-signal-safe.

std::atomic<bool> g_stop{false};
std::atomic<int> g_signals{0};
std::atomic<bool> g_fast_exit_armed{false};
std::atomic<int> g_wake_fd{-1};
std::atomic<bool> g_json_events{false}; ///< --progress json on this rank: signals are events too
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

void say(const char* text) {
    if (log_level() >= LogLevel::Warning) {
        ssize_t ignored = ::write(2, text, std::char_traits<char>::length(text));
        (void)ignored;
    }
}

/// The `signal` event of --progress json, one whole line in one write(2) so that it never splits
/// another line: [SIGTERM?][what this signal does].
constexpr const char* kSignalEvents[2][3] = {
    {"{\"event\":\"signal\",\"signal\":\"SIGINT\",\"count\":1,\"action\":\"stop after the "
     "current pass\"}\n",
     "{\"event\":\"signal\",\"signal\":\"SIGINT\",\"count\":2,\"action\":\"write the last "
     "finished pass and stop now\"}\n",
     "{\"event\":\"signal\",\"signal\":\"SIGINT\",\"action\":\"already stopping\"}\n"},
    {"{\"event\":\"signal\",\"signal\":\"SIGTERM\",\"count\":1,\"action\":\"stop after the "
     "current pass\"}\n",
     "{\"event\":\"signal\",\"signal\":\"SIGTERM\",\"count\":2,\"action\":\"write the last "
     "finished pass and stop now\"}\n",
     "{\"event\":\"signal\",\"signal\":\"SIGTERM\",\"action\":\"already stopping\"}\n"},
};

void json_signal_event(int sig, int action) {
    if (!g_json_events.load()) return;
    const char* line = kSignalEvents[sig == SIGTERM ? 1 : 0][action];
    ssize_t ignored = ::write(1, line, std::char_traits<char>::length(line));
    (void)ignored;
}

extern "C" void on_signal(int sig) {
    const int n = g_signals.fetch_add(1) + 1;
    g_stop.store(true);
    const bool fast_exit = n >= 2 && g_fast_exit_armed.load();
    json_signal_event(sig, n == 1 ? 0 : n == 2 && fast_exit ? 1 : 2);
    if (n == 1) {
        say("\ncandela: stopping after the current pass (Ctrl-C again to write what is finished "
            "and stop now)\n");
        return;
    }
    if (fast_exit) {
        const int fd = g_wake_fd.load();
        if (fd >= 0) {
            const char byte = 's';
            ssize_t ignored = ::write(fd, &byte, 1);
            (void)ignored;
        }
    } else if (n == 2) {
        say("\ncandela: already writing the image; it will be done in a moment\n");
    }
}

/// Installs on_signal for SIGINT and SIGTERM for its lifetime.
class SignalScope {
  public:
    SignalScope() {
        g_stop = false;
        g_signals = 0;
        old_int_ = std::signal(SIGINT, on_signal);
        old_term_ = std::signal(SIGTERM, on_signal);
    }
    ~SignalScope() {
        std::signal(SIGINT, old_int_);
        std::signal(SIGTERM, old_term_);
    }
    SignalScope(const SignalScope&) = delete;
    SignalScope& operator=(const SignalScope&) = delete;

  private:
    void (*old_int_)(int);
    void (*old_term_)(int);
};

// --- Resume ----------------------------------------------------------------------------------

/// What a resume needs besides the settings: where the render stands and what it took so far.
struct ResumeFrom {
    RenderState state;
    double seconds = 0.0;
    int sessions = 0;
    std::vector<std::string> commands; ///< of the sessions so far (none from old checkpoints)
    bool active = false;
    RenderSettings before; ///< the checkpoint's settings, before a refinement changed them
};

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

/// Turns `--resume CKPT [options]` into the checkpoint's own settings (with this invocation's
/// runtime options) and its state; refuses changed settings or a changed scene file.
ResumeFrom prepare_resume(RenderArgs& args) {
    // This invocation's log options decide what the refusal messages look like.
    set_log_level(log_level_of(args.log));
    Checkpoint ck = read_checkpoint(args.resume);
    RenderArgs stored = parse_render_command_line(ck.args);
    check_resume_matches(args, stored, args.resume);
    // A refinement (a larger -s, a lower noise threshold) becomes the render's own setting.
    const RenderSettings before = stored.settings;
    const bool more_samples = args.given.count("--spp") && args.settings.spp != before.spp;
    const bool lower_threshold =
        args.given.count("--noise-threshold") && args.noise_threshold != stored.noise_threshold;
    if (more_samples) set_canonical_arg(ck.args, "--spp", std::to_string(args.settings.spp));
    if (lower_threshold) {
        char value[32];
        std::snprintf(value, sizeof value, "%.9g", double(args.noise_threshold));
        set_canonical_arg(ck.args, "--noise-threshold", value);
    }
    if (more_samples || lower_threshold)
        stored = parse_render_command_line(ck.args);
    else if (render_finished(before, ck.state))
        throw Error(ErrorKind::Usage, args.resume + ": error: nothing to refine: it holds a "
                                                    "finished render; give a larger -s or a "
                                                    "lower --noise-threshold to refine it");
    // Runtime options come from this invocation.
    stored.settings.threads = args.settings.threads;
    stored.log = args.log;
    stored.strict = args.strict;
    stored.settings.progress = args.settings.progress;
    if (const auto it = args.unknown_choices.find("--progress"); it != args.unknown_choices.end())
        stored.unknown_choices[it->first] = it->second;
    stored.max_memory = args.max_memory;
    stored.checkpoint = args.checkpoint.empty() ? args.resume : args.checkpoint;
    stored.checkpoint_every = args.checkpoint_every;
    stored.resume = args.resume;
    stored.keep_checkpoint = args.keep_checkpoint;
    finalize_render_args(stored);
    if (file_hash(stored.scene) != ck.scene_hash)
        throw Error(ErrorKind::Usage, args.resume +
                                          ": error: refusing to resume: the scene file '" +
                                          stored.scene + "' has changed since the checkpoint");
    if ((stored.env_map.empty() ? 0 : file_hash(stored.env_map)) != ck.env_hash)
        throw Error(ErrorKind::Usage, args.resume + ": error: refusing to resume: the "
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

// --- Outputs ---------------------------------------------------------------------------------

/// An error message worded as a warning: `candela: warning: [FILE: ]message`.
std::string user_warning_line(const std::string& message) {
    const std::string line = user_error_line(message);
    const std::string prefix = "candela: error: ";
    return "candela: warning: " + line.substr(prefix.size());
}

std::string shell_quote(const std::string& s) {
    if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789-_./=:,+@%") == std::string::npos)
        return s;
    std::string out = "'";
    for (char c : s)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// Samples per pixel over the film: finite and dropped, i.e. the sample indices each used.
struct SppStats {
    double mean = 0.0;
    std::uint32_t min = 0, max = 0;
};

SppStats spp_stats(const Film& film) {
    SppStats r;
    if (film.pixel_count() == 0) return r;
    r.min = UINT32_MAX;
    double sum = 0.0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            const std::uint32_t n = film.count(x, y) + film.dropped(x, y);
            sum += n;
            r.min = std::min(r.min, n);
            r.max = std::max(r.max, n);
        }
    r.mean = sum / double(film.pixel_count());
    return r;
}

/// Everything the image files say about the render (README "EXR metadata").
std::vector<Attribute> image_attributes(const RenderArgs& args, const Scene& scene,
                                        const Film& film, double total_seconds, int sessions,
                                        const std::vector<std::string>& commands, bool interrupted,
                                        int ranks) {
    const RenderSettings& s = args.settings;
    std::vector<Attribute> m = {
        {exr::kSoftware, std::string("candela ") + CANDELA_VERSION},
        {exr::kVersion, CANDELA_VERSION},
        {exr::kCommandLine, commands.front()},
        {exr::kScene, args.scene},
        {exr::kSpp, s.spp},
        {exr::kSeed, int(s.seed)},
        {exr::kSampleOffset, int(s.sample_offset)},
        // One past the largest index a pixel used: under the relative sampler a pixel may take
        // more than -s samples, and merge checks parts against the indices they really used.
        {exr::kSampleEnd, int(s.sample_offset + spp_stats(film).max)},
        {exr::kSampler, enum_name(kSamplerKinds, s.sampler)},
        {exr::kLightSampler, enum_name(kLightSamplerKinds, s.light_sampler)},
        {exr::kIntegrator, enum_name(kIntegratorKinds, s.integrator)},
        {exr::kMaxDepth, s.max_depth},
        {exr::kAccumulate, s.accumulate ? 1 : 0},
        {exr::kLightSamples, s.light_samples},
        {exr::kHemisphere, s.hemisphere ? 1 : 0},
        {exr::kMis, s.mis ? 1 : 0},
        {exr::kLightPaths, enum_name(kLightPaths, s.light_paths)},
        {exr::kRrDepth, s.rr_min_depth},
        {exr::kCamera, enum_name(kCameraModes, args.build.camera_mode)},
        {exr::kCameraFile, args.camera_file},
        {exr::kLensRadius, scene.camera.lens_radius},
        {exr::kFocalDistance, scene.camera.focal_distance},
        {exr::kHfovDeg, scene.camera.hfov_deg},
        {exr::kEnv, args.env_map},
        {exr::kAdaptive, enum_name(kAdaptiveKinds, s.adaptive)},
        {exr::kAdaptiveBatch, s.adaptive == AdaptiveKind::None ? 0 : s.adaptive_batch},
        {exr::kAdaptiveTol, s.adaptive == AdaptiveKind::Cs184 ? s.adaptive_tol : 0.f},
        {exr::kNoiseThreshold, s.adaptive == AdaptiveKind::Relative ? s.noise_threshold : 0.f},
        {exr::kTimeBudget, s.time_budget},
        {exr::kPassSpp, s.pass_spp},
        {exr::kAccel, accel_kind_name(s.accel.kind)},
        {exr::kTriangle, enum_name(kTriangleTests, s.accel.triangle)},
        {exr::kEmbreeRobust, s.accel.embree_robust ? 1 : 0},
        {exr::kEmbreeQuality, enum_name(kEmbreeQualities, s.accel.quality)},
        {exr::kAov, s.aovs.str()},
        {exr::kRenderSeconds, total_seconds},
        {exr::kSessions, sessions},
        {exr::kSamplesTaken, double(film.total_samples() + film.total_dropped())},
        {exr::kNonfiniteDropped, double(film.total_dropped())},
        {exr::kInterrupted, interrupted ? 1 : 0},
        {exr::kWorldToCamera, world_to_camera_matrix(scene.camera)},
        {exr::kWorldToNdc, world_to_ndc_matrix(scene.camera, s.width, s.height)},
    };
    if (!args.region.empty())
        m.push_back({exr::kRegion,
                     std::to_string(args.region[0]) + " " + std::to_string(args.region[1]) + " " +
                         std::to_string(args.region[2]) + " " + std::to_string(args.region[3])});
    if (ranks > 1) m.push_back({exr::kMpiRanks, ranks});
    if (commands.size() > 1) {
        std::string lines;
        for (const std::string& c : commands)
            lines += (lines.empty() ? "" : "\n") + c;
        m.push_back({exr::kSessionCommands, lines});
    }
    return m;
}

/// Writes the image files of `film` (the output, the preview, the sample-rate image); returns
/// the paths written.
std::vector<std::string> write_images(const RenderArgs& args, const Film& film,
                                      const std::vector<Attribute>& attributes, int rate_max) {
    const RenderSettings& s = args.settings;
    std::vector<std::string> written;
    FrameWindow window;
    if (!s.region.full()) window = {s.region.x, s.region.y, s.width, s.height};
    switch (args.output_kind) {
    case OutputKind::Exr:
        write_exr(args.output, film_to_image(film, attributes, window), args.exr);
        break;
    case OutputKind::Hdr:
        write_image_float(args.output, film.width(), film.height(), film_rgb(film));
        break;
    case OutputKind::Ldr:
        write_image8(args.output, film.width(), film.height(),
                     film_preview(film, args.exposure, args.tonemap, args.look));
        break;
    case OutputKind::Unsupported:
        throw Error(ErrorKind::Internal, args.output + ": no writer");
    }
    written.push_back(args.output);
    const std::string preview = args.preview_path();
    if (!preview.empty()) {
        write_png(preview, film.width(), film.height(),
                  film_preview(film, args.exposure, args.tonemap, args.look));
        written.push_back(preview);
    }
    const std::string rate = args.rate_path();
    if (!rate.empty()) {
        write_png(rate, film.width(), film.height(), film_rate_image(film, rate_max));
        written.push_back(rate);
    }
    return written;
}

/// What -s means in this render, for the line before it: a budget, a cap or a count.
std::string sampling_text(const RenderSettings& s) {
    char buf[160];
    if (s.adaptive == AdaptiveKind::Relative && s.noise_threshold > 0.f)
        std::snprintf(buf, sizeof buf,
                      "budget %d samples/pixel (adaptive, stops at noise threshold %g)", s.spp,
                      double(s.noise_threshold));
    else if (s.adaptive == AdaptiveKind::Relative)
        std::snprintf(buf, sizeof buf, "budget %d samples/pixel (adaptive)", s.spp);
    else if (s.adaptive == AdaptiveKind::Cs184)
        std::snprintf(buf, sizeof buf, "up to %d samples/pixel (cs184 adaptive)", s.spp);
    else
        std::snprintf(buf, sizeof buf, "%d samples/pixel", s.spp);
    return buf;
}

/// Share of the relative sampler's cost budget spent by `state` (0 before the budget is set).
double budget_share(const RenderState& state) {
    if (state.cost_budget == 0) return 0.0;
    std::uint64_t spent = 0;
    for (std::uint64_t c : state.cost)
        spent += c;
    return double(spent) / double(state.cost_budget);
}

/// How far an interrupted render got, in the words of sampling_text().
std::string reached_text(const RenderSettings& s, const RenderState& state) {
    char buf[160];
    if (s.adaptive == AdaptiveKind::Relative)
        std::snprintf(buf, sizeof buf,
                      "%.0f %% of the budget of %d samples/pixel (mean %.2f samples/pixel)",
                      100.0 * budget_share(state), s.spp, spp_stats(state.film).mean);
    else
        std::snprintf(buf, sizeof buf, "%d of %s%d samples/pixel", state.next_sample,
                      s.adaptive == AdaptiveKind::Cs184 ? "up to " : "", s.spp);
    return buf;
}

/// Why the render stopped, for the stats block and the JSON done event.
std::string stop_text(const RenderSettings& s, const RenderStats& stats, const Film& film) {
    char buf[200];
    const double share = 100.0 * stats.budget_spent;
    switch (stats.stop) {
    case StopReason::Interrupted:
        return "interrupted";
    case StopReason::TimeBudget:
        if (s.adaptive == AdaptiveKind::Relative)
            std::snprintf(buf, sizeof buf, "time budget (%gs) reached at %.0f %% of the budget",
                          s.time_budget, share);
        else
            std::snprintf(buf, sizeof buf, "time budget (%gs) reached", s.time_budget);
        return buf;
    case StopReason::AllSamples:
        std::snprintf(buf, sizeof buf, "%s%d samples/pixel taken",
                      s.adaptive == AdaptiveKind::Cs184 ? "pixels short of the -a tolerance: "
                                                        : "all ",
                      s.spp);
        return buf;
    case StopReason::Converged:
        return "every pixel met the -a tolerance";
    case StopReason::NoiseThreshold:
        std::snprintf(buf, sizeof buf,
                      "noise threshold %g reached (estimated %.4g) at %.0f %% of "
                      "the budget",
                      double(s.noise_threshold), stats.estimated_error, share);
        return buf;
    case StopReason::BudgetSpent:
        if (film.pixel_count() == 1)
            std::snprintf(buf, sizeof buf,
                          "budget spent: %d samples in the one pixel, uniformly "
                          "(no neighbours to estimate its error from)",
                          s.spp);
        else
            std::snprintf(buf, sizeof buf, "budget spent (estimated noise %.4g)",
                          stats.estimated_error);
        return buf;
    case StopReason::NothingToGain:
        std::snprintf(buf, sizeof buf,
                      "no pixel needed more samples (estimated noise %.4g) at "
                      "%.0f %% of the budget",
                      stats.estimated_error, share);
        return buf;
    }
    return "";
}

/// How an adaptive render's sample budget is bounded, for the summary.
std::string adaptive_stop_text(const RenderSettings& s) {
    char buf[160];
    if (s.adaptive == AdaptiveKind::Relative)
        std::snprintf(buf, sizeof buf,
                      "relative: noise threshold %g, budget the cost of %d samples/pixel",
                      double(s.noise_threshold), s.spp);
    else
        std::snprintf(buf, sizeof buf, "cs184: at most %d", s.spp);
    return buf;
}

/// Mean samples per pixel in each cell of the region grid (render/region_grid.h), one text line
/// per row: where an adaptive render spent its samples.
std::vector<std::string> spp_by_region(const Film& film) {
    std::vector<std::string> lines;
    const RegionGrid grid = region_grid(film.width(), film.height());
    for (int r = 0; r < grid.rows; ++r) {
        std::string line;
        for (int c = 0; c < grid.cols; ++c) {
            const GridCell& cell = grid.at(r, c);
            double sum = 0.0;
            for (int y = cell.y0; y < cell.y1; ++y)
                for (int x = cell.x0; x < cell.x1; ++x)
                    sum += double(film.count(x, y) + film.dropped(x, y));
            char text[24];
            std::snprintf(text, sizeof text, "%8.0f", sum / double(cell.pixel_count()));
            line += text;
        }
        lines.push_back(line);
    }
    return lines;
}

/// Peak resident memory of the process in bytes (getrusage reports kibibytes on Linux).
std::uint64_t peak_memory_bytes() {
    struct rusage ru {};
    if (::getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return std::uint64_t(ru.ru_maxrss) * 1024u;
}

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v)
        s += (s.empty() ? "" : ", ") + x;
    return s;
}

std::string json_list(const std::vector<std::string>& v) {
    std::string s = "[";
    for (const std::string& x : v)
        s += (s.size() > 1 ? "," : "") + json_quote(x);
    return s + "]";
}

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
    double lap() {
        const double now = process_seconds();
        const double phase = now - last_;
        last_ = now;
        return phase;
    }
    /// Seconds from the process's start to the last lap.
    double total() const { return last_; }

  private:
    double last_ = 0.0;
};

void print_summary(const RenderArgs& args, const RenderStats& stats, const Film& film,
                   const Timings& t, const std::vector<std::string>& written,
                   const std::optional<RefineForecast>& forecast) {
    const RenderSettings& s = args.settings;
    if (!args.settings.quiet) {
        const SppStats spp = spp_stats(film);
        std::fprintf(stderr, "candela: wrote %s\n", join(written).c_str());
        std::fprintf(stderr, "stats:\n");
        if (args.settings.adaptive != AdaptiveKind::None) {
            std::fprintf(stderr, "  samples/pixel  mean %.2f, min %u, max %u (adaptive, %s)\n",
                         spp.mean, spp.min, spp.max, adaptive_stop_text(args.settings).c_str());
            std::fprintf(stderr, "  by region      mean samples/pixel, top row first:\n");
            for (const std::string& line : spp_by_region(film))
                std::fprintf(stderr, "               %s\n", line.c_str());
        } else
            std::fprintf(stderr, "  samples/pixel  %u\n", spp.max);
        std::fprintf(stderr, "  stopped        %s\n", stop_text(s, stats, film).c_str());
        std::fprintf(stderr, "  samples        %llu taken this session, %llu non-finite dropped\n",
                     (unsigned long long)stats.samples, (unsigned long long)film.total_dropped());
        std::fprintf(stderr, "  rays           %llu + %llu shadow rays, %.3g rays/s\n",
                     (unsigned long long)stats.rays, (unsigned long long)stats.shadow_rays,
                     stats.rays_per_second());
        std::fprintf(stderr,
                     "  time           %.3f s: start-up %.3f, load %.3f, build %.3f, render %.3f, "
                     "write %.3f\n",
                     t.total, t.startup, t.load, t.build, t.render, t.write);
        if (forecast && forecast->seconds > 0.0 && !stats.interrupted)
            std::fprintf(
                stderr, "  prediction     %.3f s of rendering predicted, %.3f s taken (%+.0f %%)\n",
                forecast->seconds, stats.seconds,
                100.0 * (stats.seconds - forecast->seconds) / forecast->seconds);
        std::fprintf(stderr, "  peak memory    %s\n", format_bytes(peak_memory_bytes()).c_str());
    }
}

/// The last line of --progress json. Without `stats` and `t` (the second Ctrl-C's fast exit,
/// which has no counters of the pass it cut short) it leaves out the counters and times.
/// `checkpoint` is the checkpoint written, if any: the event names it and how to resume it.
/// A refinement's `forecast` adds its predicted render time.
void print_json_done(const RenderArgs& args, const RenderStats* stats, const RenderState& state,
                     const Timings* t, const std::vector<std::string>& written, int status,
                     const std::string& checkpoint,
                     const std::optional<RefineForecast>& forecast = std::nullopt) {
    const RenderSettings& s = args.settings;
    if (s.progress != ProgressMode::Json) return;
    const SppStats spp = spp_stats(state.film);
    RenderStats cut_short;
    cut_short.interrupted = true;
    cut_short.stop = StopReason::Interrupted;
    const RenderStats& st = stats ? *stats : cut_short;
    // Where the render got to: all of it unless interrupted.
    const double fraction = !st.interrupted ? 1.0
                            : s.adaptive == AdaptiveKind::Relative
                                ? budget_share(state)
                                : double(state.next_sample) / double(std::max(1, s.spp));
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "{\"event\":\"done\",\"status\":%d,\"interrupted\":%s,\"fraction\":%.6f,"
                  "\"stop\":\"%s\",\"stop_reason\":%s,",
                  status, st.interrupted ? "true" : "false", std::min(1.0, fraction),
                  enum_name(kStopReasons, st.stop),
                  json_quote(stop_text(s, st, state.film)).c_str());
    std::string line = buf;
    if (st.estimated_error >= 0.0) {
        std::snprintf(buf, sizeof buf, "\"estimated_noise\":%.6g,\"budget_spent\":%.6f,",
                      st.estimated_error, st.budget_spent);
        line += buf;
    }
    std::snprintf(buf, sizeof buf, "\"files\":%s,\"spp_mean\":%.4f,\"spp_min\":%u,\"spp_max\":%u,",
                  json_list(written).c_str(), spp.mean, spp.min, spp.max);
    line += buf;
    if (!checkpoint.empty())
        line += "\"checkpoint\":" + json_quote(checkpoint) +
                ",\"resume\":" + json_quote("candela render --resume " + shell_quote(checkpoint)) +
                ",";
    if (stats && t) {
        std::snprintf(buf, sizeof buf,
                      "\"samples\":%llu,\"rays\":%llu,\"shadow_rays\":%llu,\"time_s\":{"
                      "\"startup\":%.4f,\"load\":%.4f,\"build\":%.4f,\"render\":%.4f,"
                      "\"write\":%.4f,"
                      "\"total\":%.4f},",
                      (unsigned long long)stats->samples, (unsigned long long)stats->rays,
                      (unsigned long long)stats->shadow_rays, t->startup, t->load, t->build,
                      t->render, t->write, t->total);
        line += buf;
    }
    if (forecast) {
        std::snprintf(buf, sizeof buf, "\"predicted_render_s\":%.4f,", forecast->seconds);
        line += buf;
    }
    std::printf("%s\"peak_memory_bytes\":%llu}\n", line.c_str(),
                (unsigned long long)peak_memory_bytes());
    std::fflush(stdout);
}

/// Waits, on its own thread, for the second Ctrl-C; then writes the last finished pass (image
/// and checkpoint) and ends the process at once.
class FastExit {
  public:
    using WriteFn = std::function<int()>;
    explicit FastExit(WriteFn write) : write_(std::move(write)) {
        if (::pipe(fds_) != 0) {
            fds_[0] = fds_[1] = -1;
            return;
        }
        g_wake_fd = fds_[1];
        thread_ = std::thread([this] {
            char c = 0;
            while (::read(fds_[0], &c, 1) < 0 && errno == EINTR) {
            }
            if (c != 's') return;
            const int status = write_();
            std::fflush(stdout);
            std::fflush(stderr);
            ::_exit(status);
        });
        g_fast_exit_armed = true;
    }
    /// Stops listening: from here on the main thread writes the outputs itself.
    void disarm() {
        if (!thread_.joinable()) return;
        g_fast_exit_armed = false;
        const char quit = 'q';
        ssize_t ignored = ::write(fds_[1], &quit, 1);
        (void)ignored;
        thread_.join();
    }
    ~FastExit() {
        disarm();
        g_wake_fd = -1;
        if (fds_[0] >= 0) ::close(fds_[0]);
        if (fds_[1] >= 0) ::close(fds_[1]);
    }
    FastExit(const FastExit&) = delete;
    FastExit& operator=(const FastExit&) = delete;

  private:
    WriteFn write_;
    int fds_[2] = {-1, -1};
    std::thread thread_;
};

// --- The render command, step by step ---------------------------------------------------------

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
        if (log_level() >= LogLevel::Warning)
            std::fprintf(stderr, "candela: warning: %s\n", w.c_str());
    return resume;
}

/// Checks that every image's format writes (check_image_format() on render_images()) on a
/// thread of its own, which loads the image module on the way: OpenImageIO's libraries take a
/// few tenths of a second of processor time to load, and this way the load overlaps the render
/// instead of coming before it. The thread starts at once but loads nothing before start(): the
/// dynamic loader holds a lock for the whole load that every new thread of the process needs
/// (for its thread-local storage), so the load must begin only once the render's threads (TBB's
/// workers, the progress and interrupt threads) are running, i.e. after its first pass. A
/// failure stops the render at the next pass (stop_on_failure()) and finish() throws it, before
/// anything is written.
class ImageFormatCheck {
  public:
    explicit ImageFormatCheck(std::vector<RenderImage> images)
        : images_(std::move(images)), thread_([this] { run(); }) {}
    /// A check not started by then is dropped (the render failed: no image will be written).
    ~ImageFormatCheck() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            dropped_ = !started_;
            started_ = true;
        }
        start_.notify_one();
        if (thread_.joinable()) thread_.join();
    }
    ImageFormatCheck(const ImageFormatCheck&) = delete;
    ImageFormatCheck& operator=(const ImageFormatCheck&) = delete;

    /// Lets the check begin (idempotent).
    void start() {
        std::lock_guard<std::mutex> lock(mutex_);
        started_ = true;
        start_.notify_one();
    }

    /// From now on a failure sets `stop`; at once when the check has failed already.
    void stop_on_failure(std::atomic<bool>& stop) {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = &stop;
        if (failure_) stop = true;
    }

    /// Starts the check if need be and waits for its end.
    void wait() {
        start();
        if (thread_.joinable()) thread_.join();
    }
    /// wait(), then throws the check's error.
    void finish() {
        wait();
        if (failure_) std::rethrow_exception(failure_);
    }

  private:
    void run() {
        {
            std::unique_lock<std::mutex> lock(mutex_);
            start_.wait(lock, [this] { return started_; });
            if (dropped_) return;
        }
        try {
            for (const RenderImage& image : images_)
                check_image_format(image.path, image.kind);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            failure_ = std::current_exception();
            if (stop_) *stop_ = true;
        }
    }

    const std::vector<RenderImage> images_;
    std::mutex mutex_;
    std::condition_variable start_;
    bool started_ = false, dropped_ = false;
    std::exception_ptr failure_;
    std::atomic<bool>* stop_ = nullptr;
    std::thread thread_; ///< last: it starts once the members it uses are there
};

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
    if (args.strict) throw Error(ErrorKind::Scene, "error: " + what + " (--strict)");
    if (log_level() >= LogLevel::Warning)
        std::fprintf(stderr, "candela: warning: %s\n", what.c_str());
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
        throw Error(ErrorKind::Usage, "candela: error: another MPI rank failed to load the "
                                      "scene (see its message)");
    }
    return loaded;
}

/// The notes and the one-line description of the render before it starts.
void print_render_intro(const RenderArgs& args, const DistributedContext& ctx, const Scene& scene,
                        const Accel& accel, bool resumed) {
    const RenderSettings& s = args.settings;
    if (!s.quiet && ctx.size() > 1)
        std::fprintf(stderr,
                     "candela: distributed render on %d MPI ranks (every rank loads the scene "
                     "and builds its own accelerator)\n",
                     ctx.size());
    if (log_level() >= LogLevel::Info && s.hemisphere && s.integrator != IntegratorKind::Normals &&
        (scene.features.has(LightKind::Point) || scene.features.has(LightKind::Spot) ||
         scene.features.has(LightKind::Directional)))
        std::fprintf(stderr, "candela: note: -H samples the point, spot and directional lights "
                             "directly: hemisphere sampling cannot find a delta light\n");
    if (log_level() >= LogLevel::Warning && s.integrator == IntegratorKind::Path && !s.hemisphere)
        for (const std::string& w : negligible_light_warnings(scene))
            std::fprintf(stderr, "candela: warning: %s\n", w.c_str());
    if (log_level() >= LogLevel::Verbose && s.integrator == IntegratorKind::Path)
        std::fprintf(stderr, "candela: note: light selection %s\n",
                     describe_light_selection(scene, s.light_sampler).c_str());
    if (!s.quiet) {
        const auto count = count_of;
        std::fprintf(stderr, "candela: %s: %s, %s, %s; %dx%d, %s, max depth %d, %s, accel %s%s\n",
                     args.scene.c_str(), count(scene.triangle_count(), "triangle").c_str(),
                     count(scene.spheres.size(), "sphere").c_str(),
                     count(scene.lights.size(), "light").c_str(), s.width, s.height,
                     sampling_text(s).c_str(), s.max_depth,
                     enum_name(kIntegratorKinds, s.integrator), accel.name(),
                     resumed ? " (resumed)" : "");
    }
    if (log_level() >= LogLevel::Verbose) {
        std::string skips;
        for (const std::string& f : skipped_features(scene))
            skips += (skips.empty() ? "" : "; ") + f;
        if (!skips.empty()) std::fprintf(stderr, "candela: note: left out: %s\n", skips.c_str());
    }
}

/// Writes the checkpoints of one render (on the root rank only). A checkpoint is insurance: a
/// failed one never costs the render or its image.
class CheckpointWriter {
  public:
    CheckpointWriter(const RenderArgs& args, const DistributedContext& ctx, std::string path,
                     double earlier_seconds, int sessions, const std::vector<std::string>& commands)
        : root_(ctx.root()), path_(std::move(path)), earlier_seconds_(earlier_seconds) {
        stale_ = root_ && args.resume.empty() && looks_like_checkpoint(path_);
        ck_.args = canonical_render_args(args);
        ck_.scene_hash = file_hash(args.scene);
        ck_.env_hash = args.env_map.empty() ? 0 : file_hash(args.env_map);
        ck_.sessions = sessions;
        ck_.commands = commands;
    }

    /// Writes a checkpoint of `st`; a failure is a warning during the render (`periodic`) and
    /// left to the caller to report at the end (failure()).
    bool save(const RenderState& st, double seconds_so_far, bool periodic) {
        if (!root_) return true;
        ck_.state = st; // a copy: the render goes on with its own
        ck_.render_seconds = earlier_seconds_ + seconds_so_far;
        try {
            write_checkpoint(path_, ck_);
            wrote_ = true;
            return true;
        } catch (const Error& e) {
            if (periodic && failure_ != e.what() && log_level() >= LogLevel::Warning)
                std::fprintf(stderr, "%s\n", user_warning_line(e.what()).c_str());
            failure_ = e.what();
            return false;
        }
    }

    const std::string& path() const { return path_; }
    bool wrote() const { return wrote_; }
    /// A checkpoint of an earlier render was at the path when this (new) render began: resuming
    /// it would overwrite this render's image, so it goes when this render writes its own.
    bool stale() const { return stale_; }
    /// The last failed write's message, reported once.
    const std::string& failure() const { return failure_; }

  private:
    bool root_;
    std::string path_;
    double earlier_seconds_;
    Checkpoint ck_;
    bool wrote_ = false;
    bool stale_ = false;
    std::string failure_;
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
};

std::vector<std::string> write_job_images(const ImageJob& job, const Film& film, double seconds,
                                          bool interrupted) {
    return write_images(job.args, film,
                        image_attributes(job.args, job.scene, film, job.earlier_seconds + seconds,
                                         job.sessions, job.commands, interrupted, job.ctx.size()),
                        job.rate_max);
}

/// An interrupt before the first pass of this session finished: no file is written, so an image
/// (or checkpoint) already at the output path is left as it was rather than replaced by one with
/// no new samples.
void say_nothing_written(const RenderArgs& args) {
    if (args.settings.quiet) return;
    std::fprintf(stderr,
                 "candela: stopped before the first pass finished; nothing written (%s left as it "
                 "was)%s\n",
                 args.output.c_str(),
                 args.resume.empty() ? ""
                                     : ("; " + args.resume +
                                        " still holds the render (continue with: candela render "
                                        "--resume " +
                                        args.resume + ")")
                                           .c_str());
}

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

std::function<void(const RenderState&)> pass_callback(PassWatch& watch, const RenderArgs& args,
                                                      const DistributedContext& ctx,
                                                      CheckpointWriter& checkpoints) {
    return [&watch, &args, &ctx, &checkpoints](const RenderState& st) {
        std::lock_guard<std::mutex> lock(watch.mutex);
        if (ctx.size() == 1) watch.snapshot = st;
        watch.any_pass = true;
        if (args.checkpoint_every <= 0.0) return;
        if (watch.since_checkpoint.seconds() < args.checkpoint_every ||
            st.finished(args.settings.spp))
            return;
        watch.since_checkpoint.restart();
        checkpoints.save(st, watch.render_time.seconds(), true);
    };
}

/// The second Ctrl-C's writer: the image and checkpoint of the last finished pass, at once.
/// Returns the exit status.
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
        std::fprintf(stderr, "%s\n", user_error_line(e.what()).c_str());
        status = static_cast<int>(e.kind());
    }
    if (!checkpoints.save(watch.snapshot, seconds, false)) {
        std::fprintf(stderr, "%s\n", user_error_line(checkpoints.failure()).c_str());
        status = static_cast<int>(ErrorKind::Io);
    }
    const std::string& ckpt_path = checkpoints.path();
    if (!job.args.settings.quiet)
        std::fprintf(stderr, "candela: stopped now; wrote %s with %s%s\n", join(written).c_str(),
                     reached_text(job.args.settings, watch.snapshot).c_str(),
                     checkpoints.wrote()
                         ? (" and checkpoint " + ckpt_path +
                            " (continue with: candela render --resume " + ckpt_path + ")")
                               .c_str()
                         : "");
    print_json_done(job.args, nullptr, watch.snapshot, nullptr, written, status,
                    checkpoints.wrote() ? ckpt_path : "");
    return status;
}

/// The first line of --progress json; after the signal handlers are in place, since a farm
/// manager may interrupt as soon as it reads it.
void print_json_start(const RenderArgs& args, const DistributedContext& ctx, bool resumed) {
    const RenderSettings& s = args.settings;
    if (s.progress != ProgressMode::Json || !ctx.root()) return;
    std::printf("{\"event\":\"start\",\"scene\":%s,\"output\":%s,\"width\":%d,\"height\":%d,"
                "\"spp\":%d,\"resumed\":%s}\n",
                json_quote(args.scene).c_str(), json_quote(args.output).c_str(), s.width, s.height,
                s.spp, resumed ? "true" : "false");
    std::fflush(stdout);
}

/// Runs the passes; a failure on one of several ranks ends the whole job.
RenderStats run_passes(const Scene& scene, const Accel& accel, const RenderSettings& s,
                       RenderState& state, const std::function<void(const RenderState&)>& on_pass,
                       const DistributedContext& ctx) {
    RenderStats stats;
    try {
        Renderer(scene, accel, s).run(state, stats, &g_stop, on_pass, ctx);
    } catch (const Error& e) {
        if (ctx.size() > 1) {
            std::fprintf(stderr, "%s\n", user_error_line(e.what()).c_str());
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
    // A finished render keeps its checkpoint when asked (to refine it later); otherwise the
    // checkpoint is stale, and an earlier render's too.
    bool kept = false;
    if (!stats.interrupted && args.keep_checkpoint) {
        kept = checkpoints.save(state, stats.seconds, false);
        if (!kept) {
            std::fprintf(stderr, "%s\n", user_error_line(checkpoints.failure()).c_str());
            status = static_cast<int>(ErrorKind::Io);
        }
    }
    if (!stats.interrupted && !kept && (checkpoints.wrote() || resumed || checkpoints.stale()))
        std::remove(ckpt_path.c_str());
    t.write = clock.lap();
    t.total = clock.total();

    print_summary(args, stats, film, t, written, job.forecast);
    if (kept && !s.quiet)
        std::fprintf(stderr,
                     "candela: kept checkpoint %s (refine with: candela render --resume %s and a "
                     "larger -s or a lower --noise-threshold)\n",
                     ckpt_path.c_str(), ckpt_path.c_str());
    if (stats.interrupted && !s.quiet) {
        if (checkpoint_ok)
            std::fprintf(stderr,
                         "candela: interrupted at %s; checkpoint %s (continue with: candela "
                         "render --resume %s)\n",
                         reached_text(s, state).c_str(), ckpt_path.c_str(), ckpt_path.c_str());
    }
    if (stats.interrupted && !checkpoint_ok)
        std::fprintf(stderr, "%s; the image holds the finished passes: %s\n",
                     user_error_line(checkpoints.failure()).c_str(),
                     reached_text(s, state).c_str());
    print_json_done(args, &stats, state, &t, written, status,
                    (stats.interrupted && checkpoint_ok) || kept ? ckpt_path : "", job.forecast);
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
    const std::string nothing = args.resume + ": error: nothing to refine: ";
    reopen_for_refinement(before, s, state);
    if (render_finished(s, state))
        throw Error(ErrorKind::Usage,
                    nothing + (s.adaptive == AdaptiveKind::Relative
                                   ? "the render has spent the budget of -s " +
                                         std::to_string(s.spp) + "; give a larger -s"
                                   : "every pixel has its samples or has converged"));
    const RefineForecast f = forecast_refinement(s, state, resume.seconds);
    // A render to this threshold would have stopped where this one did.
    if (f.noise >= 0.0 && s.noise_threshold > 0.f && f.noise <= double(s.noise_threshold)) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "the estimated noise %.4g already meets the threshold %g; give a lower one",
                      f.noise, double(s.noise_threshold));
        throw Error(ErrorKind::Usage, nothing + buf);
    }
    if (!s.quiet) {
        char noise[96] = "";
        if (f.noise >= 0.0)
            std::snprintf(noise, sizeof noise, "estimated noise %.4g, threshold %g; ", f.noise,
                          double(s.noise_threshold));
        std::fprintf(stderr,
                     "candela: refining %s: %sabout %.3g more samples, predicted %.2f s of "
                     "rendering (at the %.2f s the render took so far)\n",
                     args.output.c_str(), noise, f.samples, f.seconds, resume.seconds);
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
        throw Error(ErrorKind::Io, args.resume + ": error: checkpoint does not match its settings");
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
                       s.adaptive == AdaptiveKind::Relative ? renderer.relative_max_per_pixel()
                                                            : s.spp,
                       start_refinement(args, resume, state)};
    CheckpointWriter checkpoints(args, ctx, ckpt_path, resume.seconds, job.sessions, job.commands);
    if (checkpoints.stale() && log_level() >= LogLevel::Warning)
        std::fprintf(stderr,
                     "candela: warning: %s is the checkpoint of an earlier render; this render "
                     "replaces it when it writes %s (to continue the earlier render instead, stop "
                     "now with Ctrl-C twice and run: candela render --resume %s)\n",
                     ckpt_path.c_str(), args.output.c_str(), ckpt_path.c_str());

    PassWatch watch(state);
    // After the first pass every thread of the render runs: the image formats' check (and the
    // image module's load) may begin.
    const std::function<void(const RenderState&)> on_pass =
        [&formats,
         checkpoint_pass = pass_callback(watch, args, ctx, checkpoints)](const RenderState& st) {
            if (formats) formats->start();
            checkpoint_pass(st);
        };
    SignalScope signals;
    if (formats) formats->stop_on_failure(g_stop);
    std::unique_ptr<FastExit> fast_exit;
    if (ctx.size() == 1 && ctx.root())
        fast_exit = std::make_unique<FastExit>([&job, &watch, &checkpoints, &formats] {
            formats->wait(); // its temporary files gone before the process ends
            return write_last_pass(job, watch, checkpoints);
        });
    g_json_events = s.progress == ProgressMode::Json && ctx.root();
    print_json_start(args, ctx, resume.active);

    const RenderStats stats = run_passes(scene, accel, s, state, on_pass, ctx);
    if (fast_exit) fast_exit->disarm();
    t.render = clock.lap();
    if (!ctx.root()) return stats.interrupted ? static_cast<int>(ErrorKind::Interrupted) : 0;
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
    cmd->callback([args, cmd, status] {
        record_given_options(*cmd, *args);
        *status = run_render(*args);
    });
}

} // namespace candela::app
