// `candela check`: cross-checks accelerators against each other on the rays a render traces.
#include "commands.h"
#include "scene_source.h"

#include "candela/diagnostics/check.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>

namespace candela::app {

namespace {
struct CheckArgs {
    std::string scene, procedural, accels = "embree,builtin,brute", triangle = "mt";
    std::string worst_path;
    bool json = false, robust = false, strict = false;
    CheckOptions opt;
    LogArgs log;
};
} // namespace

void add_check_command(CLI::App& app, int* status) {
    auto a = std::make_shared<CheckArgs>();
    CLI::App* cmd = app.add_subcommand(
        "check", "Cross-check ray-traversal backends ray by ray: camera, incoherent bounce, "
                 "shadow and edge/vertex rays; classify every disagreement");
    cmd->add_option("scene", a->scene, "COLLADA scene file (.dae)");
    cmd->add_option("--procedural", a->procedural, "Generated scene instead, e.g. sphere:100000");
    cmd->add_option("--accel", a->accels,
                    "Backends to compare, at least two; each is compared with the reference, "
                    "which is brute when listed, else builtin, else the first")
        ->capture_default_str();
    cmd->add_option("--triangle", a->triangle,
                    "Triangle test of builtin/brute: " +
                        enum_choices(kTriangleTests, {", ", " or ", "", "", false}))
        ->capture_default_str();
    cmd->add_flag("--embree-robust", a->robust, "Embree robust traversal");
    cmd->add_option("--camera-rays", a->opt.camera_width, "Camera rays: grid width (height 3/4)")
        ->capture_default_str();
    cmd->add_option("--bounce-rays", a->opt.bounce_rays, "Incoherent bounce rays")
        ->capture_default_str();
    cmd->add_option("--shadow-rays", a->opt.shadow_rays, "Shadow rays")->capture_default_str();
    cmd->add_option("--edge-rays", a->opt.edge_rays, "Rays aimed at edges and vertices")
        ->capture_default_str();
    cmd->add_option("--seed", a->opt.seed, "Random seed")->capture_default_str();
    cmd->add_option("-t,--threads", a->opt.threads, "Threads, 0 = all")->capture_default_str();
    cmd->add_option("--worst", a->worst_path,
                    "Write the worst cases as replayable rays 'ox oy oz dx dy dz tmin tmax'");
    cmd->add_option("--worst-cases", a->opt.worst_cases,
                    "How many of the worst cases to print (and write with --worst)")
        ->capture_default_str();
    cmd->add_flag("--json", a->json, "Machine-readable JSON");
    cmd->add_flag("--strict", a->strict, "Treat scene warnings as errors");
    add_log_options(*cmd, a->log);
    cmd->callback([a, status] {
        set_log_level(log_level_of(a->log));
        a->opt.accels = parse_accel_list(a->accels);
        std::vector<AccelKind> distinct;
        for (AccelKind k : a->opt.accels)
            if (std::find(distinct.begin(), distinct.end(), k) == distinct.end())
                distinct.push_back(k);
        if (distinct.size() < 2)
            throw Error(ErrorKind::Usage, "check: --accel '" + a->accels +
                                              "' names one backend; give at least two to "
                                              "compare (e.g. --accel builtin,brute)");
        a->opt.triangle = parse_triangle_test(a->triangle);
        if (a->opt.camera_width < 1) throw Error(ErrorKind::Usage, "--camera-rays must be >= 1");
        a->opt.camera_height = std::max(1, a->opt.camera_width * 3 / 4);
        a->opt.embree_robust = a->robust;
        a->opt.worst_cases_path = a->worst_path;
        Scene scene = load_scene_or_procedural(a->scene, a->procedural, a->strict);
        CheckReport report = run_check(scene, a->opt);
        std::string text = a->json ? report.to_json() : report.to_text();
        std::fwrite(text.data(), 1, text.size(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
