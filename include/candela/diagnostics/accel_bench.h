#pragma once
// Accelerator throughput: rays per second per backend x ray kind x thread count, build time,
// memory, and raw Embree calls on the same rays as the ceiling candela's Embree path can reach.
#include "candela/accel/accel.h"
#include "candela/render/progress.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// A figure measured several times: its median and its range over the repeats. A bench reports
/// the median, which one slow or lucky round does not move, and the range, which says how far
/// the rounds disagreed (on a shared machine, by far the larger uncertainty).
struct Spread {
    double median = 0.0, min = 0.0, max = 0.0;
    int repeats = 0; ///< 0: not measured
    /// The spread of `values` (not measured when empty).
    static Spread of(std::vector<double> values);
    bool measured() const { return repeats > 0; }
    /// "12.34 (11.90-12.80)" with `decimals` decimals: the median, then the range of the
    /// repeats ("12.34 (1 round)" for one); "n/a" when not measured.
    std::string text(int decimals) const;
};

/// The one-minute load average of the machine, when the system reports it.
std::optional<double> one_minute_load();

/// A warning when the one-minute load average exceeds the cores (other processes then take
/// time from the bench's threads: its figures are low and spread); empty otherwise.
std::string load_warning(double load, int cores);

/// Where the bench's progress goes: a bar or lines on stderr when --progress asks for one;
/// "auto" is a bar when stderr is a terminal and nothing otherwise (bench's stdout is its
/// report, so JSON progress is not offered).
ProgressMode resolve_bench_progress(ProgressMode requested, bool quiet);

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
    /// rounds are interleaved across backends and the median round is reported with the range.
    double min_seconds = 0.5;
    int rounds = 5;
    /// Builds per backend: each build figure is the median of these (the last build is traced).
    int build_rounds = 3;
    ProgressMode progress = ProgressMode::None; ///< resolved (resolve_bench_progress)
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
    /// Of one round by time_batch; in a BenchReport, the median over the rounds, whose spread
    /// is `mrays`.
    double mrays_per_s = 0.0;
    Spread mrays;
    /// Processor time of the whole process over the timed loop (all threads), and rays per
    /// processor-second: on a shared machine, time other processes took from this one's cores
    /// does not count, so these drift far less than the wall-clock figures.
    double cpu_seconds = 0.0;
    double mrays_per_cpu_s = 0.0;
};

/// Build cost and memory of one backend.
struct BenchBuild {
    std::string accel;
    double build_seconds = 0.0; ///< median over the builds
    Spread seconds;             ///< the build time's spread over the builds
    double mtris_per_s = 0.0;   ///< primitives (triangles + spheres) per second, in millions
    std::size_t memory_bytes = 0;
    double bytes_per_prim = 0.0;
    bool memory_measured = true; ///< false for the raw Embree scene, whose memory is not asked
};

struct BenchReport {
    std::string scene;
    std::size_t triangles = 0, spheres = 0;
    int max_threads = 1;
    std::string embree_config;
    std::vector<BenchBuild> builds;
    std::vector<BenchResult> results;
    std::vector<std::string> notes;

    /// Mrays/s of a measurement (the median of its rounds), or 0 when it was not run.
    double mrays(const std::string& accel, BenchRayKind kind, int threads) const;
    /// mrays(a) / mrays(b), or 0 when either is missing.
    double ratio(const std::string& a, const std::string& b, BenchRayKind kind, int threads) const;
    std::string to_text() const; ///< tables plus the embree/raw and builtin/embree ratios
    std::string to_json() const;
};

/// Raw Embree throughput (Mrays/s) on given rays: rtcIntersect1 on `camera` and `bounce`,
/// rtcOccluded1 on `shadow`, in tight loops over a scene built from `scene`'s own buffers with
/// no candela code between the calls. The ceiling a renderer's traversal could reach on rays of
/// these kinds. Each round times each kind for at least min_seconds / rounds.
struct RawEmbreeRates {
    Spread camera, bounce, shadow;                               ///< per wall second
    double camera_cpu = 0.0, bounce_cpu = 0.0, shadow_cpu = 0.0; ///< per processor second
    std::string embree_config;
};
/// Each figure is the median of `rounds` rounds (its spread in the Spread); `progress`, when
/// given, counts one per timed loop.
RawEmbreeRates time_raw_embree(const Scene& scene, const AccelOptions& accel,
                               const std::vector<Ray>& camera, const std::vector<Ray>& bounce,
                               const std::vector<Ray>& shadow, int threads, double min_seconds,
                               int rounds, Progress* progress = nullptr);

/// Processor time (user + system, all threads) the process has used so far, in seconds.
double process_cpu_seconds();

/// Runs the benchmark. Ray batches are generated before any timed loop; hit counts of every
/// backend are reported so that a broken backend cannot post a fast time unnoticed.
BenchReport run_bench(const Scene& scene, const BenchOptions& opt);

} // namespace candela
