#include "commands.h"
#include "scene_source.h"

#include "candela/accel/bench.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>

namespace candela::app {

namespace {
struct BenchArgs {
    std::string scene, procedural, accels = "embree,builtin", triangle = "mt";
    std::string quality = "medium";
    std::vector<int> threads = {1, 0};
    bool json = false, robust = false, strict = false, no_raw = false;
    BenchOptions opt;
    LogArgs log;
};
} // namespace

void add_bench_command(CLI::App& app, int* status) {
    auto a = std::make_shared<BenchArgs>();
    CLI::App* cmd = app.add_subcommand(
        "bench", "Rays per second per backend and ray kind (primary, incoherent bounce, "
                 "shadow), build time and memory, against raw Embree calls in the same run");
    cmd->add_option("scene", a->scene, "COLLADA scene file (.dae)");
    cmd->add_option("--procedural", a->procedural,
                    "Generated scene instead: sphere:N (tessellated sphere, ~N triangles) or "
                    "soup:N (random triangles)");
    cmd->add_option("--accel", a->accels, "Backends: embree, builtin, brute")
        ->capture_default_str();
    cmd->add_option("--triangle", a->triangle, "Triangle test of builtin/brute: mt or watertight")
        ->capture_default_str();
    cmd->add_flag("--embree-robust", a->robust, "Embree robust traversal");
    cmd->add_option("--embree-quality", a->quality, "low, medium or high")->capture_default_str();
    cmd->add_option("--embree-isa", a->opt.embree_isa,
                    "Embree device ISA, e.g. avx2 or avx512; default: Embree's choice")
        ->capture_default_str();
    cmd->add_option("-t,--threads", a->threads, "Thread counts to measure; 0 = all cores")
        ->capture_default_str();
    cmd->add_option("--rays", a->opt.bounce_rays, "Incoherent and shadow rays per batch")
        ->capture_default_str();
    cmd->add_option("--min-seconds", a->opt.min_seconds, "Minimum timed duration per figure")
        ->capture_default_str();
    cmd->add_option("--seed", a->opt.seed, "Random seed")->capture_default_str();
    cmd->add_flag("--no-raw", a->no_raw, "Skip the raw Embree ceiling");
    cmd->add_flag("--json", a->json, "Machine-readable JSON");
    cmd->add_flag("--strict", a->strict, "Treat scene warnings as errors");
    add_log_options(*cmd, a->log);
    cmd->callback([a, status] {
        set_log_level(log_level_of(a->log));
        a->opt.accels = parse_accel_list(a->accels);
        a->opt.triangle = parse_triangle_test(a->triangle);
        if (a->quality == "low")
            a->opt.embree_quality = AccelOptions::Quality::Low;
        else if (a->quality == "medium")
            a->opt.embree_quality = AccelOptions::Quality::Medium;
        else if (a->quality == "high")
            a->opt.embree_quality = AccelOptions::Quality::High;
        else
            throw Error(ErrorKind::Usage, "error: --embree-quality: expected low, medium or high");
        for (int t : a->threads)
            if (t < 0) throw Error(ErrorKind::Usage, "error: --threads must be >= 0");
        a->opt.threads = a->threads;
        a->opt.shadow_rays = a->opt.bounce_rays;
        a->opt.embree_robust = a->robust;
        a->opt.raw_embree = !a->no_raw;
        Scene scene = load_scene_or_procedural(a->scene, a->procedural, a->strict);
        BenchReport report = run_bench(scene, a->opt);
        std::string text = a->json ? report.to_json() : report.to_text();
        std::fwrite(text.data(), 1, text.size(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
