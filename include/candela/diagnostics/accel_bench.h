#pragma once
// Accelerator throughput: rays per second per backend x ray kind x thread count, build time,
// memory, and raw Embree calls on the same rays as the ceiling candela's Embree path can reach.
#include "candela/accel/accel.h"

#include <cstdint>
#include <string>
#include <vector>

namespace candela {

enum class BenchRayKind { Primary = 0, Bounce, Shadow, Count };
const char* bench_ray_kind_name(BenchRayKind k);

struct BenchOptions {
    /// Backends to time; brute is skipped (with a note) when triangles x rays is unaffordable.
    std::vector<AccelKind> accels = {AccelKind::Embree, AccelKind::Builtin};
    TriangleTest triangle = TriangleTest::MollerTrumbore; ///< builtin and brute
    bool embree_robust = false;
    AccelOptions::Quality embree_quality = AccelOptions::Quality::Medium;
    /// Embree ISA ("" = Embree's own choice, "default" = candela's EmbreeDevice::default_isa()).
    std::string embree_isa = "default";
    int primary_width = 512; ///< primary rays: pixel centres of the scene camera
    int primary_height = 512;
    std::size_t bounce_rays = 1u << 20; ///< incoherent closest-hit rays (make_bounce_rays)
    std::size_t shadow_rays = 1u << 20; ///< occlusion rays (make_shadow_rays)
    /// Thread counts to time; 0 means all available.
    std::vector<int> threads = {1, 0};
    std::uint64_t seed = 1;
    /// Each measurement repeats its batch for at least min_seconds / rounds per round; the
    /// rounds are interleaved across backends and the best round is reported.
    double min_seconds = 0.5;
    int rounds = 5;
    bool raw_embree = true; ///< also time direct rtcIntersect1 / rtcOccluded1 loops
    double brute_max_tests = 2e9;
    /// Build threads of the builtin BVH (its build figure is meant single-threaded; 0 = all).
    int builtin_build_threads = 1;
};

/// One timed measurement.
struct BenchResult {
    std::string accel; ///< backend name, or "embree-raw"
    BenchRayKind kind = BenchRayKind::Primary;
    int threads = 1;
    std::uint64_t rays = 0; ///< rays traced in the timed loop (batch x repeats)
    std::uint64_t hits = 0; ///< hits (or occluded rays) in one pass of the batch
    double seconds = 0.0;
    double mrays_per_s = 0.0;
    /// Processor time of the whole process over the timed loop (all threads), and rays per
    /// processor-second: on a shared machine, time other processes took from this one's cores
    /// does not count, so these drift far less than the wall-clock figures.
    double cpu_seconds = 0.0;
    double mrays_per_cpu_s = 0.0;
};

/// Build cost and memory of one backend.
struct BenchBuild {
    std::string accel;
    double build_seconds = 0.0;
    double mtris_per_s = 0.0; ///< primitives (triangles + spheres) per second, in millions
    std::size_t memory_bytes = 0;
    double bytes_per_prim = 0.0;
};

struct BenchReport {
    std::string scene;
    std::size_t triangles = 0, spheres = 0;
    int max_threads = 1;
    std::string embree_config;
    std::vector<BenchBuild> builds;
    std::vector<BenchResult> results;
    std::vector<std::string> notes;

    /// Mrays/s of a measurement, or 0 when it was not run.
    double mrays(const std::string& accel, BenchRayKind kind, int threads) const;
    /// mrays(a) / mrays(b), or 0 when either is missing.
    double ratio(const std::string& a, const std::string& b, BenchRayKind kind, int threads) const;
    std::string to_text() const; ///< tables plus the embree/raw and builtin/embree ratios
    std::string to_json() const;
};

/// Raw Embree throughput (Mrays/s) on given rays: rtcIntersect1 on `camera` and `bounce`,
/// rtcOccluded1 on `shadow`, in tight loops over a scene built from `scene`'s own buffers with
/// no candela code between the calls. The ceiling a renderer's traversal could reach on rays of
/// these kinds. Each figure is the best of `rounds` rounds of at least min_seconds / rounds.
struct RawEmbreeRates {
    double camera = 0.0, bounce = 0.0, shadow = 0.0;             ///< per wall second
    double camera_cpu = 0.0, bounce_cpu = 0.0, shadow_cpu = 0.0; ///< per processor second
    std::string embree_config;
};
RawEmbreeRates time_raw_embree(const Scene& scene, const AccelOptions& accel,
                               const std::vector<Ray>& camera, const std::vector<Ray>& bounce,
                               const std::vector<Ray>& shadow, int threads, double min_seconds,
                               int rounds);

/// Processor time (user + system, all threads) the process has used so far, in seconds.
double process_cpu_seconds();

/// Runs the benchmark. Ray batches are generated before any timed loop; hit counts of every
/// backend are reported so that a broken backend cannot post a fast time unnoticed.
BenchReport run_bench(const Scene& scene, const BenchOptions& opt);

} // namespace candela
