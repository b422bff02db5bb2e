#include "commands.h"

#include "candela/accel/accel.h"
#include "candela/io/cli.h"
#include "candela/io/image_io.h"
#include "candela/render/checkpoint.h"
#include "candela/render/distributed.h"
#include "candela/render/memory_budget.h"
#include "candela/render/output.h"
#include "candela/render/renderer.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <thread>

namespace candela::app {

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) {
    g_stop.store(true);
}

/// Fails early (before loading and rendering) when the output cannot be written: the directory
/// is missing or not writable, or the output would overwrite the input scene.
void check_output_path(const std::string& output, const std::string& scene) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(output, ec) && fs::exists(scene, ec) && fs::equivalent(output, scene, ec))
        throw Error(ErrorKind::Usage, output + ": error: refusing to overwrite the input scene");
    std::string probe = temp_path_for(output);
    {
        std::ofstream f(probe, std::ios::binary);
        if (!f) {
            fs::path dir = fs::path(output).parent_path();
            throw Error(ErrorKind::Io, output + ": error: cannot write to directory '" +
                                           (dir.empty() ? std::string(".") : dir.string()) +
                                           "' (missing or not writable)");
        }
    }
    fs::remove(probe, ec);
}

std::string fmt_double(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

/// What a resume needs besides the settings: where the render stands.
struct ResumeFrom {
    RenderState state;
    bool active = false;
};

/// Turns `--resume CKPT [args]` into the checkpoint's own arguments (with this invocation's
/// runtime options) and its state; refuses changed settings or a changed scene file.
ResumeFrom prepare_resume(RenderArgs& args, std::vector<std::string>& argv) {
    Checkpoint ck = read_checkpoint(args.resume);
    std::vector<std::string> given = image_defining_args(argv);
    std::vector<std::string> stored = image_defining_args(ck.args);
    if (!given.empty() && given != stored) {
        std::string s;
        for (const auto& a : stored)
            s += " " + a;
        throw Error(ErrorKind::Usage, args.resume +
                                          ": error: refusing to resume: the "
                                          "checkpoint was made with different "
                                          "settings (" +
                                          s.substr(s.empty() ? 0 : 1) +
                                          "); give only --resume and runtime options");
    }
    RenderArgs resumed = parse_render_command_line(ck.args);
    // Runtime options come from this invocation.
    resumed.settings.threads = args.settings.threads;
    resumed.settings.quiet = args.settings.quiet;
    resumed.checkpoint = args.checkpoint.empty() ? args.resume : args.checkpoint;
    resumed.checkpoint_every = args.checkpoint_every;
    if (file_hash(resumed.scene) != ck.scene_hash)
        throw Error(ErrorKind::Usage, args.resume +
                                          ": error: refusing to resume: the scene file '" +
                                          resumed.scene + "' has changed since the checkpoint");
    if ((resumed.build.env_map.empty() ? 0 : file_hash(resumed.build.env_map)) != ck.env_hash)
        throw Error(ErrorKind::Usage, args.resume + ": error: refusing to resume: the "
                                                    "environment map has changed since the "
                                                    "checkpoint");
    argv = ck.args;
    args = resumed;
    ResumeFrom r;
    r.state = std::move(ck.state);
    r.active = true;
    return r;
}

int run_render(RenderArgs& args) {
    // Under mpirun every rank runs this function; rank 0 alone writes files and reports.
    DistributedContext ctx;
    std::vector<std::string> argv = command_args("render");
    ResumeFrom resume;
    if (!args.resume.empty())
        resume = prepare_resume(args, argv);
    else
        finalize_render_args(args);
    RenderSettings& s = args.settings;
    if (!ctx.root()) s.quiet = true;
    set_verbose(!s.quiet);
    const std::string ckpt_path =
        args.checkpoint.empty() ? checkpoint_path_for(args.output) : args.checkpoint;

    // Loading can fail on one rank only (a file missing on one node): the ranks agree on the
    // outcome before the first collective operation of the render, so none waits forever.
    double load_s = 0.0, build_s = 0.0;
    Scene scene;
    std::unique_ptr<Accel> accel;
    std::exception_ptr failure;
    try {
        if (ctx.root()) check_output_path(args.output, args.scene);
        auto t_load = std::chrono::steady_clock::now();
        Diagnostics diag(args.strict);
        scene = load_scene(args.scene, args.build, diag);
        diag.flush();
        if (!args.camera_file.empty()) apply_camera_file(args.camera_file, scene);
        if (args.lens_radius) scene.camera.lens_radius = *args.lens_radius;
        if (args.focal_distance) scene.camera.focal_distance = *args.focal_distance;
        load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_load).count();

        // Before anything large (accelerator, film) is allocated.
        check_memory_budget(estimate_render_memory(scene, s), args.max_memory_bytes);
        auto t_build = std::chrono::steady_clock::now();
        accel = make_accel(scene, s.accel);
        build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();
    } catch (...) {
        failure = std::current_exception();
    }
    if (ctx.any(failure != nullptr)) {
        if (failure) std::rethrow_exception(failure);
        throw Error(ErrorKind::Usage, "candela: error: another MPI rank failed to load the "
                                      "scene (see its message)");
    }

    if (!s.quiet && ctx.size() > 1)
        std::fprintf(stderr,
                     "candela: distributed render on %d MPI ranks (every rank loads the scene "
                     "and builds its own accelerator)\n",
                     ctx.size());
    if (!s.quiet)
        std::fprintf(stderr,
                     "candela: %s: %zu triangles, %zu spheres, %zu lights; %dx%d, %d spp, "
                     "max depth %d, %s, accel %s (load %.3fs, build %.3fs)%s\n",
                     args.scene.c_str(), scene.triangle_count(), scene.spheres.size(),
                     scene.lights.size(), s.width, s.height, s.spp, s.max_depth,
                     args.integrator.c_str(), accel->name(), load_s, build_s,
                     resume.active ? " (resumed)" : "");

    if (!s.quiet && s.hemisphere && s.integrator != IntegratorKind::Normals &&
        (scene.features.has(LightKind::Point) || scene.features.has(LightKind::Spot) ||
         scene.features.has(LightKind::Directional)))
        std::fprintf(stderr, "candela: note: -H samples the point, spot and directional lights "
                             "directly: hemisphere sampling cannot find a delta light\n");
    if (!s.quiet) {
        std::string skips;
        for (const std::string& f : skipped_features(scene))
            skips += (skips.empty() ? "" : "; ") + f;
        if (!skips.empty()) std::fprintf(stderr, "candela: left out: %s\n", skips.c_str());
    }
    Renderer renderer(scene, *accel, s);
    RenderState state = resume.active ? std::move(resume.state) : renderer.start();
    if (state.film.width() != renderer.film_width() ||
        state.film.height() != renderer.film_height())
        throw Error(ErrorKind::Io, args.resume + ": error: checkpoint does not match its settings");

    Checkpoint ck;
    ck.args = argv;
    ck.scene_hash = file_hash(args.scene);
    ck.env_hash = args.build.env_map.empty() ? 0 : file_hash(args.build.env_map);
    bool wrote_checkpoint = false;
    auto last_ckpt = std::chrono::steady_clock::now();
    auto save = [&](const RenderState& st) {
        if (!ctx.root()) return;
        ck.state = st; // a copy: the render goes on with its own
        write_checkpoint(ckpt_path, ck);
        wrote_checkpoint = true;
    };
    std::function<void(const RenderState&)> on_pass;
    if (args.checkpoint_every > 0.0)
        on_pass = [&](const RenderState& st) {
            auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - last_ckpt).count() < args.checkpoint_every ||
                st.finished(s.spp))
                return;
            save(st);
            last_ckpt = now;
        };

    g_stop = false;
    auto old_int = std::signal(SIGINT, on_signal);
    auto old_term = std::signal(SIGTERM, on_signal);
    RenderStats stats;
    try {
        Renderer(scene, *accel, s).run(state, stats, &g_stop, on_pass, ctx);
    } catch (const Error& e) {
        // E.g. a checkpoint that rank 0 cannot write: the other ranks are inside a collective.
        if (ctx.size() > 1) {
            std::fprintf(stderr, "%s\n", e.what());
            ctx.abort_job(static_cast<int>(e.kind()));
        }
        throw;
    }
    std::signal(SIGINT, old_int);
    std::signal(SIGTERM, old_term);
    if (stats.interrupted) save(state);
    const Film& film = state.film;

    std::vector<std::pair<std::string, std::string>> meta = {
        {"candela:version", CANDELA_VERSION},
        {"candela:scene", args.scene},
        {"candela:spp", std::to_string(s.spp)},
        {"candela:seed", std::to_string(s.seed)},
        {"candela:sample_offset", std::to_string(s.sample_offset)},
        {"candela:accel", accel_kind_name(s.accel.kind)},
        {"candela:triangle", args.triangle},
        {"candela:sampler", args.sampler},
        {"candela:integrator", args.integrator},
        {"candela:max_depth", std::to_string(s.max_depth)},
        {"candela:light_samples", std::to_string(s.light_samples)},
        {"candela:render_seconds", fmt_double(stats.seconds)},
        {"candela:samples", std::to_string(film.total_samples() + film.total_dropped())},
        {"candela:nonfinite_dropped", std::to_string(film.total_dropped())},
        {"candela:interrupted", stats.interrupted ? "1" : "0"},
    };
    if (ctx.size() > 1) meta.push_back({"candela:mpi_ranks", std::to_string(ctx.size())});
    if (!ctx.root()) return stats.interrupted ? static_cast<int>(ErrorKind::Interrupted) : 0;
    const bool png = path_extension(args.output) == ".png";
    if (!png) write_exr(args.output, film_to_image(film, meta));
    if (png || args.preview) {
        std::string preview =
            png ? args.output : args.output.substr(0, args.output.size() - 4) + ".png";
        write_png(preview, film.width(), film.height(), film_preview(film, args.exposure));
        // The relative sampler may give a pixel more than -s samples: scale the ramp to the
        // most a pixel can get, so red still means "the most samples".
        const int rate_max =
            s.adaptive == AdaptiveKind::Relative ? renderer.relative_max_per_pixel() : s.spp;
        write_png(rate_image_path(preview), film.width(), film.height(),
                  film_rate_image(film, rate_max));
    }
    // A finished render makes its checkpoint stale.
    if (!stats.interrupted && (wrote_checkpoint || resume.active)) std::remove(ckpt_path.c_str());

    if (!s.quiet) {
        std::fprintf(stderr,
                     "candela: wrote %s\n"
                     "summary: %.3f s wall, %llu samples, %llu rays + %llu shadow rays, "
                     "%.3g rays/s, %llu non-finite samples dropped\n",
                     args.output.c_str(), stats.seconds, (unsigned long long)stats.samples,
                     (unsigned long long)stats.rays, (unsigned long long)stats.shadow_rays,
                     stats.rays_per_second(), (unsigned long long)film.total_dropped());
        if (stats.interrupted)
            std::fprintf(stderr,
                         "candela: interrupted after %d of %d samples per pixel; checkpoint "
                         "%s (continue with: candela render --resume %s)\n",
                         state.next_sample, s.spp, ckpt_path.c_str(), ckpt_path.c_str());
    }
    return stats.interrupted ? static_cast<int>(ErrorKind::Interrupted) : 0;
}

} // namespace

namespace {
std::vector<std::string> g_argv;
}

void set_command_line(int argc, char** argv) {
    g_argv.assign(argv, argv + argc);
}

std::vector<std::string> command_args(const std::string& subcommand) {
    for (std::size_t i = 1; i < g_argv.size(); ++i)
        if (g_argv[i] == subcommand) return {g_argv.begin() + long(i) + 1, g_argv.end()};
    return {};
}

void add_render_command(CLI::App& app, int* status) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand(
        "render", "Render a scene to an HDR EXR (or a PNG preview). Flags follow the CS184 "
                  "path tracer (-s -l -t -m -o -e -b -d -f -r -p -c -a -H) with long forms");
    add_render_options(*cmd, *args);
    cmd->callback([args, status] { *status = run_render(*args); });
}

} // namespace candela::app
