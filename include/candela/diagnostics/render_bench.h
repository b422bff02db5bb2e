#pragma once
// How much of a render is traversal: renders a scene, counts its rays of each kind (camera,
// bounce, shadow), times raw Embree calls (rtcIntersect1 / rtcOccluded1 in tight loops) on rays
// recorded from the same render, and reports the fraction of that raw-Embree ceiling the render
// reached: ceiling seconds = sum over kinds of count / raw rate, fraction = ceiling / render.
// Each configuration (uniform samples; the render command's default, the relative adaptive
// sampler) is measured on rays recorded from its own render.
#include "candela/diagnostics/accel_bench.h"
#include "candela/render/settings.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

class Scene;

struct RenderBenchOptions {
    /// The render to measure, uniform samples (its accel must be embree for the ceiling to be
    /// like for like).
    RenderSettings settings;
    /// The render command's default sampling (the relative adaptive sampler) with the same
    /// scene, size, budget and threads, measured after `settings`; unset: uniform only.
    std::optional<RenderSettings> default_settings;
    /// Thread counts to measure; 0 means all available.
    std::vector<int> threads = {0};
    /// Rays of each kind recorded from a render of the same settings for the raw loops (a
    /// uniform sample of all its rays of that kind).
    std::size_t record_rays = std::size_t(1) << 20;
    /// Renders per thread count; their median time is reported with the range.
    int render_rounds = 3;
    /// Minimum duration of each raw-Embree figure, split over raw_rounds rounds (median kept).
    double raw_seconds = 1.5;
    int raw_rounds = 3;
    ProgressMode progress = ProgressMode::None; ///< resolved (resolve_bench_progress)
};

struct RenderBenchRow {
    std::string config = "uniform"; ///< "uniform" or "default"
    int threads = 1;
    /// Median render time over the rounds (passes only: no load, build or write); `render`
    /// has its range.
    double render_seconds = 0.0;
    Spread render;
    std::uint64_t camera_rays = 0, bounce_rays = 0, shadow_rays = 0;
    /// Mrays/s of the raw loops, the medians of their rounds (0: no ray of that kind), and
    /// their spreads.
    double raw_camera = 0.0, raw_bounce = 0.0, raw_shadow = 0.0;
    Spread raw_camera_spread, raw_bounce_spread, raw_shadow_spread;
    double ceiling_seconds = 0.0; ///< the same ray counts at the raw rates
    /// The same in processor time (all threads): the render's, and the ray counts at the raw
    /// loops' rays per processor-second. Other processes on the machine inflate wall times
    /// (render and raw loops alike, but not in step); processor time leaves them out.
    double render_cpu_seconds = 0.0, ceiling_cpu_seconds = 0.0;
    double fraction() const { return render_seconds > 0.0 ? ceiling_seconds / render_seconds : 0; }
    double cpu_fraction() const {
        return render_cpu_seconds > 0.0 ? ceiling_cpu_seconds / render_cpu_seconds : 0.0;
    }
    double mrays_per_s() const {
        return render_seconds > 0.0
                   ? double(camera_rays + bounce_rays + shadow_rays) / render_seconds * 1e-6
                   : 0.0;
    }
};

struct RenderBenchReport {
    std::string scene;
    std::size_t triangles = 0, spheres = 0;
    int width = 0, height = 0, spp = 0, max_depth = 0;
    std::string embree_config;
    std::size_t recorded_camera = 0, recorded_bounce = 0, recorded_shadow = 0; ///< uniform's
    std::vector<RenderBenchRow> rows;
    std::vector<std::string> notes; ///< e.g. the load warning
    std::string to_text() const;
    std::string to_json() const;
};

RenderBenchReport run_render_bench(const Scene& scene, const RenderBenchOptions& opt);

} // namespace candela
