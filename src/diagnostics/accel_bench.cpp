// Accelerator throughput: rays per second per backend, ray kind and thread count (accel_bench.h).
#include "candela/diagnostics/accel_bench.h"

#include "candela/accel/embree_accel.h"
#include "candela/diagnostics/check.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"
#include "candela/util/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>

namespace candela {

namespace {

/// Rays per parallel task: large enough that scheduling is negligible next to traversal.
constexpr std::size_t kBenchGrain = 512;

/// One pass over `rays` with `threads` threads, calling f(ray) -> bool; returns the count of
/// true answers.
template <typename F>
std::uint64_t run_pass(tbb::task_arena* arena, const std::vector<Ray>& rays, const F& f) {
    if (!arena) {
        std::uint64_t n = 0;
        for (const Ray& r : rays)
            n += f(r) ? 1 : 0;
        return n;
    }
    std::uint64_t n = 0;
    arena->execute([&] {
        n = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, rays.size(), kBenchGrain), std::uint64_t(0),
            [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t acc) {
                for (std::size_t i = r.begin(); i < r.end(); ++i)
                    acc += f(rays[i]) ? 1 : 0;
                return acc;
            },
            [](std::uint64_t a, std::uint64_t b) { return a + b; });
    });
    return n;
}

template <typename F>
BenchResult time_batch(const std::string& name, BenchRayKind kind, int threads,
                       const std::vector<Ray>& rays, double min_seconds, const F& f) {
    BenchResult res;
    res.accel = name;
    res.kind = kind;
    res.threads = threads;
    if (rays.empty()) return res;
    std::unique_ptr<tbb::task_arena> arena;
    if (threads != 1) arena = std::make_unique<tbb::task_arena>(threads);
    res.hits = run_pass(arena.get(), rays, f); // warm-up pass, also the hit count
    const double cpu0 = process_cpu_seconds();
    const Stopwatch timer;
    do {
        const std::uint64_t h = run_pass(arena.get(), rays, f);
        if (h != res.hits)
            throw Error(ErrorKind::Internal,
                        "bench: " + name + " gave different hit counts " + "on identical passes");
        res.rays += rays.size();
        res.seconds = timer.seconds();
    } while (res.seconds < min_seconds);
    res.cpu_seconds = process_cpu_seconds() - cpu0;
    res.mrays_per_s = static_cast<double>(res.rays) / res.seconds * 1e-6;
    res.mrays_per_cpu_s =
        res.cpu_seconds > 0.0 ? static_cast<double>(res.rays) / res.cpu_seconds * 1e-6 : 0.0;
    return res;
}

/// An Embree scene of its own, built from the scene's shared buffers: what the raw loops trace.
struct RawEmbreeScene {
    EmbreeDevice device;
    RTCScene scene = nullptr;
    RawEmbreeScene(const Scene& s, const std::string& isa, bool robust,
                   AccelOptions::Quality quality)
        : device(isa, 0) {
        scene = rtcNewScene(device.get());
        device.check("rtcNewScene");
        rtcSetSceneFlags(scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
        rtcSetSceneBuildQuality(scene, embree_build_quality(quality));
        attach_embree_geometry(device.get(), scene, s, embree_build_quality(quality));
        rtcCommitScene(scene);
        device.check("rtcCommitScene");
    }
    ~RawEmbreeScene() {
        if (scene) rtcReleaseScene(scene);
    }
    RawEmbreeScene(const RawEmbreeScene&) = delete;
    RawEmbreeScene& operator=(const RawEmbreeScene&) = delete;
};

/// One rtcIntersect1 call; true on a hit.
struct RawClosest {
    RTCScene scene;
    bool operator()(const Ray& r) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh = to_embree_rayhit(r);
        rtcIntersect1(scene, &ctx, &rh);
        return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
};

/// One rtcOccluded1 call; true when occluded.
struct RawOccluded {
    RTCScene scene;
    bool operator()(const Ray& r) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh = to_embree_rayhit(r);
        rtcOccluded1(scene, &ctx, &rh.ray);
        return rh.ray.tfar == -std::numeric_limits<float>::infinity();
    }
};

} // namespace

double process_cpu_seconds() {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    auto sec = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; };
    return sec(u.ru_utime) + sec(u.ru_stime);
}

const char* bench_ray_kind_name(BenchRayKind k) {
    switch (k) {
    case BenchRayKind::Primary:
        return "primary";
    case BenchRayKind::Bounce:
        return "bounce";
    case BenchRayKind::Shadow:
        return "shadow";
    case BenchRayKind::Count:
        break;
    }
    return "?";
}

double BenchReport::mrays(const std::string& accel, BenchRayKind kind, int threads) const {
    for (const BenchResult& r : results)
        if (r.accel == accel && r.kind == kind && r.threads == threads) return r.mrays_per_s;
    return 0.0;
}

double BenchReport::ratio(const std::string& a, const std::string& b, BenchRayKind kind,
                          int threads) const {
    const double x = mrays(a, kind, threads), y = mrays(b, kind, threads);
    return x > 0.0 && y > 0.0 ? x / y : 0.0;
}

std::string BenchReport::to_text() const {
    std::ostringstream os;
    os << "scene " << scene << ": " << count_of(triangles, "triangle") << ", "
       << count_of(spheres, "sphere") << "; embree device \"" << embree_config << "\"; up to "
       << max_threads << " threads\n";
    for (const std::string& n : notes)
        os << "note: " << n << "\n";
    os << "\nbuild      seconds   Mprims/s      memory   bytes/prim\n";
    for (const BenchBuild& b : builds) {
        char line[160];
        std::snprintf(line, sizeof line, "%-10s %8.4f %10.2f %11zu %12.1f\n", b.accel.c_str(),
                      b.build_seconds, b.mtris_per_s, b.memory_bytes, b.bytes_per_prim);
        os << line;
    }
    os << "\naccel       kind     threads    Mrays/s       hits\n";
    for (const BenchResult& r : results) {
        char line[160];
        std::snprintf(line, sizeof line, "%-11s %-8s %7d %10.3f %10llu\n", r.accel.c_str(),
                      bench_ray_kind_name(r.kind), r.threads, r.mrays_per_s,
                      static_cast<unsigned long long>(r.hits));
        os << line;
    }
    os << "\nratios at 1 thread:\n";
    for (int k = 0; k < static_cast<int>(BenchRayKind::Count); ++k) {
        const auto kind = static_cast<BenchRayKind>(k);
        const double er = ratio("embree", "embree-raw", kind, 1);
        const double be = ratio("builtin", "embree", kind, 1);
        os << "  " << bench_ray_kind_name(kind) << ": embree/raw "
           << (er > 0 ? fmt::format("{:.3f}", er) : "-") << ", builtin/embree "
           << (be > 0 ? fmt::format("{:.3f}", be) : "-") << "\n";
    }
    return os.str();
}

std::string BenchReport::to_json() const {
    using Json = nlohmann::ordered_json;
    Json build_list = Json::array();
    for (const BenchBuild& b : builds)
        build_list.push_back({{"accel", b.accel},
                              {"build_seconds", b.build_seconds},
                              {"mprims_per_s", b.mtris_per_s},
                              {"memory_bytes", b.memory_bytes},
                              {"bytes_per_prim", b.bytes_per_prim}});
    Json result_list = Json::array();
    for (const BenchResult& r : results)
        result_list.push_back({{"accel", r.accel},
                               {"kind", bench_ray_kind_name(r.kind)},
                               {"threads", r.threads},
                               {"rays", r.rays},
                               {"hits", r.hits},
                               {"seconds", r.seconds},
                               {"mrays_per_s", r.mrays_per_s}});
    const Json j = {{"scene", scene},
                    {"triangles", triangles},
                    {"spheres", spheres},
                    {"max_threads", max_threads},
                    {"embree_config", embree_config},
                    {"builds", build_list},
                    {"results", result_list},
                    {"notes", notes}};
    return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

BenchReport run_bench(const Scene& scene, const BenchOptions& opt) {
    BenchReport rep;
    rep.scene = scene.source;
    rep.triangles = scene.triangle_count();
    rep.spheres = scene.spheres.size();
    rep.max_threads = tbb::info::default_concurrency();
    const std::string isa =
        opt.embree_isa == "default" ? EmbreeDevice::default_isa() : opt.embree_isa;
    const double prims = static_cast<double>(rep.triangles + rep.spheres);

    // Ray batches first, outside every timed loop.
    std::vector<Ray> batches[static_cast<int>(BenchRayKind::Count)];
    batches[0] = make_camera_rays(scene, opt.primary_width, opt.primary_height);
    batches[1] = make_bounce_rays(scene, opt.bounce_rays, opt.seed);
    batches[2] = make_shadow_rays(scene, opt.shadow_rays, opt.seed);
    std::size_t total_rays = 0;
    for (const auto& b : batches)
        total_rays += b.size();

    std::vector<int> threads;
    for (int t : opt.threads) {
        const int n = t > 0 ? t : rep.max_threads;
        if (std::find(threads.begin(), threads.end(), n) == threads.end()) threads.push_back(n);
    }

    // Build everything first, then time in interleaved rounds keeping each measurement's best
    // round: other processes on a shared machine only ever slow a round down.
    std::vector<std::unique_ptr<Accel>> accels;
    for (AccelKind kind : opt.accels) {
        if (kind == AccelKind::Brute &&
            static_cast<double>(total_rays) * prims > opt.brute_max_tests) {
            rep.notes.push_back("brute skipped: too many triangle tests for a benchmark");
            continue;
        }
        AccelOptions ao;
        ao.kind = kind;
        ao.triangle = opt.triangle;
        ao.embree_robust = opt.embree_robust;
        ao.quality = opt.embree_quality;
        if (kind == AccelKind::Builtin) ao.build_threads = opt.builtin_build_threads;
        const Stopwatch timer;
        if (kind == AccelKind::Embree)
            accels.push_back(std::make_unique<EmbreeAccel>(scene, ao, isa));
        else
            accels.push_back(make_accel(scene, ao));
        BenchBuild b;
        b.accel = accels.back()->name();
        b.build_seconds = timer.seconds();
        b.mtris_per_s = b.build_seconds > 0.0 ? prims / b.build_seconds * 1e-6 : 0.0;
        b.memory_bytes = accels.back()->memory_bytes();
        b.bytes_per_prim = prims > 0.0 ? static_cast<double>(b.memory_bytes) / prims : 0.0;
        rep.builds.push_back(b);
    }

    // The ceiling: Embree called directly in a tight loop, on a scene built here from the very
    // same shared buffers, with no virtual call, optional or validity check.
    std::unique_ptr<RawEmbreeScene> raw;
    if (opt.raw_embree) {
        const Stopwatch timer;
        raw = std::make_unique<RawEmbreeScene>(scene, isa, opt.embree_robust, opt.embree_quality);
        rep.embree_config = raw->device.config();
        BenchBuild b;
        b.accel = "embree-raw";
        b.build_seconds = timer.seconds();
        b.mtris_per_s = b.build_seconds > 0.0 ? prims / b.build_seconds * 1e-6 : 0.0;
        rep.builds.push_back(b);
    }

    if (std::find(opt.accels.begin(), opt.accels.end(), AccelKind::Builtin) != opt.accels.end())
        rep.notes.push_back("builtin build with " +
                            (opt.builtin_build_threads > 0
                                 ? std::to_string(opt.builtin_build_threads)
                                 : std::string("all")) +
                            " build thread(s)");

    auto keep_best = [&](const BenchResult& r) {
        for (BenchResult& old : rep.results)
            if (old.accel == r.accel && old.kind == r.kind && old.threads == r.threads) {
                if (r.hits != old.hits)
                    throw Error(ErrorKind::Internal,
                                "bench: " + r.accel + " changed its hit count between rounds");
                if (r.mrays_per_s > old.mrays_per_s) old = r;
                return;
            }
        rep.results.push_back(r);
    };
    const double slice = opt.min_seconds / std::max(1, opt.rounds);
    for (int round = 0; round < std::max(1, opt.rounds); ++round) {
        for (int t : threads) {
            for (const auto& accel : accels) {
                const Accel& a = *accel;
                auto closest = [&a](const Ray& r) { return a.intersect(r).has_value(); };
                auto occl = [&a](const Ray& r) { return a.occluded(r); };
                keep_best(
                    time_batch(a.name(), BenchRayKind::Primary, t, batches[0], slice, closest));
                keep_best(
                    time_batch(a.name(), BenchRayKind::Bounce, t, batches[1], slice, closest));
                keep_best(time_batch(a.name(), BenchRayKind::Shadow, t, batches[2], slice, occl));
            }
            if (raw) {
                const RTCScene rs = raw->scene;
                keep_best(time_batch("embree-raw", BenchRayKind::Primary, t, batches[0], slice,
                                     RawClosest{rs}));
                keep_best(time_batch("embree-raw", BenchRayKind::Bounce, t, batches[1], slice,
                                     RawClosest{rs}));
                keep_best(time_batch("embree-raw", BenchRayKind::Shadow, t, batches[2], slice,
                                     RawOccluded{rs}));
            }
        }
    }
    return rep;
}

RawEmbreeRates time_raw_embree(const Scene& scene, const AccelOptions& accel,
                               const std::vector<Ray>& camera, const std::vector<Ray>& bounce,
                               const std::vector<Ray>& shadow, int threads, double min_seconds,
                               int rounds) {
    RawEmbreeScene raw(scene, EmbreeDevice::default_isa(), accel.embree_robust, accel.quality);
    RawEmbreeRates rates;
    rates.embree_config = raw.device.config();
    rounds = std::max(1, rounds);
    const double slice = min_seconds / rounds;
    for (int round = 0; round < rounds; ++round) {
        const BenchResult c = time_batch("embree-raw", BenchRayKind::Primary, threads, camera,
                                         slice, RawClosest{raw.scene});
        const BenchResult b = time_batch("embree-raw", BenchRayKind::Bounce, threads, bounce, slice,
                                         RawClosest{raw.scene});
        const BenchResult s = time_batch("embree-raw", BenchRayKind::Shadow, threads, shadow, slice,
                                         RawOccluded{raw.scene});
        rates.camera = std::max(rates.camera, c.mrays_per_s);
        rates.bounce = std::max(rates.bounce, b.mrays_per_s);
        rates.shadow = std::max(rates.shadow, s.mrays_per_s);
        rates.camera_cpu = std::max(rates.camera_cpu, c.mrays_per_cpu_s);
        rates.bounce_cpu = std::max(rates.bounce_cpu, b.mrays_per_cpu_s);
        rates.shadow_cpu = std::max(rates.shadow_cpu, s.mrays_per_cpu_s);
    }
    return rates;
}

} // namespace candela
