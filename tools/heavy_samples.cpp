// Finds the camera samples that carry the most squared error of a uniform render, and splits
// each of them by scattering order.
//
//   heavy_samples SCENE [-r W H] [-s SPP] [-m DEPTH] [--seed N] [--sampler sobol|independent]
//                 [--ref EXR] [--top K] [-t THREADS] [--rr-depth N] [--no-mis]
//
// Renders every pixel with SPP samples, one integrator call per pixel, so each sample's
// radiance is seen on its own (the same samples `candela render --adaptive none` takes with the
// same seed, sampler and depth). A sample's score is its share of the image's relMSE,
// mean over channels of (L - r)^2 / (r^2 + 0.01) / SPP^2 / pixels, with r the pixel's value in
// the reference EXR (--ref; default: the render's own pixel mean). Prints the relMSE of the
// render, the share of it in the worst 1 % of pixels and in the K heaviest samples, then one
// line per heavy sample: pixel, sample index, radiance, score, and the radiance of the same
// sample rendered with -o 0 -m k for k = 0..DEPTH (the light that scattered exactly k times;
// the same random numbers drive the path, so the orders add up to the sample).
//
// `candela probe` splits one pixel's samples, given the pixel; this searches the whole image for
// the samples to look at. The relMSE is candela's (diagnostics/converge.h).
#include "candela/accel/accel.h"
#include "candela/diagnostics/converge.h"
#include "candela/io/collada.h"
#include "candela/io/image_io.h"
#include "candela/render/integrator.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace candela;

struct Options {
    std::string scene, ref;
    int width = 480, height = 360, spp = 64, max_depth = 8, top = 20, threads = 1;
    int rr_depth = 3;
    bool mis = true;
    std::uint64_t seed = 1;
    SamplerKind sampler = SamplerKind::Sobol;
};

[[noreturn]] void usage(const char* why) {
    fmt::print(stderr,
               "heavy_samples: {}\nusage: heavy_samples SCENE [-r W H] [-s SPP] [-m DEPTH] "
               "[--seed N] [--sampler sobol|independent] [--ref EXR] [--top K] [-t THREADS] "
               "[--rr-depth N] [--no-mis]\n",
               why);
    std::exit(2);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> const char* {
            if (i + 1 >= argc) usage(("missing value after " + a).c_str());
            return argv[++i];
        };
        if (a == "-r") {
            o.width = std::atoi(next());
            o.height = std::atoi(next());
        } else if (a == "-s") {
            o.spp = std::atoi(next());
        } else if (a == "-m") {
            o.max_depth = std::atoi(next());
        } else if (a == "--seed") {
            o.seed = std::strtoull(next(), nullptr, 10);
        } else if (a == "--sampler") {
            const std::string s = next();
            if (s != "sobol" && s != "independent") usage("--sampler takes sobol or independent");
            o.sampler = s == "sobol" ? SamplerKind::Sobol : SamplerKind::Independent;
        } else if (a == "--ref") {
            o.ref = next();
        } else if (a == "--top") {
            o.top = std::atoi(next());
        } else if (a == "-t") {
            o.threads = std::max(1, std::atoi(next()));
        } else if (a == "--rr-depth") {
            o.rr_depth = std::atoi(next());
        } else if (a == "--no-mis") {
            o.mis = false;
        } else if (!a.empty() && a[0] != '-' && o.scene.empty()) {
            o.scene = a;
        } else {
            usage(("unknown argument " + a).c_str());
        }
    }
    if (o.scene.empty()) usage("no scene");
    if (o.width < 1 || o.height < 1 || o.spp < 1 || o.max_depth < 0 || o.top < 1)
        usage("sizes, samples and --top must be positive");
    return o;
}

struct Heavy {
    double score = 0.0;
    SampleRequest request;
    Rgb L;
};

/// The samples of pixel (x, y), rendered in one call.
void render_pixel(const Integrator& integrator, int x, int y, int spp, BatchWorkspace& ws,
                  std::vector<SampleRequest>& requests, std::vector<SampleResult>& results) {
    requests.resize(std::size_t(spp));
    results.resize(std::size_t(spp));
    for (int k = 0; k < spp; ++k)
        requests[std::size_t(k)] =
            SampleRequest{std::uint32_t(x), std::uint32_t(y), std::uint64_t(k)};
    RenderCounters counters;
    integrator.render(requests.data(), requests.size(), results.data(), ws, counters);
}

/// relMSE of one RGB value against another (the mean over its channels).
double rel_sq(const Rgb& a, const Rgb& r) {
    ErrorSums s;
    for (int c = 0; c < 3; ++c)
        s.add(double(a[c]), double(r[c]));
    return s.error().rel_mse;
}

} // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse(argc, argv);
        Diagnostics diag(false);
        const Scene scene = load_scene(o.scene, BuildOptions{}, diag);
        RenderSettings s;
        s.width = o.width;
        s.height = o.height;
        s.max_depth = o.max_depth;
        s.seed = o.seed;
        s.sampler = o.sampler;
        s.rr_min_depth = o.rr_depth;
        s.mis = o.mis;
        s.quiet = true;
        const auto accel = make_accel(scene, s.accel);
        const Integrator integrator(scene, *accel, s);

        ImageData ref;
        if (!o.ref.empty()) {
            ref = read_image(o.ref);
            if (ref.width != o.width || ref.height != o.height || ref.channels() < 3)
                usage("the reference differs in size or has no RGB");
        }
        const std::size_t n_pixels = std::size_t(o.width) * std::size_t(o.height);
        std::vector<double> pixel_error(n_pixels, 0.0);
        std::vector<std::vector<Heavy>> heavy(std::size_t(o.threads));
        auto work = [&](int t) {
            BatchWorkspace ws;
            std::vector<SampleRequest> requests;
            std::vector<SampleResult> results;
            std::vector<Heavy>& mine = heavy[std::size_t(t)];
            auto lighter = [](const Heavy& a, const Heavy& b) { return a.score > b.score; };
            for (int y = t; y < o.height; y += o.threads) {
                for (int x = 0; x < o.width; ++x) {
                    render_pixel(integrator, x, y, o.spp, ws, requests, results);
                    Rgb mean(0.f);
                    for (const SampleResult& r : results)
                        if (is_finite(r.fs.L)) mean += r.fs.L;
                    mean = mean * (1.f / float(o.spp));
                    const Rgb r = o.ref.empty()
                                      ? mean
                                      : Rgb(ref.at(x, y, 0), ref.at(x, y, 1), ref.at(x, y, 2));
                    const std::size_t p = std::size_t(y) * std::size_t(o.width) + std::size_t(x);
                    // Without a reference, the pixel's squared error is estimated by the
                    // spread of its samples (the variance of their mean).
                    double spread = 0.0;
                    for (std::size_t k = 0; k < results.size(); ++k) {
                        const double score = rel_sq(results[k].fs.L, r) /
                                             (double(o.spp) * double(o.spp) * double(n_pixels));
                        spread += score;
                        if (int(mine.size()) < o.top || score > mine.front().score) {
                            mine.push_back({score, requests[k], results[k].fs.L});
                            std::push_heap(mine.begin(), mine.end(), lighter);
                            if (int(mine.size()) > o.top) {
                                std::pop_heap(mine.begin(), mine.end(), lighter);
                                mine.pop_back();
                            }
                        }
                    }
                    pixel_error[p] = o.ref.empty() ? spread * double(n_pixels) : rel_sq(mean, r);
                }
            }
        };
        std::vector<std::thread> pool;
        for (int t = 1; t < o.threads; ++t)
            pool.emplace_back(work, t);
        work(0);
        for (std::thread& th : pool)
            th.join();

        std::vector<Heavy> all;
        for (const auto& h : heavy)
            all.insert(all.end(), h.begin(), h.end());
        std::sort(all.begin(), all.end(),
                  [](const Heavy& a, const Heavy& b) { return a.score > b.score; });
        if (int(all.size()) > o.top) all.resize(std::size_t(o.top));

        double total = 0.0;
        for (double e : pixel_error)
            total += e;
        std::vector<double> sorted = pixel_error;
        std::sort(sorted.begin(), sorted.end(), std::greater<double>());
        double worst = 0.0;
        for (std::size_t i = 0; i < n_pixels / 100; ++i)
            worst += sorted[i];
        double top_sum = 0.0;
        for (const Heavy& h : all)
            top_sum += h.score;
        fmt::print("{}: {}x{}, {} spp, -m {}, seed {}: relMSE {:.4g}, worst 1% of pixels {:.3f} "
                   "of it, the {} heaviest samples {:.3f}\n",
                   o.scene, o.width, o.height, o.spp, o.max_depth, o.seed, total / double(n_pixels),
                   total > 0 ? worst / total : 0.0, all.size(),
                   total > 0 ? top_sum / total * double(n_pixels) : 0.0);
        fmt::print("pixel     sample  L (r g b)                  share     by order k = 0..{} "
                   "(max component)\n",
                   o.max_depth);
        std::vector<Integrator> by_order;
        for (int k = 0; k <= o.max_depth; ++k) {
            RenderSettings sk = s;
            sk.accumulate = false;
            sk.max_depth = k;
            by_order.emplace_back(scene, *accel, sk);
        }
        BatchWorkspace ws;
        for (const Heavy& h : all) {
            fmt::print("{:4} {:4} {:5}  {:8.3f} {:8.3f} {:8.3f}  {:.2e} ", h.request.px,
                       h.request.py, h.request.index, double(h.L.x), double(h.L.y), double(h.L.z),
                       h.score * double(n_pixels) / total);
            for (const Integrator& ik : by_order) {
                SampleResult r;
                RenderCounters counters;
                ik.render(&h.request, 1, &r, ws, counters);
                fmt::print(" {:.3g}", double(max_component(r.fs.L)));
            }
            fmt::print("\n");
        }
        return 0;
    } catch (const Error& e) {
        fmt::print(stderr, "heavy_samples: {}\n", e.what());
        return int(e.kind());
    }
}
