// Accelerator throughput: rays per second per backend, ray kind and thread count (accel_bench.h).
#include "candela/diagnostics/accel_bench.h"

#include "candela/accel/raw_embree.h"
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
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace candela {

namespace {

/// Rays per parallel task: large enough that scheduling is negligible next to traversal.
constexpr std::size_t kBenchGrain = 512;

/// One pass over `rays` with `threads` threads, calling f(first, count) -> how many of the
/// rays [first, first + count) answer true (hit, or occluded); returns the total.
template <typename F>
std::uint64_t run_pass(tbb::task_arena* arena, const std::vector<Ray>& rays, const F& f) {
    if (!arena) return f(rays.data(), rays.size());
    std::uint64_t n = 0;
    arena->execute([&] {
        n = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, rays.size(), kBenchGrain), std::uint64_t(0),
            [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t acc) {
                return acc + f(rays.data() + r.begin(), r.size());
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

/// Closest-hit queries of an accelerator, one virtual call per ray as a render's scalar paths
/// make them: how many of rays [first, first + n) hit.
struct AccelClosest {
    const Accel& accel;
    std::uint64_t operator()(const Ray* rays, std::size_t n) const {
        std::uint64_t hits = 0;
        for (std::size_t i = 0; i < n; ++i)
            hits += accel.intersect(rays[i]).has_value() ? 1 : 0;
        return hits;
    }
};

/// Occlusion queries of an accelerator, one virtual call per ray.
struct AccelOccluded {
    const Accel& accel;
    std::uint64_t operator()(const Ray* rays, std::size_t n) const {
        std::uint64_t hits = 0;
        for (std::size_t i = 0; i < n; ++i)
            hits += accel.occluded(rays[i]) ? 1 : 0;
        return hits;
    }
};

/// Embree called directly in a tight loop (RawEmbree), closest hits.
struct RawClosest {
    const RawEmbree& raw;
    std::uint64_t operator()(const Ray* rays, std::size_t n) const {
        return raw.count_hits(rays, n);
    }
};

/// Embree called directly in a tight loop, occlusion.
struct RawOccluded {
    const RawEmbree& raw;
    std::uint64_t operator()(const Ray* rays, std::size_t n) const {
        return raw.count_occluded(rays, n);
    }
};

} // namespace

Spread Spread::of(std::vector<double> values) {
    Spread s;
    if (values.empty()) return s;
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    s.min = values.front();
    s.max = values.back();
    s.repeats = int(n);
    return s;
}

std::string Spread::text(int decimals) const {
    if (!measured()) return "n/a";
    if (repeats == 1) return fmt::format("{:.{}f} (1 round)", median, decimals);
    return fmt::format("{:.{}f} ({:.{}f}-{:.{}f})", median, decimals, min, decimals, max, decimals);
}

std::optional<double> one_minute_load() {
    double load[1] = {0.0};
    if (::getloadavg(load, 1) != 1) return std::nullopt;
    return load[0];
}

std::string load_warning(double load, int cores) {
    if (!(load > double(cores))) return "";
    return fmt::format("the one-minute load average is {:.2f} on {} cores: other processes take "
                       "time from the bench's threads, so its figures are low and spread; run "
                       "it on an idle machine for figures to compare",
                       load, cores);
}

ProgressMode resolve_bench_progress(ProgressMode requested, bool quiet) {
    if (requested == ProgressMode::Json)
        throw Error(ErrorKind::Usage,
                    "bench: --progress json is not offered (stdout holds the report); use bar "
                    "or lines, which go to stderr");
    if (requested == ProgressMode::Auto)
        return !quiet && ::isatty(2) != 0 ? ProgressMode::Bar : ProgressMode::None;
    return quiet ? ProgressMode::None : requested;
}

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
    // Each figure is the median of its repeats, then their range; n/a: not measured.
    os << "\nbuild      seconds (range)                Mprims/s      memory   bytes/prim\n";
    for (const BenchBuild& b : builds)
        os << fmt::format("{:<10} {:<30} {:>8} {:>11} {:>12}\n", b.accel, b.seconds.text(4),
                          b.mtris_per_s > 0.0 ? fmt::format("{:.2f}", b.mtris_per_s) : "n/a",
                          b.memory_measured ? std::to_string(b.memory_bytes) : "n/a",
                          b.memory_measured && b.bytes_per_prim > 0.0
                              ? fmt::format("{:.1f}", b.bytes_per_prim)
                              : "n/a");
    os << "\naccel       kind     threads  Mrays/s (range)                    hits\n";
    for (const BenchResult& r : results)
        os << fmt::format("{:<11} {:<8} {:>7}  {:<30} {:>10}\n", r.accel,
                          bench_ray_kind_name(r.kind), r.threads, r.mrays.text(3),
                          r.mrays.measured() ? std::to_string(r.hits) : "n/a");
    os << "\nratios of the medians at 1 thread:\n";
    for (int k = 0; k < static_cast<int>(BenchRayKind::Count); ++k) {
        const auto kind = static_cast<BenchRayKind>(k);
        const double er = ratio("embree", "embree-raw", kind, 1);
        const double be = ratio("builtin", "embree", kind, 1);
        os << "  " << bench_ray_kind_name(kind) << ": embree/raw "
           << (er > 0 ? fmt::format("{:.3f}", er) : "n/a") << ", builtin/embree "
           << (be > 0 ? fmt::format("{:.3f}", be) : "n/a") << "\n";
    }
    return os.str();
}

std::string BenchReport::to_json() const {
    using Json = nlohmann::ordered_json;
    // What was not measured is null, not 0.
    auto measured = [](bool yes, const Json& v) { return yes ? v : Json(nullptr); };
    Json build_list = Json::array();
    for (const BenchBuild& b : builds)
        build_list.push_back(
            {{"accel", b.accel},
             {"build_seconds", b.build_seconds},
             {"build_seconds_min", b.seconds.min},
             {"build_seconds_max", b.seconds.max},
             {"builds", b.seconds.repeats},
             {"mprims_per_s", measured(b.mtris_per_s > 0.0, b.mtris_per_s)},
             {"memory_bytes", measured(b.memory_measured, b.memory_bytes)},
             {"bytes_per_prim",
              measured(b.memory_measured && b.bytes_per_prim > 0.0, b.bytes_per_prim)}});
    Json result_list = Json::array();
    for (const BenchResult& r : results)
        result_list.push_back({{"accel", r.accel},
                               {"kind", bench_ray_kind_name(r.kind)},
                               {"threads", r.threads},
                               {"rays", r.rays},
                               {"hits", measured(r.mrays.measured(), r.hits)},
                               {"seconds", r.seconds},
                               {"mrays_per_s", measured(r.mrays.measured(), r.mrays.median)},
                               {"mrays_per_s_min", measured(r.mrays.measured(), r.mrays.min)},
                               {"mrays_per_s_max", measured(r.mrays.measured(), r.mrays.max)},
                               {"rounds", r.mrays.repeats}});
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
    const std::string isa = opt.embree_isa == "default" ? embree_default_isa() : opt.embree_isa;
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

    // Which backends are timed: brute only where its tests are affordable.
    std::vector<AccelKind> kinds;
    for (AccelKind kind : opt.accels) {
        if (kind == AccelKind::Brute &&
            static_cast<double>(total_rays) * prims > opt.brute_max_tests) {
            rep.notes.push_back("brute skipped: too many triangle tests for a benchmark");
            continue;
        }
        kinds.push_back(kind);
    }
    const int build_rounds = std::max(1, opt.build_rounds);
    const int rounds = std::max(1, opt.rounds);
    const std::size_t traced = kinds.size() + (opt.raw_embree ? 1 : 0);
    // One step per build and per timed loop.
    Progress progress(traced * std::size_t(build_rounds) + std::size_t(rounds) * threads.size() *
                                                               traced *
                                                               std::size_t(BenchRayKind::Count),
                      opt.progress);

    // Build everything first (each backend build_rounds times, the last build kept), then time
    // in interleaved rounds: a slow spell of a shared machine falls on every backend alike.
    std::vector<std::unique_ptr<Accel>> accels;
    auto build_figure = [&](const std::string& name, const std::vector<double>& seconds) {
        BenchBuild b;
        b.accel = name;
        b.seconds = Spread::of(seconds);
        b.build_seconds = b.seconds.median;
        b.mtris_per_s = b.build_seconds > 0.0 ? prims / b.build_seconds * 1e-6 : 0.0;
        return b;
    };
    for (AccelKind kind : kinds) {
        AccelOptions ao;
        ao.kind = kind;
        ao.triangle = opt.triangle;
        ao.embree_robust = opt.embree_robust;
        ao.quality = opt.embree_quality;
        ao.embree_isa = isa;
        if (kind == AccelKind::Builtin) ao.build_threads = opt.builtin_build_threads;
        std::vector<double> seconds;
        std::unique_ptr<Accel> accel;
        for (int round = 0; round < build_rounds; ++round) {
            accel.reset(); // one structure in memory at a time
            const Stopwatch timer;
            accel = make_accel(scene, ao);
            seconds.push_back(timer.seconds());
            progress.add(1);
        }
        BenchBuild b = build_figure(accel->name(), seconds);
        b.memory_bytes = accel->memory_bytes();
        b.bytes_per_prim = prims > 0.0 ? static_cast<double>(b.memory_bytes) / prims : 0.0;
        rep.builds.push_back(b);
        accels.push_back(std::move(accel));
    }

    // The ceiling: Embree called directly in a tight loop, on a scene built here from the very
    // same shared buffers, with no virtual call, optional or validity check.
    std::unique_ptr<RawEmbree> raw;
    if (opt.raw_embree) {
        std::vector<double> seconds;
        for (int round = 0; round < build_rounds; ++round) {
            raw.reset();
            const Stopwatch timer;
            raw = std::make_unique<RawEmbree>(scene, isa, opt.embree_robust, opt.embree_quality);
            seconds.push_back(timer.seconds());
            progress.add(1);
        }
        rep.embree_config = raw->config();
        BenchBuild b = build_figure("embree-raw", seconds);
        b.memory_measured = false; // Embree is not asked for the raw scene's memory
        rep.builds.push_back(b);
    }

    if (std::find(kinds.begin(), kinds.end(), AccelKind::Builtin) != kinds.end())
        rep.notes.push_back("builtin build with " +
                            (opt.builtin_build_threads > 0
                                 ? std::to_string(opt.builtin_build_threads)
                                 : std::string("all")) +
                            " build thread(s)");

    // Every round's rate of each measurement; the report gives their median and range.
    std::vector<std::vector<double>> wall_rates, cpu_rates;
    auto record = [&](const BenchResult& r) {
        progress.add(1);
        std::size_t i = 0;
        for (; i < rep.results.size(); ++i) {
            const BenchResult& old = rep.results[i];
            if (old.accel == r.accel && old.kind == r.kind && old.threads == r.threads) break;
        }
        if (i == rep.results.size()) {
            rep.results.push_back(r);
            wall_rates.emplace_back();
            cpu_rates.emplace_back();
        } else if (r.hits != rep.results[i].hits) {
            throw Error(ErrorKind::Internal,
                        "bench: " + r.accel + " changed its hit count between rounds");
        }
        if (r.rays == 0) return; // an empty batch: nothing measured
        wall_rates[i].push_back(r.mrays_per_s);
        cpu_rates[i].push_back(r.mrays_per_cpu_s);
    };
    const double slice = opt.min_seconds / rounds;
    for (int round = 0; round < rounds; ++round) {
        for (int t : threads) {
            for (const auto& accel : accels) {
                const Accel& a = *accel;
                const AccelClosest closest{a};
                const AccelOccluded occl{a};
                record(time_batch(a.name(), BenchRayKind::Primary, t, batches[0], slice, closest));
                record(time_batch(a.name(), BenchRayKind::Bounce, t, batches[1], slice, closest));
                record(time_batch(a.name(), BenchRayKind::Shadow, t, batches[2], slice, occl));
            }
            if (raw) {
                record(time_batch("embree-raw", BenchRayKind::Primary, t, batches[0], slice,
                                  RawClosest{*raw}));
                record(time_batch("embree-raw", BenchRayKind::Bounce, t, batches[1], slice,
                                  RawClosest{*raw}));
                record(time_batch("embree-raw", BenchRayKind::Shadow, t, batches[2], slice,
                                  RawOccluded{*raw}));
            }
        }
    }
    for (std::size_t i = 0; i < rep.results.size(); ++i) {
        BenchResult& r = rep.results[i];
        r.mrays = Spread::of(wall_rates[i]);
        r.mrays_per_s = r.mrays.median;
        r.mrays_per_cpu_s = Spread::of(cpu_rates[i]).median;
    }
    progress.finish();
    return rep;
}

RawEmbreeRates time_raw_embree(const Scene& scene, const AccelOptions& accel,
                               const std::vector<Ray>& camera, const std::vector<Ray>& bounce,
                               const std::vector<Ray>& shadow, int threads, double min_seconds,
                               int rounds, Progress* progress) {
    const RawEmbree raw(scene, accel.embree_isa, accel.embree_robust, accel.quality);
    RawEmbreeRates rates;
    rates.embree_config = raw.config();
    rounds = std::max(1, rounds);
    const double slice = min_seconds / rounds;
    // Per kind: the rounds' rates per wall second and per processor second (an empty batch
    // measures nothing).
    std::vector<double> wall[3], cpu[3];
    auto keep = [&](int k, const BenchResult& r) {
        if (progress) progress->add(1);
        if (r.rays == 0) return;
        wall[k].push_back(r.mrays_per_s);
        cpu[k].push_back(r.mrays_per_cpu_s);
    };
    for (int round = 0; round < rounds; ++round) {
        keep(0, time_batch("embree-raw", BenchRayKind::Primary, threads, camera, slice,
                           RawClosest{raw}));
        keep(1, time_batch("embree-raw", BenchRayKind::Bounce, threads, bounce, slice,
                           RawClosest{raw}));
        keep(2, time_batch("embree-raw", BenchRayKind::Shadow, threads, shadow, slice,
                           RawOccluded{raw}));
    }
    rates.camera = Spread::of(wall[0]);
    rates.bounce = Spread::of(wall[1]);
    rates.shadow = Spread::of(wall[2]);
    rates.camera_cpu = Spread::of(cpu[0]).median;
    rates.bounce_cpu = Spread::of(cpu[1]).median;
    rates.shadow_cpu = Spread::of(cpu[2]).median;
    return rates;
}

} // namespace candela
