// `candela bench`: ray throughput per backend, or with --render how much of a render is traversal.
#include "commands.h"
#include "scene_source.h"

#include "candela/app/cli.h"
#include "candela/diagnostics/accel_bench.h"
#include "candela/diagnostics/render_bench.h"
#include "candela/render/adaptive.h"
#include "candela/render/setting_table.h"
#include "candela/util/enum_table.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

namespace candela::app {

namespace {
struct BenchArgs {
    std::string scene, procedural, accels = "embree,builtin", triangle = "mt";
    std::string quality = enum_name(kEmbreeQualities, AccelOptions::Quality::Medium);
    std::vector<int> threads = {1, 0};
    bool json = false, robust = false, strict = false, no_raw = false;
    BenchOptions opt;
    // --render
    bool render = false;
    std::vector<int> resolution = {640, 480};
    int spp = 64, max_depth = 8, rounds = 3;
    SceneView view;
    std::string camera = enum_name(kCameraModes, CameraMode::Framed);
    std::string progress = enum_name(kProgressModes, ProgressMode::Auto);
    LogArgs log;
};

/// The machine's cores, which its load average counts against.
int machine_cores() {
    return std::max(1, int(std::thread::hardware_concurrency()));
}

/// The load warning (accel_bench.h) for this machine now, on stderr and in the report's notes;
/// empty when the load is within the cores or unknown.
std::string check_load(int cores) {
    const std::optional<double> load = one_minute_load();
    const std::string w = load ? load_warning(*load, cores) : "";
    if (!w.empty()) print_warning(w);
    return w;
}

/// The ISAs an Embree 3 device accepts in its "isa=" configuration; Embree ignores any other
/// name silently, so a typo would measure its default device under the wrong label.
const std::vector<std::string>& embree_isas() {
    static const std::vector<std::string> isas = {"sse2",      "sse4.2",    "avx",   "avx2",
                                                  "avx512knl", "avx512skx", "avx512"};
    return isas;
}

void check_embree_isa(const std::string& isa) {
    if (isa.empty() || isa == "default") return;
    const std::vector<std::string>& isas = embree_isas();
    if (std::find(isas.begin(), isas.end(), isa) != isas.end()) return;
    const std::string near = nearest_name(isa, isas);
    throw Error(ErrorKind::Usage,
                "bench: --embree-isa: unknown ISA '" + isa + "'" +
                    (near.empty() ? "" : "; did you mean '" + near + "'?") +
                    " (default, sse2, sse4.2, avx, avx2, avx512knl, avx512skx, avx512)");
}

} // namespace

void add_bench_command(CLI::App& app, int* status) {
    auto a = std::make_shared<BenchArgs>();
    CLI::App* cmd = app.add_subcommand(
        "bench", "Rays per second per backend and ray kind (primary, incoherent bounce, "
                 "shadow), build time and memory, against raw Embree calls in the same run");
    cmd->add_option("scene", a->scene, "COLLADA scene file (.dae)");
    cmd->add_option("--procedural", a->procedural,
                    "Generated scene instead: sphere:N (tessellated sphere, ~N triangles), "
                    "soup:N (random triangles), cube:N, spheres:N (analytic); box:KIND:N puts "
                    "it in a lit open box");
    cmd->add_flag("--render", a->render,
                  "Time renders instead (Sobol, embree; uniform samples, then the render "
                  "command's default relative adaptive sampler with -s as its budget): count "
                  "their camera, bounce and shadow rays, time raw rtcIntersect1/rtcOccluded1 "
                  "loops on rays recorded from each and print the fraction of that ceiling each "
                  "render reached");
    cmd->add_option("-r,--resolution", a->resolution, "With --render: width height")
        ->expected(2)
        ->capture_default_str();
    cmd->add_option("-s,--spp", a->spp, "With --render: samples per pixel")->capture_default_str();
    cmd->add_option("-m,--max-depth", a->max_depth, "With --render: maximum bounces")
        ->capture_default_str();
    cmd->add_option("-e,--env", a->view.env_map,
                    "Lat-long environment map (EXR or any image), as the render command's -e");
    cmd->add_option("--camera", a->camera,
                    "The render command's --camera: " +
                        enum_choices(kCameraModes, {"; ", "; ", ": ", ""}))
        ->capture_default_str();
    cmd->add_option("-c,--camera-file", a->view.camera_file,
                    "CS184 camera settings file, as the render command's -c");
    cmd->add_option("--render-rounds", a->rounds,
                    "With --render: renders per thread count (their median time is reported with "
                    "the range)")
        ->capture_default_str();
    cmd->add_option("--accel", a->accels,
                    "Backends: " + enum_choices(kAccelKinds, {", ", ", "}) + " (not with --render)")
        ->capture_default_str();
    cmd->add_option("--triangle", a->triangle,
                    "Triangle test of builtin/brute: " +
                        enum_choices(kTriangleTests, {", ", " or ", "", "", false}) +
                        " (not with --render)")
        ->capture_default_str();
    cmd->add_flag("--embree-robust", a->robust, "Embree robust traversal");
    cmd->add_option("--embree-quality", a->quality, enum_choices(kEmbreeQualities))
        ->capture_default_str();
    cmd->add_option("--embree-isa", a->opt.embree_isa,
                    "Embree device ISA: default (candela's: avx2 where the processor has it), "
                    "sse2, sse4.2, avx, avx2, avx512knl, avx512skx or avx512 (not with --render)")
        ->capture_default_str();
    // One value per -t, split at commas: "-t 1,2 SCENE" leaves SCENE to the scene.
    cmd->add_option("-t,--threads", a->threads,
                    "Thread counts to measure, comma-separated (e.g. -t 1,2); 0 = all cores")
        ->delimiter(',')
        ->allow_extra_args(false)
        ->capture_default_str();
    cmd->add_option("--rays", a->opt.bounce_rays,
                    "Incoherent and shadow rays per batch (not with --render)")
        ->capture_default_str();
    cmd->add_option("--min-seconds", a->opt.min_seconds, "Minimum timed duration per figure")
        ->capture_default_str();
    cmd->add_option("--seed", a->opt.seed, "Random seed")->capture_default_str();
    cmd->add_flag("--no-raw", a->no_raw,
                  "Skip the raw Embree ceiling (not with --render, which measures it)");
    cmd->add_flag("--json", a->json, "Machine-readable JSON");
    cmd->add_option("--progress", a->progress,
                    "Progress on stderr while it measures: auto (a bar when stderr is a "
                    "terminal, else nothing), bar, lines or none")
        ->capture_default_str();
    cmd->add_flag("--strict", a->strict, "Treat scene warnings as errors");
    add_log_options(*cmd, a->log);
    cmd->callback([a, status, cmd] {
        set_log_level(log_level_of(a->log));
        const ProgressMode progress = resolve_bench_progress(
            parse_enum(kProgressModes, setting_row(Setting::Progress).flag, a->progress),
            log_level() < LogLevel::Info);
        a->opt.progress = progress;
        a->opt.accels = parse_accel_list(a->accels);
        a->opt.triangle = parse_triangle_test(a->triangle);
        a->opt.embree_quality = parse_enum(kEmbreeQualities, "--embree-quality", a->quality);
        for (int t : a->threads)
            if (t < 0) throw Error(ErrorKind::Usage, "--threads must be >= 0");
        a->opt.threads = a->threads;
        if (a->opt.bounce_rays < 1) throw Error(ErrorKind::Usage, "bench: --rays must be >= 1");
        check_embree_isa(a->opt.embree_isa);
        a->opt.shadow_rays = a->opt.bounce_rays;
        a->opt.embree_robust = a->robust;
        a->opt.raw_embree = !a->no_raw;
        a->view.camera_mode = parse_enum(kCameraModes, "--camera", a->camera);
        if (a->render) {
            // The renders use the render command's accelerator (Embree, candela's device) and
            // record their own rays; the ray-rate bench's choices would be silently ignored.
            for (const char* flag : {"--accel", "--triangle", "--embree-isa", "--rays", "--no-raw"})
                if (cmd->count(flag) > 0)
                    throw Error(ErrorKind::Usage,
                                std::string("bench --render: ") + flag +
                                    " applies to the ray-rate bench only (--render measures the "
                                    "render command's Embree device on the renders' own rays)");
            if (a->resolution[0] < 1 || a->resolution[1] < 1 || a->spp < 1 || a->max_depth < 0 ||
                a->rounds < 1)
                throw Error(ErrorKind::Usage,
                            "bench --render: resolution, -s and --render-rounds must be "
                            ">= 1 and -m >= 0");
            RenderBenchOptions ro;
            ro.settings.width = a->resolution[0];
            ro.settings.height = a->resolution[1];
            ro.settings.spp = a->spp;
            ro.settings.max_depth = a->max_depth;
            ro.settings.sampler = SamplerKind::Sobol;
            ro.settings.seed = a->opt.seed;
            ro.settings.accel.kind = AccelKind::Embree;
            ro.settings.accel.embree_robust = a->robust;
            ro.settings.accel.quality = a->opt.embree_quality;
            ro.threads = a->threads;
            ro.render_rounds = a->rounds;
            ro.raw_seconds = std::max(a->opt.min_seconds, 0.1) * 3.0;
            RenderSettings d = ro.settings;
            use_relative_sampler(d, kDefaultAdaptiveBatch, kDefaultNoiseThreshold);
            ro.default_settings = d;
            ro.progress = progress;
            Scene scene = load_scene_with_view(a->scene, a->procedural, a->strict, a->view);
            const std::string load = check_load(machine_cores());
            RenderBenchReport report = run_render_bench(scene, ro);
            if (!load.empty()) report.notes.push_back("warning: " + load);
            std::string text = a->json ? report.to_json() + "\n" : report.to_text();
            std::fwrite(text.data(), 1, text.size(), stdout);
            *status = 0;
            return;
        }
        Scene scene = load_scene_with_view(a->scene, a->procedural, a->strict, a->view);
        const std::string load = check_load(machine_cores());
        BenchReport report = run_bench(scene, a->opt);
        if (!load.empty()) report.notes.push_back("warning: " + load);
        std::string text = a->json ? report.to_json() : report.to_text();
        std::fwrite(text.data(), 1, text.size(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
