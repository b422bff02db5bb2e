#include "candela/io/cli.h"

#include "candela/render/memory_budget.h"

#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace candela {

namespace {

/// Largest accepted image edge: far above any real frame, far below sizes whose film (about
/// 100 bytes per pixel with every channel) would not fit in memory.
constexpr int kMaxImageEdge = 32768;
/// Largest accepted pixel count (256 Mpixel).
constexpr long long kMaxPixels = 1ll << 28;
/// Largest accepted samples per pixel (2^24: sample counts stay exact in a float channel).
constexpr int kMaxSpp = 1 << 24;
constexpr int kMaxThreads = 4096;
constexpr int kMaxDepth = 1 << 16;

[[noreturn]] void usage(const std::string& what) {
    throw Error(ErrorKind::Usage, "error: " + what);
}

template <typename T>
T pick(const std::string& flag, const std::string& value,
       std::initializer_list<std::pair<const char*, T>> choices) {
    std::string names;
    for (const auto& c : choices) {
        if (value == c.first) return c.second;
        names += names.empty() ? "" : ", ";
        names += c.first;
    }
    usage(flag + ": unknown value '" + value + "' (expected one of: " + names + ")");
}

} // namespace

std::string default_output_path(const std::string& scene_path) {
    std::size_t slash = scene_path.find_last_of('/');
    std::string base = slash == std::string::npos ? scene_path : scene_path.substr(slash + 1);
    std::size_t dot = base.find_last_of('.');
    if (dot != std::string::npos && dot > 0) base = base.substr(0, dot);
    return base + ".exr";
}

void add_render_options(CLI::App& app, RenderArgs& a) {
    RenderSettings& s = a.settings;
    app.add_option("scene", a.scene, "COLLADA scene file (.dae)");
    app.add_option("-f,--output", a.output,
                   "Output image: .exr (HDR with auxiliary channels) or .png (sRGB preview plus "
                   "<name>_rate.png). Default: <scene name>.exr in the current directory");
    app.add_option("-s,--spp", s.spp, "Samples per pixel; the maximum when adaptive")
        ->capture_default_str();
    app.add_option("-l,--light-samples", s.light_samples,
                   "Light samples per shading point (per non-delta light for --integrator=direct)"
                   "; also the -H budget")
        ->capture_default_str();
    app.add_option("-t,--threads", s.threads, "Worker threads; 0 = all cores")
        ->capture_default_str();
    app.add_option("-m,--max-depth", s.max_depth, "Maximum number of scattering events per path")
        ->capture_default_str();
    app.add_option("-o,--accumulate", a.accumulate,
                   "1: sum light scattered 0..m times; 0: only light scattered exactly m times")
        ->capture_default_str();
    app.add_option("-e,--env", a.build.env_map, "Lat-long EXR environment map");
    app.add_option_function<float>(
        "-b,--lens-radius", [&a](const float& v) { a.lens_radius = v; },
        "Thin-lens aperture radius; 0 = pinhole (default: the camera file's, else 0)");
    app.add_option_function<float>(
        "-d,--focal-distance", [&a](const float& v) { a.focal_distance = v; },
        "Distance to the plane in focus (default: the camera file's, else 4.7)");
    app.add_option("-r,--resolution", a.resolution, "Image width and height (default 800 600)")
        ->expected(2)
        ->allow_extra_args(false);
    app.add_option("-p,--region", a.region,
                   "Render only the cell X Y DX DY (origin bottom-left, as in CS184); the output "
                   "is DX x DY")
        ->expected(4)
        ->allow_extra_args(false);
    app.add_option("-c,--camera-file", a.camera_file, "CS184 camera settings file");
    app.add_option("-a,--adaptive-sampling", a.adaptive,
                   "Adaptive sampling: BATCH TOLERANCE (CS184: batch 32, tolerance 0.05)")
        ->expected(2)
        ->allow_extra_args(false);
    app.add_flag("-H,--hemisphere", s.hemisphere,
                 "Direct light by uniform hemisphere sampling instead of light sampling");
    app.add_option("--adaptive", a.adaptive_kind,
                   "Adaptive criterion with -a: cs184 (per-pixel stop at 1.96 sigma/sqrt(n) <= "
                   "TOL mu) or relative (the cost of a uniform -s render, spent in batches on the "
                   "pixels with the most smoothed relative error per unit of cost; stop at "
                   "estimated relative RMS error TOL)")
        ->capture_default_str();
    app.add_option("--time-budget", s.time_budget,
                   "Stop starting passes after SECONDS of rendering (whole passes; -s stays the "
                   "maximum); 0 = no limit")
        ->capture_default_str();
    app.add_option("--camera", a.camera_mode,
                   "framed: CS184 placement around the scene bounds; file: the COLLADA pose")
        ->capture_default_str();
    app.add_option("--accel", a.accel, "Ray traversal backend: embree, builtin or brute")
        ->capture_default_str();
    app.add_option("--triangle", a.triangle,
                   "Triangle test of builtin/brute: mt (Moller-Trumbore) or watertight")
        ->capture_default_str();
    app.add_flag("--embree-robust", a.embree_robust, "Embree robust (watertight) traversal");
    app.add_option("--embree-quality", a.embree_quality, "Embree build quality: low, medium, high")
        ->capture_default_str();
    app.add_option("--seed", s.seed, "Random seed")->capture_default_str();
    app.add_option("--sample-offset", s.sample_offset,
                   "First sample index (renders of disjoint ranges merge exactly)")
        ->capture_default_str();
    app.add_option("--sampler", a.sampler, "independent or sobol (Owen-scrambled)")
        ->capture_default_str();
    app.add_option("--integrator", a.integrator, "path, direct or normals")->capture_default_str();
    app.add_option("--light-paths", a.light_paths,
                   "all; direct (emitters seen directly + one bounce); indirect (two or more)")
        ->capture_default_str();
    app.add_flag("--no-mis", a.no_mis, "Disable multiple importance sampling");
    app.add_option("--rr-depth", s.rr_min_depth,
                   "Russian roulette starts after this many scattering events")
        ->capture_default_str();
    app.add_option("--aov", a.aov,
                   "EXR auxiliary channels: all, none, or a list of albedo,normal,depth,variance")
        ->capture_default_str();
    app.add_flag("--preview", a.preview,
                 "With an .exr output, also write an sRGB PNG preview and the sample-rate image "
                 "beside it");
    app.add_option("--exposure", a.exposure, "PNG preview exposure in stops")
        ->capture_default_str();
    app.add_flag("--strict", a.strict, "Treat scene warnings as errors");
    app.add_flag("-q,--quiet", s.quiet, "No progress or summary on stderr");
    app.add_option("--pass-spp", s.pass_spp,
                   "Samples per pixel per pass (the granularity of interrupts and checkpoints); "
                   "0 = automatic")
        ->capture_default_str();
    app.add_option("--checkpoint", a.checkpoint,
                   "Checkpoint file written on SIGINT/SIGTERM and with --checkpoint-every "
                   "(default: <output>.ckpt)");
    app.add_option("--checkpoint-every", a.checkpoint_every,
                   "Also write a checkpoint every SECONDS during the render (0 = only when "
                   "interrupted)")
        ->capture_default_str();
    app.add_option("--max-memory", a.max_memory,
                   "Refuse renders estimated to need more memory than this (e.g. 8G, 512M; "
                   "default: three quarters of physical memory)");
    app.add_option("--resume", a.resume,
                   "Continue an interrupted render from its checkpoint; the result is "
                   "bit-identical to an uninterrupted render. Other image settings may be "
                   "omitted; if given they must match the checkpoint's");
}

std::vector<std::string> image_defining_args(const std::vector<std::string>& argv) {
    // Options that change how or where a render runs, never its pixels.
    static const char* const with_value[] = {
        "-t", "--threads", "--checkpoint", "--checkpoint-every", "--resume", "--max-memory"};
    static const char* const flags[] = {"-q", "--quiet"};
    std::vector<std::string> out;
    for (std::size_t i = 0; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        bool skip = false;
        for (const char* f : flags)
            skip |= a == f;
        for (const char* o : with_value) {
            std::string eq = std::string(o) + "=";
            if (a == o) {
                skip = true;
                ++i; // its value
            } else if (a.rfind(eq, 0) == 0) {
                skip = true;
            }
        }
        if (!skip) out.push_back(a);
    }
    return out;
}

void finalize_render_args(RenderArgs& a) {
    RenderSettings& s = a.settings;
    if (a.scene.empty() && a.resume.empty())
        usage("a scene file is required (or --resume CHECKPOINT)");
    if (s.pass_spp < 0) usage("--pass-spp must be >= 0");
    a.max_memory_bytes =
        a.max_memory.empty() ? default_max_memory() : parse_memory_size(a.max_memory);
    if (!(s.time_budget >= 0.0) || !std::isfinite(s.time_budget))
        usage("--time-budget must be a finite number of seconds >= 0");
    if (!(a.checkpoint_every >= 0.0)) usage("--checkpoint-every must be >= 0");
    if (s.spp < 1 || s.spp > kMaxSpp)
        usage("-s/--spp: " + std::to_string(s.spp) + " is out of range [1, " +
              std::to_string(kMaxSpp) + "]");
    if (s.light_samples < 1 || s.light_samples > 65536)
        usage("-l/--light-samples: " + std::to_string(s.light_samples) +
              " is out of range [1, 65536]");
    if (s.threads < 0 || s.threads > kMaxThreads)
        usage("-t/--threads: " + std::to_string(s.threads) + " is out of range [0, " +
              std::to_string(kMaxThreads) + "]");
    if (s.max_depth < 0 || s.max_depth > kMaxDepth)
        usage("-m/--max-depth: " + std::to_string(s.max_depth) + " is out of range [0, " +
              std::to_string(kMaxDepth) + "]");
    if (s.rr_min_depth < 0) usage("--rr-depth must be >= 0");
    s.accumulate = a.accumulate > 0;
    if (a.lens_radius && (!std::isfinite(*a.lens_radius) || *a.lens_radius < 0.f))
        usage("-b/--lens-radius must be a finite number >= 0");
    if (a.focal_distance && (!std::isfinite(*a.focal_distance) || *a.focal_distance <= 0.f))
        usage("-d/--focal-distance must be a finite number > 0");
    if (!std::isfinite(a.exposure)) usage("--exposure must be finite");
    if (!a.resolution.empty()) {
        s.width = a.resolution[0];
        s.height = a.resolution[1];
    }
    if (s.width < 1 || s.height < 1 || s.width > kMaxImageEdge || s.height > kMaxImageEdge ||
        (long long)s.width * s.height > kMaxPixels)
        usage("-r/--resolution: " + std::to_string(s.width) + "x" + std::to_string(s.height) +
              " is out of range (each side 1.." + std::to_string(kMaxImageEdge) +
              ", at most 2^28 pixels)");
    if (!a.region.empty()) {
        int x = a.region[0], y = a.region[1], dx = a.region[2], dy = a.region[3];
        if (x < 0 || y < 0 || dx < 1 || dy < 1 || x + dx > s.width || y + dy > s.height)
            usage("-p/--region: cell " + std::to_string(x) + " " + std::to_string(y) + " " +
                  std::to_string(dx) + " " + std::to_string(dy) + " is not inside the " +
                  std::to_string(s.width) + "x" + std::to_string(s.height) + " frame");
        // CS184 cells count rows from the bottom; the film counts from the top.
        s.region = Region{x, s.height - (y + dy), dx, dy};
    }
    if (!a.adaptive.empty()) {
        double batch = a.adaptive[0], tol = a.adaptive[1];
        if (batch < 1 || batch != std::floor(batch) || batch > kMaxSpp)
            usage("-a: the batch size must be a whole number >= 1");
        if (!std::isfinite(tol) || tol <= 0.0) usage("-a: the tolerance must be > 0");
        s.adaptive_batch = int(batch);
        s.adaptive_tol = float(tol);
        s.adaptive = pick<AdaptiveKind>(
            "--adaptive", a.adaptive_kind,
            {{"cs184", AdaptiveKind::Cs184}, {"relative", AdaptiveKind::Relative}});
    }
    s.accel.kind = pick<AccelKind>("--accel", a.accel,
                                   {{"embree", AccelKind::Embree},
                                    {"builtin", AccelKind::Builtin},
                                    {"brute", AccelKind::Brute}});
    s.accel.triangle = pick<TriangleTest>(
        "--triangle", a.triangle,
        {{"mt", TriangleTest::MollerTrumbore}, {"watertight", TriangleTest::Watertight}});
    s.accel.embree_robust = a.embree_robust;
    s.accel.quality = pick<AccelOptions::Quality>("--embree-quality", a.embree_quality,
                                                  {{"low", AccelOptions::Quality::Low},
                                                   {"medium", AccelOptions::Quality::Medium},
                                                   {"high", AccelOptions::Quality::High}});
    s.sampler = pick<SamplerKind>(
        "--sampler", a.sampler,
        {{"independent", SamplerKind::Independent}, {"sobol", SamplerKind::Sobol}});
    s.integrator = pick<IntegratorKind>("--integrator", a.integrator,
                                        {{"path", IntegratorKind::Path},
                                         {"direct", IntegratorKind::Direct},
                                         {"normals", IntegratorKind::Normals}});
    s.light_paths = pick<LightPaths>("--light-paths", a.light_paths,
                                     {{"all", LightPaths::All},
                                      {"direct", LightPaths::Direct},
                                      {"indirect", LightPaths::Indirect}});
    s.mis = !a.no_mis;
    s.aovs = AovSet::parse(a.aov);
    a.build.camera_mode = pick<CameraMode>(
        "--camera", a.camera_mode, {{"framed", CameraMode::Framed}, {"file", CameraMode::File}});
    if (a.output.empty()) a.output = default_output_path(a.scene);
    std::string ext;
    {
        std::size_t dot = a.output.find_last_of('.');
        std::size_t slash = a.output.find_last_of('/');
        if (dot != std::string::npos && (slash == std::string::npos || dot > slash))
            ext = a.output.substr(dot);
        for (char& c : ext)
            c = char(std::tolower(static_cast<unsigned char>(c)));
    }
    if (ext != ".exr" && ext != ".png")
        usage("-f/--output: '" + a.output + "' must end in .exr or .png");
}

RenderArgs parse_render_command_line(const std::vector<std::string>& argv) {
    RenderArgs args;
    CLI::App app{"render"};
    add_render_options(app, args);
    std::vector<std::string> reversed(argv.rbegin(), argv.rend());
    try {
        app.parse(reversed);
    } catch (const CLI::ParseError& e) {
        throw Error(ErrorKind::Usage, std::string("error: ") + e.what());
    }
    finalize_render_args(args);
    return args;
}

void apply_camera_file(const std::string& path, Scene& scene) {
    std::ifstream in(path);
    if (!in) throw Error(ErrorKind::Io, path + ": error: cannot open camera file");
    std::vector<double> v;
    std::string tok;
    int line = 1;
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) {
            if (text[i] == '\n') ++line;
            ++i;
        }
        std::size_t j = i;
        while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j])))
            ++j;
        if (j == i) break;
        tok = text.substr(i, j - i);
        char* end = nullptr;
        double d = std::strtod(tok.c_str(), &end);
        if (end != tok.c_str() + tok.size() || !std::isfinite(d))
            throw Error(ErrorKind::Scene, path + ":" + std::to_string(line) + ": error: '" + tok +
                                              "' is not a finite number");
        v.push_back(d);
        i = j;
    }
    // hFov vFov aspect nClip fClip | pos(3) target(3) | phi theta r minR maxR | c2w(9) |
    // screenW screenH screenDist | focalDistance lensRadius  = 5+6+5+9+3+2 = 30 numbers.
    constexpr std::size_t kCameraFileNumbers = 30;
    if (v.size() != kCameraFileNumbers)
        throw Error(ErrorKind::Scene, path + ":" + std::to_string(line) + ": error: expected " +
                                          std::to_string(kCameraFileNumbers) +
                                          " numbers in a camera settings file, found " +
                                          std::to_string(v.size()));
    Camera& c = scene.camera;
    c.hfov_deg = float(v[0]);
    c.znear = float(v[3]);
    c.zfar = float(v[4]);
    c.pos = Vec3(float(v[5]), float(v[6]), float(v[7]));
    c.target = Vec3(float(v[8]), float(v[9]), float(v[10]));
    // c2w is row-major; its columns are the camera X, Y, Z axes.
    const double* m = &v[16];
    c.x = normalize(Vec3(float(m[0]), float(m[3]), float(m[6])));
    c.y = normalize(Vec3(float(m[1]), float(m[4]), float(m[7])));
    c.z = normalize(Vec3(float(m[2]), float(m[5]), float(m[8])));
    c.focal_distance = float(v[28]);
    c.lens_radius = float(v[29]);
    if (!(c.hfov_deg > 0.f && c.hfov_deg < 180.f) || !(c.znear >= 0.f) || !(c.zfar > c.znear))
        throw Error(ErrorKind::Scene, path + ": error: camera field of view or clip planes out "
                                             "of range");
}

} // namespace candela
