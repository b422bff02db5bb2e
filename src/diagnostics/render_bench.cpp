// How much of a render is traversal: the render against raw Embree calls on its own rays.
#include "candela/diagnostics/render_bench.h"

#include "candela/diagnostics/accel_bench.h"
#include "candela/render/renderer.h"
#include "candela/sampling/rng.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <sstream>

namespace candela {

namespace {

/// Passes every query to `inner` and keeps a uniform sample of `cap` rays of each kind (a
/// reservoir, so that a render whose ray mix changes from pass to pass, like the relative
/// sampler's, is sampled over all its passes): camera rays are the coherent closest-hit
/// batches, bounce rays the other closest-hit queries, shadow rays the occlusion queries. Used
/// only for the untimed recording render, so its lock costs nothing that is measured.
class RecordingAccel final : public Accel {
  public:
    RecordingAccel(const Accel& inner, std::size_t cap) : inner_(inner), cap_(cap) {}

    std::optional<Hit> intersect(const Ray& ray) const override {
        keep(bounce_, ray);
        return inner_.intersect(ray);
    }
    bool occluded(const Ray& ray) const override {
        keep(shadow_, ray);
        return inner_.occluded(ray);
    }
    void intersect_batch(BatchRayHit* rays, std::size_t n,
                         BatchCoherence coherence) const override {
        Reservoir& dst = coherence == BatchCoherence::Coherent ? camera_ : bounce_;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            for (std::size_t i = 0; i < n; ++i)
                if (rays[i].ray.tnear <= rays[i].ray.tfar) offer(dst, batch_ray(rays[i].ray));
        }
        inner_.intersect_batch(rays, n, coherence);
    }
    void occluded_batch(BatchRay* rays, std::size_t n) const override {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            for (std::size_t i = 0; i < n; ++i)
                if (rays[i].tnear <= rays[i].tfar) offer(shadow_, batch_ray(rays[i]));
        }
        inner_.occluded_batch(rays, n);
    }
    Bounds3 bounds() const override { return inner_.bounds(); }
    const char* name() const override { return inner_.name(); }
    std::size_t memory_bytes() const override { return inner_.memory_bytes(); }

    struct Reservoir {
        std::vector<Ray> rays;
        std::uint64_t seen = 0;
    };
    mutable Reservoir camera_, bounce_, shadow_;

  private:
    void keep(Reservoir& dst, const Ray& ray) const {
        std::lock_guard<std::mutex> lock(mutex_);
        if (is_valid_ray(ray)) offer(dst, ray);
    }
    /// Reservoir sampling (lock held): the k-th ray offered replaces a kept one with probability
    /// cap / k.
    void offer(Reservoir& dst, const Ray& ray) const {
        ++dst.seen;
        if (dst.rays.size() < cap_) {
            dst.rays.push_back(ray);
            return;
        }
        const std::uint64_t j = hash_combine(kReservoirSeed, dst.seen) % dst.seen;
        if (j < cap_) dst.rays[std::size_t(j)] = ray;
    }
    /// Seeds the reservoir's choices: which rays are kept matters only for timing.
    static constexpr std::uint64_t kReservoirSeed = 0x7265636f7264ULL;
    const Accel& inner_;
    std::size_t cap_;
    mutable std::mutex mutex_;
};

/// Rays recorded from a render of `s` (with `spp` samples per pixel) through `accel`.
struct RecordedRays {
    std::vector<Ray> camera, bounce, shadow;
};
RecordedRays record_rays(const Scene& scene, const Accel& accel, RenderSettings s, int spp,
                         std::size_t cap) {
    RecordingAccel recorder(accel, cap);
    s.spp = spp;
    s.time_budget = 0.0;
    RenderStats st;
    Renderer(scene, recorder, s).render(st);
    return {std::move(recorder.camera_.rays), std::move(recorder.bounce_.rays),
            std::move(recorder.shadow_.rays)};
}

/// The rows of one configuration: its renders at every thread count, and the raw loops on rays
/// recorded from it.
void bench_config(const Scene& scene, const Accel& accel, const std::string& name,
                  const RenderSettings& base, const RecordedRays& rec,
                  const std::vector<int>& threads, const RenderBenchOptions& opt,
                  RenderBenchReport& rep, Progress& progress) {
    for (int t : threads) {
        RenderBenchRow row;
        row.config = name;
        row.threads = t;
        RenderSettings s = base;
        s.threads = t;
        const Renderer renderer(scene, accel, s);
        std::vector<double> wall, cpu;
        for (int round = 0; round < std::max(1, opt.render_rounds); ++round) {
            RenderStats st;
            const double cpu0 = process_cpu_seconds();
            renderer.render(st);
            cpu.push_back(process_cpu_seconds() - cpu0);
            wall.push_back(st.seconds);
            row.camera_rays = st.camera_rays;
            row.bounce_rays = st.rays - st.camera_rays;
            row.shadow_rays = st.shadow_rays;
            progress.add(1);
        }
        row.render = Spread::of(wall);
        row.render_seconds = row.render.median;
        row.render_cpu_seconds = Spread::of(cpu).median;
        const RawEmbreeRates raw =
            time_raw_embree(scene, s.accel, rec.camera, rec.bounce, rec.shadow, t, opt.raw_seconds,
                            opt.raw_rounds, &progress);
        rep.embree_config = raw.embree_config;
        row.raw_camera = raw.camera.median;
        row.raw_bounce = raw.bounce.median;
        row.raw_shadow = raw.shadow.median;
        row.raw_camera_spread = raw.camera;
        row.raw_bounce_spread = raw.bounce;
        row.raw_shadow_spread = raw.shadow;
        // A kind the render traced but the raw loops could not time (no ray of it recorded)
        // leaves the ceiling unmeasured (0, printed n/a) rather than too low.
        bool complete = true;
        auto at = [&complete](std::uint64_t n, double mrays) {
            if (n > 0 && !(mrays > 0.0)) complete = false;
            return mrays > 0.0 ? double(n) / (mrays * 1e6) : 0.0;
        };
        const double ceiling = at(row.camera_rays, row.raw_camera) +
                               at(row.bounce_rays, row.raw_bounce) +
                               at(row.shadow_rays, row.raw_shadow);
        const double ceiling_cpu = at(row.camera_rays, raw.camera_cpu) +
                                   at(row.bounce_rays, raw.bounce_cpu) +
                                   at(row.shadow_rays, raw.shadow_cpu);
        row.ceiling_seconds = complete ? ceiling : 0.0;
        row.ceiling_cpu_seconds = complete ? ceiling_cpu : 0.0;
        rep.rows.push_back(row);
    }
}

} // namespace

RenderBenchReport run_render_bench(const Scene& scene, const RenderBenchOptions& opt) {
    if (opt.settings.accel.kind != AccelKind::Embree)
        throw Error(ErrorKind::Usage,
                    "bench --render: the raw-Embree ceiling compares like for like only with "
                    "--accel embree");
    RenderBenchReport rep;
    rep.scene = scene.source;
    rep.triangles = scene.triangle_count();
    rep.spheres = scene.spheres.size();
    rep.width = opt.settings.width;
    rep.height = opt.settings.height;
    rep.spp = opt.settings.spp;
    rep.max_depth = opt.settings.max_depth;

    RenderSettings base = opt.settings;
    base.quiet = true;
    base.progress = ProgressMode::None;
    const std::unique_ptr<Accel> accel = make_accel(scene, base.accel);

    // Rays to time the raw loops on. Uniform renders trace the same mix of rays in every pass:
    // recorded from a render of the same settings with just enough samples per pixel to fill
    // the record. The default's mix changes from pass to pass: recorded from the whole render.
    const std::size_t pixels = std::size_t(base.width) * std::size_t(base.height);
    const int uniform_spp = static_cast<int>(std::min<std::size_t>(
        std::size_t(base.spp), std::max<std::size_t>(1, (opt.record_rays + pixels - 1) /
                                                            std::max<std::size_t>(pixels, 1))));
    const RecordedRays uniform_rays =
        record_rays(scene, *accel, base, uniform_spp, opt.record_rays);
    rep.recorded_camera = uniform_rays.camera.size();
    rep.recorded_bounce = uniform_rays.bounce.size();
    rep.recorded_shadow = uniform_rays.shadow.size();

    std::vector<int> threads;
    for (int t : opt.threads) {
        const int n = t > 0 ? t : tbb::info::default_concurrency();
        if (std::find(threads.begin(), threads.end(), n) == threads.end()) threads.push_back(n);
    }
    // One step per timed render and per raw loop (three kinds a round).
    const std::size_t configs = opt.default_settings ? 2 : 1;
    Progress progress(
        configs * threads.size() *
            std::size_t(std::max(1, opt.render_rounds) + 3 * std::max(1, opt.raw_rounds)),
        opt.progress);
    bench_config(scene, *accel, "uniform", base, uniform_rays, threads, opt, rep, progress);
    if (opt.default_settings) {
        RenderSettings d = *opt.default_settings;
        d.quiet = true;
        d.progress = ProgressMode::None;
        const RecordedRays default_rays = record_rays(scene, *accel, d, d.spp, opt.record_rays);
        bench_config(scene, *accel, "default", d, default_rays, threads, opt, rep, progress);
    }
    progress.finish();
    return rep;
}

std::string RenderBenchReport::to_text() const {
    std::ostringstream os;
    os << "scene " << scene << ": " << count_of(triangles, "triangle") << ", "
       << count_of(spheres, "sphere") << "; " << width << "x" << height << ", " << spp
       << " spp, max depth " << max_depth << "; embree device \"" << embree_config << "\"\n";
    os << "raw rays recorded from the render: " << recorded_camera << " camera, " << recorded_bounce
       << " bounce, " << recorded_shadow << " shadow\n";
    for (const std::string& n : notes)
        os << "note: " << n << "\n";
    os << "\n";
    // A figure that was not measured (no ray of a kind, no ceiling) is n/a, not 0.
    auto num = [](double v, const char* format) {
        return v > 0.0 ? fmt::format(format, v) : std::string("n/a");
    };
    auto share = [](double ceiling, double fraction) {
        return ceiling > 0.0 ? fmt::format("{:.1f}%", 100.0 * fraction) : std::string("n/a");
    };
    os << "config   threads  render s   Mrays/s   camera M  bounce M  shadow M   raw Mrays/s "
          "(cam/bnc/shd)   ceiling s  of ceiling   cpu: render s  ceiling s  of ceiling\n";
    for (const RenderBenchRow& r : rows)
        os << fmt::format("{:<8} {:>7} {:>9} {:>9} {:>10.2f} {:>9.2f} {:>9.2f}   {:>7} {:>7} "
                          "{:>7}   {:>10} {:>11}   {:>13} {:>10} {:>11}\n",
                          r.config, r.threads, num(r.render_seconds, "{:.3f}"),
                          num(r.mrays_per_s(), "{:.2f}"), r.camera_rays * 1e-6,
                          r.bounce_rays * 1e-6, r.shadow_rays * 1e-6, num(r.raw_camera, "{:.2f}"),
                          num(r.raw_bounce, "{:.2f}"), num(r.raw_shadow, "{:.2f}"),
                          num(r.ceiling_seconds, "{:.3f}"), share(r.ceiling_seconds, r.fraction()),
                          num(r.render_cpu_seconds, "{:.3f}"), num(r.ceiling_cpu_seconds, "{:.3f}"),
                          share(r.ceiling_cpu_seconds, r.cpu_fraction()));
    os << "\nspread over the repeats, median (min-max):\n";
    for (const RenderBenchRow& r : rows)
        os << fmt::format("  {} at {} threads: render s {}; raw Mrays/s camera {}, bounce {}, "
                          "shadow {}\n",
                          r.config, r.threads, r.render.text(3), r.raw_camera_spread.text(2),
                          r.raw_bounce_spread.text(2), r.raw_shadow_spread.text(2));
    os << "\nuniform: uniform Sobol samples; default: the render command's default (the relative"
          " adaptive sampler, its noise threshold, the same -s as its budget). Each time and rate"
          " is the median of its repeats. ceiling s: the render's own ray counts at the raw"
          " rtcIntersect1/rtcOccluded1 rates; of ceiling = ceiling s / render s (wall clock); cpu:"
          " the same in processor seconds of all threads, which time taken by other processes"
          " does not inflate\n";
    return os.str();
}

std::string RenderBenchReport::to_json() const {
    using Json = nlohmann::ordered_json;
    // What was not measured is null, not 0.
    auto measured = [](double v) { return v > 0.0 ? Json(v) : Json(nullptr); };
    auto range = [](const Spread& s) {
        return s.measured() ? Json::array({s.min, s.max}) : Json(nullptr);
    };
    Json row_list = Json::array();
    for (const RenderBenchRow& r : rows)
        row_list.push_back(
            {{"config", r.config},
             {"threads", r.threads},
             {"render_seconds", r.render_seconds},
             {"render_seconds_range", range(r.render)},
             {"render_rounds", r.render.repeats},
             {"camera_rays", r.camera_rays},
             {"bounce_rays", r.bounce_rays},
             {"shadow_rays", r.shadow_rays},
             {"raw_mrays_per_s",
              {{"camera", measured(r.raw_camera)},
               {"bounce", measured(r.raw_bounce)},
               {"shadow", measured(r.raw_shadow)}}},
             {"raw_mrays_per_s_range",
              {{"camera", range(r.raw_camera_spread)},
               {"bounce", range(r.raw_bounce_spread)},
               {"shadow", range(r.raw_shadow_spread)}}},
             {"ceiling_seconds", measured(r.ceiling_seconds)},
             {"fraction_of_ceiling", r.ceiling_seconds > 0.0 ? Json(r.fraction()) : Json()},
             {"render_cpu_seconds", measured(r.render_cpu_seconds)},
             {"ceiling_cpu_seconds", measured(r.ceiling_cpu_seconds)},
             {"cpu_fraction_of_ceiling",
              r.ceiling_cpu_seconds > 0.0 ? Json(r.cpu_fraction()) : Json()}});
    const Json j = {{"scene", scene},         {"triangles", triangles},
                    {"spheres", spheres},     {"width", width},
                    {"height", height},       {"spp", spp},
                    {"max_depth", max_depth}, {"embree_config", embree_config},
                    {"rows", row_list},       {"notes", notes}};
    return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

} // namespace candela
