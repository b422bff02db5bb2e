// Bounds what any per-pixel sample allocation can gain on a scene.
//
// An adaptive sampler of the relative kind only decides how many samples each pixel gets. Its
// best possible gain is therefore set by the scene: by how unevenly the per-pixel errors and the
// per-sample costs are spread. This tool measures both from uniform renders and prints the cost
// each allocation n_p = clamp(lambda w_p, floor, cap) needs to reach the relMSE that the uniform
// render has at --spp, relative to that uniform render's cost.
//
//   adaptive_bound [scene] [-r W H] [--spp N] [--seeds K] [--ref-spp N] [-m depth] [-t threads]
//                  [--sampler independent|sobol|both]
//
// Model and measurements:
//   - The per-pixel error at n samples is E_p(n) = E_p(spp) spp / n, the rate of an independent
//     estimator. The tool prints the image's measured slope between spp / 4 and spp as a check
//     of that model (it also holds on average for the Sobol points on the CS184 scenes).
//   - E_p(spp) is each pixel's squared error against a reference, weighted as relMSE, averaged
//     over K seeds, less the reference's own variance. Two independent sets of K seeds are
//     rendered: allocations are built from set A and all errors are evaluated on set B, so an
//     allocation cannot profit from the noise of the errors it is judged by. The exception is
//     the oracle, which is built from set B itself and is therefore optimistic: no allocation
//     from the render's own samples can beat it.
//   - c_p is the cost of one sample of pixel p in the renderer's cost units (cost_units() in
//     renderer.h, calibrated against time), taken from the reference render.
//   - floor is the relative sampler's first batch (32 samples); cap is its 8 x spp limit.
//   - One line judges the counts the relative sampler itself chose in a render (scaled to the
//     target), so its practical allocation can be compared with the bounds in the same units.
//
// Prints, per sampler, one line per allocation with its cost ratio (< 1: cheaper than uniform).
#include "candela/accel/accel.h"
#include "candela/diagnostics/converge.h"
#include "candela/io/collada.h"
#include "candela/render/adaptive.h"
#include "candela/render/film.h"
#include "candela/render/renderer.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <string>
#include <vector>

namespace {

using namespace candela;

/// The relative sampler's first batch: no pixel gets fewer samples (converge's configuration).
constexpr double kFloorSamples = 32.0;
/// The relative sampler lets one pixel take at most this many times spp (renderer.cpp).
constexpr double kCapFactor = 8.0;
/// Seed of the reference render, apart from the seeds of the measured renders (1 .. 2K).
constexpr std::uint64_t kReferenceSeed = 1u << 20;

struct Options {
    std::string scene = "../shared/scenes/cs184/CBbunny.dae";
    int width = 64, height = 48;
    int spp = 1024, seeds = 8, ref_spp = 32768, max_depth = 8, threads = 0;
    std::vector<SamplerKind> samplers = {SamplerKind::Independent, SamplerKind::Sobol};
};

/// A uniform render's per-pixel means, per-sample variances and (when traced with costs) cost
/// per sample, row-major, three channels per pixel.
struct PixelData {
    std::vector<double> mean, sample_var, cost;
};

/// Renders `spp` samples in every pixel. The renderer records per-pixel costs only for the
/// relative sampler, so the render runs as a relative render whose first batch is the whole
/// budget: that batch is a uniform render, and the budget is spent when it ends.
PixelData render_uniform(const Scene& scene, const Accel& accel, RenderSettings s, int spp,
                         SamplerKind sampler, std::uint64_t seed) {
    s.spp = spp;
    s.sampler = sampler;
    s.seed = seed;
    use_relative_sampler(s, spp, 0.f);
    Renderer renderer(scene, accel, s);
    RenderState st = renderer.start();
    RenderStats stats;
    renderer.run(st, stats);
    const Film& f = st.film;
    PixelData d;
    const std::size_t n_pixels = f.pixel_count();
    d.mean.resize(3 * n_pixels);
    d.sample_var.resize(3 * n_pixels);
    d.cost.resize(n_pixels);
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const std::size_t i = std::size_t(y) * s.width + x;
            const double n = f.count(x, y);
            if (n + f.dropped(x, y) != spp || n < 2)
                throw Error(ErrorKind::Internal, "adaptive_bound: pixel (" + std::to_string(x) +
                                                     ", " + std::to_string(y) + ") took " +
                                                     std::to_string(int(n)) +
                                                     " finite samples of " + std::to_string(spp));
            const Rgb m = f.mean(x, y), v = f.variance_of_mean(x, y);
            for (int c = 0; c < 3; ++c) {
                d.mean[3 * i + c] = m[c];
                d.sample_var[3 * i + c] = double(v[c]) * n;
            }
            d.cost[i] = double(st.cost[i]) / n;
        }
    return d;
}

/// Per-pixel errors of K renders in relMSE units (averaged over the channels): `error` is the
/// squared error against the reference less the reference's own variance, `sample_var` the
/// relative variance of one sample. Both are means over the K seeds.
struct ErrorMaps {
    std::vector<double> error, sample_var;
};

ErrorMaps measure(const Scene& scene, const Accel& accel, const RenderSettings& base, int spp,
                  SamplerKind sampler, std::uint64_t first_seed, int seeds, const PixelData& ref,
                  int ref_spp) {
    const std::size_t n_pixels = ref.cost.size();
    ErrorMaps m{std::vector<double>(n_pixels, 0.0), std::vector<double>(n_pixels, 0.0)};
    for (int k = 0; k < seeds; ++k) {
        const PixelData img = render_uniform(scene, accel, base, spp, sampler, first_seed + k);
        for (std::size_t j = 0; j < 3 * n_pixels; ++j) {
            const double weight = 1.0 / (ref.mean[j] * ref.mean[j] + kRelMseEps);
            const double diff = img.mean[j] - ref.mean[j];
            const double ref_var = ref.sample_var[j] / ref_spp;
            m.error[j / 3] += (diff * diff - ref_var) * weight / (3.0 * seeds);
            m.sample_var[j / 3] += img.sample_var[j] * weight / (3.0 * seeds);
        }
    }
    return m;
}

/// Mean of `v` over each pixel's (2 radius + 1)^2 neighbourhood, clipped at the frame.
std::vector<double> box_mean(const std::vector<double>& v, int w, int h, int radius) {
    return window_mean(v, std::vector<std::uint8_t>(v.size(), 1), w, h, radius,
                       WindowCentre::Include);
}

/// Evaluates allocations n_p = clamp(lambda w_p, floor, cap) against per-pixel errors measured
/// at `spp` samples, under the 1 / n model.
class AllocationBound {
  public:
    AllocationBound(std::vector<double> error_at_spp, std::vector<double> cost, int spp)
        : error_(std::move(error_at_spp)), cost_(std::move(cost)), spp_(spp) {
        for (double& e : error_)
            e = std::max(e, 0.0); // below the reference's noise: no error
        for (double e : error_)
            target_ += e;
        target_ /= double(error_.size());
        for (double c : cost_)
            uniform_cost_ += c * spp_;
    }

    /// The relMSE that the uniform render reaches at spp (the target of every allocation).
    double target() const { return target_; }

    /// Cost of the allocation with weights `w` that reaches the target, over uniform's cost.
    double cost_ratio(const std::vector<double>& w) const {
        const double cap = kCapFactor * spp_;
        auto counts = [&](double lambda, std::size_t i) {
            return std::clamp(lambda * w[i], kFloorSamples, cap);
        };
        auto error = [&](double lambda) {
            double sum = 0.0;
            for (std::size_t i = 0; i < error_.size(); ++i)
                sum += error_[i] * spp_ / counts(lambda, i);
            return sum / double(error_.size());
        };
        // error(lambda) falls monotonically in lambda: bisect in log space.
        double lo = 1e-12, hi = 1e12;
        if (error(hi) > target_) return INFINITY; // even every pixel at the cap is not enough
        for (int it = 0; it < 200; ++it) {
            const double mid = std::sqrt(lo * hi);
            (error(mid) > target_ ? lo : hi) = mid;
        }
        double cost = 0.0;
        for (std::size_t i = 0; i < error_.size(); ++i)
            cost += cost_[i] * counts(hi, i);
        return cost / uniform_cost_;
    }

    /// The weights of the optimum for per-pixel errors e (errors at spp): minimising
    /// sum_p e_p / n_p subject to sum_p c_p n_p = C gives n_p proportional to sqrt(e_p / c_p).
    std::vector<double> optimal_weights(const std::vector<double>& e) const {
        std::vector<double> w(e.size());
        for (std::size_t i = 0; i < e.size(); ++i)
            w[i] = std::sqrt(std::max(e[i], 0.0) / cost_[i]);
        return w;
    }

    const std::vector<double>& errors() const { return error_; }

  private:
    std::vector<double> error_, cost_;
    int spp_;
    double target_ = 0.0, uniform_cost_ = 0.0;
};

double mean_of(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v)
        s += x;
    return s / double(v.size());
}

int parse_int(int argc, char** argv, int& i, const char* flag) {
    if (i + 1 >= argc) throw Error(ErrorKind::Usage, std::string(flag) + " needs a value");
    char* end = nullptr;
    const long v = std::strtol(argv[++i], &end, 10);
    if (*end != '\0' || v <= 0 || v > (1 << 24))
        throw Error(ErrorKind::Usage,
                    std::string(flag) + ": '" + argv[i] + "' is not a positive integer");
    return int(v);
}

Options parse(int argc, char** argv) {
    Options o;
    bool scene_given = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") {
            fmt::print("usage: adaptive_bound [scene] [-r W H] [--spp N] [--seeds K] "
                       "[--ref-spp N] [-m depth] [-t threads] [--sampler "
                       "independent|sobol|both]\n"
                       "Prints the cost, relative to a uniform render, that per-pixel sample "
                       "allocations need to reach the uniform render's relMSE at --spp "
                       "(default 1024). Defaults: CBbunny, 64x48, 8 seeds per set, reference "
                       "32768 spp, depth 8, both samplers.\n");
            std::exit(0);
        } else if (a == "-r") {
            o.width = parse_int(argc, argv, i, "-r");
            o.height = parse_int(argc, argv, i, "-r");
        } else if (a == "--spp") {
            o.spp = parse_int(argc, argv, i, "--spp");
        } else if (a == "--seeds") {
            o.seeds = parse_int(argc, argv, i, "--seeds");
        } else if (a == "--ref-spp") {
            o.ref_spp = parse_int(argc, argv, i, "--ref-spp");
        } else if (a == "-m") {
            o.max_depth = parse_int(argc, argv, i, "-m");
        } else if (a == "-t") {
            o.threads = parse_int(argc, argv, i, "-t");
        } else if (a == "--sampler") {
            if (i + 1 >= argc) throw Error(ErrorKind::Usage, "--sampler needs a value");
            const std::string v = argv[++i];
            if (const std::optional<SamplerKind> k = find_enum(kSamplerKinds, v))
                o.samplers = {*k};
            else if (v != "both")
                throw Error(ErrorKind::Usage,
                            "--sampler: '" + v + "' (expected independent, sobol or both)");
        } else if (!scene_given && !a.empty() && a[0] != '-') {
            o.scene = a;
            scene_given = true;
        } else {
            throw Error(ErrorKind::Usage, "unknown argument '" + a + "' (see --help)");
        }
    }
    if (o.spp < 4 * int(kFloorSamples))
        throw Error(ErrorKind::Usage, "--spp must be at least " +
                                          std::to_string(4 * int(kFloorSamples)) +
                                          " (the slope check renders spp / 4)");
    return o;
}

/// The per-pixel sample counts (finite or dropped) of one render by the relative sampler, with
/// the settings `candela converge` uses for it. Scaled, they are one more allocation to judge.
std::vector<double> relative_sampler_counts(const Scene& scene, const Accel& accel,
                                            const RenderSettings& base, int spp,
                                            SamplerKind sampler) {
    RenderSettings s = make_converge_config("relative", base).settings;
    s.spp = spp;
    s.sampler = sampler;
    s.seed = 1;
    Renderer renderer(scene, accel, s);
    RenderStats stats;
    const Film f = renderer.render(stats);
    std::vector<double> counts(f.pixel_count());
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x)
            counts[std::size_t(y) * s.width + x] = double(f.count(x, y)) + f.dropped(x, y);
    return counts;
}

void report(const Scene& scene, const Accel& accel, const RenderSettings& base, const Options& o,
            const PixelData& ref, SamplerKind sampler) {
    const char* name = enum_name(kSamplerKinds, sampler);
    const std::uint64_t set_a = 1, set_b = 1 + std::uint64_t(o.seeds);
    const ErrorMaps a = measure(scene, accel, base, o.spp, sampler, set_a, o.seeds, ref, o.ref_spp);
    const ErrorMaps b = measure(scene, accel, base, o.spp, sampler, set_b, o.seeds, ref, o.ref_spp);
    const ErrorMaps b4 =
        measure(scene, accel, base, o.spp / 4, sampler, set_b, o.seeds, ref, o.ref_spp);

    const double err_b = mean_of(b.error), err_b4 = mean_of(b4.error);
    fmt::print("\n{} sampler: uniform relMSE at {} spp {:.4g} (set A {:.4g}), at {} spp {:.4g}: "
               "slope {:.3f}; the per-sample variance predicts {:.4g}\n",
               name, o.spp, err_b, mean_of(a.error), o.spp / 4, err_b4,
               std::log(err_b / err_b4) / std::log(4.0), mean_of(b.sample_var) / o.spp);

    const AllocationBound bound(b.error, ref.cost, o.spp);
    auto line = [&](const std::string& label, const std::vector<double>& w) {
        const double ratio = bound.cost_ratio(w);
        if (std::isfinite(ratio))
            fmt::print("  {:<58} {:.3f}\n", label, ratio);
        else // pixels the weights leave at the floor have more error than the target allows
            fmt::print("  {:<58} unreachable within the floor and cap\n", label);
    };
    line("uniform (check: 1)", std::vector<double>(b.error.size(), 1.0));
    line("oracle: optimum for set B's own errors (optimistic)", bound.optimal_weights(b.error));
    line("the relative sampler's own counts (" + std::string(name) + ", seed 1)",
         relative_sampler_counts(scene, accel, base, o.spp, sampler));
    std::vector<double> cost_blind = box_mean(a.sample_var, o.width, o.height, 2);
    for (double& w : cost_blind)
        w = std::sqrt(std::max(w, 0.0));
    line("from set A's per-sample variances, 5x5, cost ignored", cost_blind);
    for (int radius = 0; radius <= 2; ++radius) {
        const std::string win =
            std::to_string(2 * radius + 1) + "x" + std::to_string(2 * radius + 1);
        line("from set A's errors, averaged over " + win,
             bound.optimal_weights(box_mean(a.error, o.width, o.height, radius)));
        line("from set A's per-sample variances, averaged over " + win,
             bound.optimal_weights(box_mean(a.sample_var, o.width, o.height, radius)));
    }
}

} // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse(argc, argv);
        Diagnostics diag(false);
        const Scene scene = load_scene(o.scene, BuildOptions{}, diag);
        RenderSettings base;
        base.width = o.width;
        base.height = o.height;
        base.max_depth = o.max_depth;
        base.threads = o.threads;
        base.quiet = true;
        base.aovs = AovSet::parse("variance");
        const auto accel = make_accel(scene, base.accel);

        fmt::print("{}, {}x{}, depth {}, {} spp, {} seeds per set, reference {} spp\n", o.scene,
                   o.width, o.height, o.max_depth, o.spp, o.seeds, o.ref_spp);
        fmt::print("cost of each allocation that reaches uniform's relMSE at {} spp, over "
                   "uniform's cost (floor {:.0f}, cap {:.0f} x spp samples per pixel):\n",
                   o.spp, kFloorSamples, kCapFactor);
        const PixelData ref = render_uniform(scene, *accel, base, o.ref_spp,
                                             SamplerKind::Independent, kReferenceSeed);
        for (SamplerKind sampler : o.samplers)
            report(scene, *accel, base, o, ref, sampler);
        return 0;
    } catch (const Error& e) {
        fmt::print(stderr, "adaptive_bound: {}\n", e.what());
        return int(e.kind());
    }
}
