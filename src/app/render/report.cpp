// The image files, the summary and the JSON events of `candela render` (report.h).
#include "report.h"
#include "../output_paths.h"

#include "../commands.h"

#include "candela/io/image_io.h"
#include "candela/render/adaptive.h"
#include "candela/render/exr_layout.h"
#include "candela/render/output.h"
#include "candela/render/progress.h"
#include "candela/render/region_grid.h"
#include "candela/render/setting_table.h"
#include "candela/util/check.h"
#include "candela/util/error.h"
#include "candela/util/process_clock.h"
#include "candela/util/strings.h"
#include "candela/version.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sys/resource.h>

namespace candela::app {

namespace {

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

/// What an 8-bit image of the render says about itself (docs/exr-metadata.md "8-bit images"):
/// the software, the command that reproduces it and, for the image of the radiance
/// (`radiance`; not the sample-rate image), the look its bytes were encoded with and the
/// samples per pixel and sampler that made them.
std::vector<Attribute> image8_attributes(const RenderArgs& args, const std::string& command,
                                         bool radiance) {
    std::vector<Attribute> m = {{exr::kSoftware, software_text()}, {exr::kCommandLine, command}};
    if (!radiance) return m;
    m.push_back({exr::kLook, enum_name(kLooks, args.look)});
    // The sample count and sampler: `candela compare` estimates the light the 8-bit white
    // clips from renders at the image's own fixed sample count.
    for (Setting id : {Setting::Spp, Setting::Adaptive})
        m.push_back({setting_key(id), setting_row(id).text(args.settings)});
    if (args.look == Look::Candela) {
        m.push_back({exr::kExposure, fmt::format("{:g}", double(args.exposure))});
        m.push_back({exr::kTonemap, tonemap_name(args.tonemap)});
    }
    return m;
}

/// Everything the image files say about the render (docs/exr-metadata.md).
std::vector<Attribute> image_attributes(const RenderArgs& args, const Scene& scene,
                                        const Film& film, double total_seconds, int sessions,
                                        const std::vector<std::string>& commands, bool interrupted,
                                        int ranks) {
    const RenderSettings& s = args.settings;
    const std::unique_ptr<PassPolicy> sampler = make_pass_policy(s);
    std::vector<Attribute> m = {
        {exr::kSoftware, software_text()},
        {exr::kVersion, CANDELA_VERSION},
        {exr::kCommandLine, commands.front()},
        {exr::kScene, args.scene},
        // One past the largest index a pixel used: under the relative sampler a pixel may take
        // more than -s samples, and merge checks parts against the indices they really used.
        {exr::kSampleEnd, int(s.sample_offset + spp_stats(film).max)},
        {exr::kCamera, enum_name(kCameraModes, args.build.camera_mode)},
        {exr::kCameraFile, args.camera_file},
        {exr::kLensRadius, scene.camera.lens_radius},
        {exr::kFocalDistance, scene.camera.focal_distance},
        {exr::kHfovDeg, scene.camera.hfov_deg},
        {exr::kFraming, enum_name(kFramings, args.build.framing)},
        {exr::kEnv, args.env_map},
        {exr::kRenderSeconds, total_seconds},
        {exr::kSessions, sessions},
        {exr::kSamplesTaken, double(film.total_samples() + film.total_dropped())},
        {exr::kNonfiniteDropped, double(film.total_dropped())},
        {exr::kInterrupted, interrupted ? 1 : 0},
        {exr::kWorldToCamera, world_to_camera_matrix(scene.camera)},
        {exr::kWorldToNdc, world_to_ndc_matrix(scene.camera, s.width, s.height)},
    };
    for (Attribute& a : setting_attributes(s))
        m.push_back(std::move(a));
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

/// Writes the image files of `film` (the output, the preview, the sample-rate image): the EXR
/// with `attributes`, the others with image8_attributes() naming `command`; returns the paths
/// written.
std::vector<std::string> write_images(const RenderArgs& args, const Film& film,
                                      const std::vector<Attribute>& attributes,
                                      const std::string& command, int rate_max) {
    const RenderSettings& s = args.settings;
    std::vector<std::string> written;
    FrameWindow window;
    if (!s.region.full()) window = {s.region.x, s.region.y, s.width, s.height};
    const std::string rate = args.rate_path();
    switch (args.output_kind) {
    case OutputKind::Exr: {
        // The EXR says what the colours of the rate image beside it mean.
        std::vector<Attribute> with_legend = attributes;
        if (!rate.empty()) with_legend.push_back({exr::kRateLegend, rate_legend(rate_max)});
        write_exr(args.output, film_to_image(film, with_legend, window), args.exr);
        break;
    }
    case OutputKind::Hdr:
        write_image_float(args.output, film.width(), film.height(), film_rgb(film),
                          image8_attributes(args, command, false));
        break;
    case OutputKind::Ldr:
        write_image8(args.output, film.width(), film.height(),
                     film_preview(film, args.exposure, args.tonemap, args.look),
                     image8_attributes(args, command, true));
        break;
    case OutputKind::Unsupported: // refused by finalize_render_args
        CANDELA_CHECK(false, args.output + ": no writer");
    }
    written.push_back(args.output);
    const std::string preview = args.preview_path();
    if (!preview.empty()) {
        write_png(preview, film.width(), film.height(),
                  film_preview(film, args.exposure, args.tonemap, args.look),
                  image8_attributes(args, command, true));
        written.push_back(preview);
    }
    if (!rate.empty()) {
        write_png(rate, film.width(), film.height(), film_rate_image(film, rate_max),
                  image8_attributes(args, command, false));
        written.push_back(rate);
    }
    return written;
}

/// Why the render stopped, for the stats block and the JSON done event.
std::string stop_text(const RenderSettings& s, const RenderStats& stats, const Film& film) {
    return make_pass_policy(s)->stop_text(stats, film.pixel_count());
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
            line += fmt::format("{:8.0f}", sum / double(cell.pixel_count()));
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

/// One event of --progress json on stdout, a whole line.
void print_event(const nlohmann::ordered_json& event) {
    fmt::print("{}\n", event.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(stdout);
}

} // namespace

std::string software_text() {
    return std::string("candela ") + CANDELA_VERSION + " (" + CANDELA_GIT_COMMIT + ")";
}

double PhaseClock::lap() {
    const double now = process_seconds();
    const double phase = now - last_;
    last_ = now;
    return phase;
}

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v)
        s += (s.empty() ? "" : ", ") + x;
    return s;
}

std::vector<std::string> write_job_images(const ImageJob& job, const Film& film, double seconds,
                                          bool interrupted) {
    if (job.keep_earlier_images)
        std::call_once(job.kept_earlier, [&job] {
            std::vector<std::string> paths;
            for (const RenderImage& image : render_images(job.args))
                paths.push_back(image.path);
            for (const auto& [from, to] : keep_numbered_backups(paths))
                if (log_level() >= LogLevel::Warning)
                    fmt::print(stderr,
                               "candela: kept the earlier {} as {} (the default output name; "
                               "-f names the image to write)\n",
                               from, to);
        });
    return write_images(job.args, film,
                        image_attributes(job.args, job.scene, film, job.earlier_seconds + seconds,
                                         job.sessions, job.commands, interrupted, job.ctx.size()),
                        job.commands.front(), job.rate_max);
}

/// What -s means in this render, for the line before it: a budget, a cap or a count.
std::string sampling_text(const RenderSettings& s) {
    return make_pass_policy(s)->sampling_text();
}

/// How far an interrupted render got, in the words of sampling_text().
std::string reached_text(const RenderSettings& s, const RenderState& state) {
    return make_pass_policy(s)->reached_text(state);
}

/// An interrupt before the first pass of this session finished: no file is written, so an image
/// (or checkpoint) already at the output path is left as it was rather than replaced by one with
/// no new samples.
void say_nothing_written(const RenderArgs& args) {
    if (args.settings.quiet) return;
    fmt::print(stderr,
               "candela: stopped before the first pass finished; nothing written ({} left as it "
               "was){}\n",
               args.output,
               args.resume.empty() ? ""
                                   : ("; " + args.resume +
                                      " still holds the render (continue with: candela render "
                                      "--resume " +
                                      args.resume + ")"));
}

void print_summary(const RenderArgs& args, const RenderStats& stats, const Film& film,
                   const Timings& t, const std::vector<std::string>& written,
                   const std::optional<RefineForecast>& forecast, int rate_max) {
    const RenderSettings& s = args.settings;
    if (!args.settings.quiet) {
        const SppStats spp = spp_stats(film);
        fmt::print(stderr, "candela: wrote {}\n", join(written));
        const std::string rate = args.rate_path();
        if (!rate.empty())
            fmt::print(stderr, "  rate image     {}: {}\n", rate, rate_legend(rate_max));
        fmt::print(stderr, "stats:\n");
        const std::string bounded = make_pass_policy(s)->summary_text();
        if (!bounded.empty()) {
            fmt::print(stderr, "  samples/pixel  mean {:.2f}, min {}, max {} (adaptive, {})\n",
                       spp.mean, spp.min, spp.max, bounded);
            fmt::print(stderr, "  by region      mean samples/pixel, top row first:\n");
            for (const std::string& line : spp_by_region(film))
                fmt::print(stderr, "               {}\n", line);
        } else
            fmt::print(stderr, "  samples/pixel  {}\n", spp.max);
        fmt::print(stderr, "  stopped        {}\n", stop_text(s, stats, film));
        fmt::print(stderr, "  samples        {} taken this session, {} non-finite dropped\n",
                   stats.samples, film.total_dropped());
        fmt::print(stderr, "  rays           {} + {} shadow rays, {:.3g} rays/s\n", stats.rays,
                   stats.shadow_rays, stats.rays_per_second());
        fmt::print(
            stderr,
            "  time           {:.3f} s: start-up {:.3f}, load {:.3f}, build {:.3f}, render {:.3f}, "
            "write {:.3f}\n",
            t.total, t.startup, t.load, t.build, t.render, t.write);
        if (forecast && forecast->seconds > 0.0 && !stats.interrupted)
            fmt::print(
                stderr,
                "  prediction     {:.3f} s of rendering predicted, {:.3f} s taken ({:+.0f} %)\n",
                forecast->seconds, stats.seconds,
                100.0 * (stats.seconds - forecast->seconds) / forecast->seconds);
        fmt::print(stderr, "  peak memory    {}\n", format_bytes(peak_memory_bytes()));
    }
}

void print_json_start(const RenderArgs& args, const DistributedContext& ctx, bool resumed) {
    const RenderSettings& s = args.settings;
    if (s.progress != ProgressMode::Json || !ctx.root()) return;
    print_event({{"event", "start"},
                 {"scene", args.scene},
                 {"output", args.output},
                 {"width", s.width},
                 {"height", s.height},
                 {"spp", s.spp},
                 {"resumed", resumed}});
}

void print_json_done(const RenderArgs& args, const RenderStats* stats, const RenderState& state,
                     const Timings* t, const std::vector<std::string>& written, int status,
                     const std::string& checkpoint, const std::optional<RefineForecast>& forecast) {
    const RenderSettings& s = args.settings;
    if (s.progress != ProgressMode::Json) return;
    const SppStats spp = spp_stats(state.film);
    RenderStats cut_short;
    cut_short.interrupted = true;
    cut_short.stop = StopReason::Interrupted;
    const RenderStats& st = stats ? *stats : cut_short;
    // Where the render got to: all of it unless interrupted, and never less than the progress
    // events said before.
    const double reached = !st.interrupted ? 1.0 : make_pass_policy(s)->reached(state);
    const double fraction = std::max(reached, reported_progress_fraction());
    nlohmann::ordered_json e = {{"event", "done"},
                                {"status", status},
                                {"interrupted", st.interrupted},
                                {"fraction", printed_number(std::min(1.0, fraction), "{:.6f}")},
                                {"stop", enum_name(kStopReasons, st.stop)},
                                {"stop_reason", stop_text(s, st, state.film)}};
    if (st.estimated_error >= 0.0) {
        e["estimated_noise"] = printed_number(st.estimated_error, "{:.6g}");
        e["budget_spent"] = printed_number(st.budget_spent, "{:.6f}");
    }
    e["files"] = written;
    e["spp_mean"] = printed_number(spp.mean, "{:.4f}");
    e["spp_min"] = spp.min;
    e["spp_max"] = spp.max;
    if (!checkpoint.empty()) {
        e["checkpoint"] = checkpoint;
        e["resume"] = "candela render --resume " + shell_quote(checkpoint);
    }
    if (stats && t) {
        e["samples"] = stats->samples;
        e["rays"] = stats->rays;
        e["shadow_rays"] = stats->shadow_rays;
        e["time_s"] = {{"startup", printed_number(t->startup, "{:.4f}")},
                       {"load", printed_number(t->load, "{:.4f}")},
                       {"build", printed_number(t->build, "{:.4f}")},
                       {"render", printed_number(t->render, "{:.4f}")},
                       {"write", printed_number(t->write, "{:.4f}")},
                       {"total", printed_number(t->total, "{:.4f}")}};
    }
    if (forecast) e["predicted_render_s"] = printed_number(forecast->seconds, "{:.4f}");
    e["peak_memory_bytes"] = peak_memory_bytes();
    print_event(e);
}

} // namespace candela::app
