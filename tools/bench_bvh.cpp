// Benchmarks the builtin BVH side by side with Embree on one scene (run_bench), and optionally
// times the builtin build alone (with the tree's shape and SAH cost, so a faster build can be
// checked for what it costs the tree), the SSE2 traversal against the AVX2 one, and the nodes
// a bounce ray must enter (--visits), a measure of traversal work that caches do not blur.
//
//   bench_bvh [scene] [--threads N] [--rays N] [--seconds S] [--build-only] [--builds K]
//             [--build-threads T] [--isa-compare] [--visits] [--watertight]
//   --build-threads T: time only builds with T threads (default: 1, then all available)
//   scene: a .dae path (e.g. ../shared/scenes/cs184/CBbunny.dae) or a procedural spec
//   (e.g. sphere:1000000); default ../shared/scenes/cs184/CBbunny.dae
#include "candela/accel/bvh.h"
#include "candela/diagnostics/accel_bench.h"
#include "candela/diagnostics/check.h"
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fmt/format.h>
#include <string>
#include <utility>
#include <vector>

namespace {

/// Half the surface area of a box given by its low and high corners.
double half_area(const float lo[3], const float hi[3]) {
    const double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return dx * dy + dy * dz + dz * dx;
}

/// SAH cost of the tree relative to its root box, with the costs the builder assumes: one unit
/// per visit of an 8-wide inner node and one per block of four leaf primitives. Lower is
/// better; it tells whether a change to the build traded tree quality for speed.
double sah_cost(const candela::BvhAccel& bvh) {
    const candela::Bounds3 b = bvh.bounds();
    const float rlo[3] = {b.lo.x, b.lo.y, b.lo.z}, rhi[3] = {b.hi.x, b.hi.y, b.hi.z};
    const double root_area = half_area(rlo, rhi);
    if (!(root_area > 0.0) || bvh.nodes().empty()) return 0.0;
    double cost = 0.0;
    // Each inner node is visited with the probability of its parent's slot box; the root always.
    std::vector<std::pair<std::uint32_t, double>> stack = {{bvh.root(), root_area}};
    while (!stack.empty()) {
        const auto [index, area] = stack.back();
        stack.pop_back();
        cost += area / root_area;
        const candela::Bvh8Node& n = bvh.nodes()[index];
        for (int k = 0; k < candela::kBvhWidth; ++k) {
            const float lo[3] = {n.bounds[0][0][k], n.bounds[1][0][k], n.bounds[2][0][k]};
            const float hi[3] = {n.bounds[0][1][k], n.bounds[1][1][k], n.bounds[2][1][k]};
            if (!(lo[0] <= hi[0])) continue; // unused slot
            const std::uint32_t c = n.child[k];
            if (c & candela::kBvhLeafBit)
                cost += half_area(lo, hi) / root_area * static_cast<double>(((c & 7u) + 4u) / 4u);
            else
                stack.push_back({c, half_area(lo, hi)});
        }
    }
    return cost;
}

/// Nodes and leaves of the tree whose boxes a ray enters before its closest hit (before tmax
/// if it misses): the visits any near-to-far traversal must make, whatever its ordering. A
/// measure of the tree's traversal work that, unlike time, does not depend on caches.
struct VisitCounts {
    double nodes = 0.0, leaves = 0.0; ///< per ray
};

VisitCounts count_visits(const candela::BvhAccel& bvh, const std::vector<candela::Ray>& rays) {
    VisitCounts total;
    if (bvh.nodes().empty()) return total;
    std::vector<std::uint32_t> stack;
    for (const candela::Ray& ray : rays) {
        const auto hit = bvh.intersect(ray);
        const double t_end = hit ? hit->t : ray.tmax;
        const double o[3] = {ray.o.x, ray.o.y, ray.o.z};
        const double inv[3] = {1.0 / ray.d.x, 1.0 / ray.d.y, 1.0 / ray.d.z};
        stack.assign(1, bvh.root());
        while (!stack.empty()) {
            const candela::Bvh8Node& n = bvh.nodes()[stack.back()];
            stack.pop_back();
            total.nodes += 1.0;
            for (int k = 0; k < candela::kBvhWidth; ++k) {
                if (!(n.bounds[0][0][k] <= n.bounds[0][1][k])) continue; // unused slot
                double t0 = ray.tmin, t1 = t_end;
                for (int a = 0; a < 3; ++a) {
                    const double ta = (n.bounds[a][0][k] - o[a]) * inv[a];
                    const double tb = (n.bounds[a][1][k] - o[a]) * inv[a];
                    t0 = std::max(t0, std::min(ta, tb));
                    t1 = std::min(t1, std::max(ta, tb));
                }
                if (t0 > t1) continue;
                if (n.child[k] & candela::kBvhLeafBit)
                    total.leaves += 1.0;
                else
                    stack.push_back(n.child[k]);
            }
        }
    }
    const double count = static_cast<double>(std::max<std::size_t>(rays.size(), 1));
    return {total.nodes / count, total.leaves / count};
}

} // namespace

int main(int argc, char** argv) {
    std::string spec = "../shared/scenes/cs184/CBbunny.dae";
    int threads = 1, builds = 0, build_threads = -1;
    bool build_only = false, isa_compare = false, visits = false;
    candela::BenchOptions opt;
    opt.accels = {candela::AccelKind::Embree, candela::AccelKind::Builtin};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--threads" && i + 1 < argc) {
            threads = std::atoi(argv[++i]);
        } else if (a == "--rays" && i + 1 < argc) {
            opt.bounce_rays = opt.shadow_rays = std::strtoull(argv[++i], nullptr, 10);
        } else if (a == "--seconds" && i + 1 < argc) {
            opt.min_seconds = std::atof(argv[++i]);
        } else if (a == "--build-only") {
            build_only = true;
        } else if (a == "--builds" && i + 1 < argc) {
            builds = std::atoi(argv[++i]);
        } else if (a == "--build-threads" && i + 1 < argc) {
            build_threads = std::atoi(argv[++i]);
        } else if (a == "--isa-compare") {
            isa_compare = true;
        } else if (a == "--visits") {
            visits = true;
        } else if (a == "--watertight") {
            opt.triangle = candela::TriangleTest::Watertight;
        } else if (a == "-h" || a == "--help") {
            fmt::print("usage: bench_bvh [scene] [--threads N] [--rays N] [--seconds S] "
                       "[--build-only] [--builds K] [--build-threads T] [--isa-compare] "
                       "[--visits] [--watertight]\n");
            return 0;
        } else {
            spec = a;
        }
    }
    opt.threads = {threads};
    try {
        candela::Diagnostics diag;
        const candela::Scene scene = spec.size() > 4 && spec.substr(spec.size() - 4) == ".dae"
                                         ? candela::load_scene(spec, candela::BuildOptions{}, diag)
                                         : candela::make_procedural_scene(spec);
        if (builds > 0) {
            // Builtin build alone, serial and default-threaded, median of `builds` runs.
            std::vector<int> thread_counts = {1, 0};
            if (build_threads >= 0) thread_counts = {build_threads};
            for (int bt : thread_counts) {
                std::vector<double> s, cpu;
                std::size_t mem = 0, nodes = 0, leaves = 0;
                int depth = 0;
                double sah = 0.0;
                for (int k = 0; k < builds; ++k) {
                    timespec c0{}, c1{};
                    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
                    const candela::Stopwatch timer;
                    const candela::BvhAccel bvh(scene, opt.triangle, bt);
                    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
                    cpu.push_back(static_cast<double>(c1.tv_sec - c0.tv_sec) +
                                  1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec));
                    s.push_back(timer.seconds());
                    mem = bvh.memory_bytes();
                    nodes = bvh.node_count();
                    leaves = bvh.leaf_count();
                    depth = bvh.depth();
                    sah = sah_cost(bvh);
                }
                std::sort(s.begin(), s.end());
                std::sort(cpu.begin(), cpu.end());
                const double prims =
                    static_cast<double>(scene.triangle_count() + scene.spheres.size());
                fmt::print(
                    "builtin build threads={}: median {:.4f} s (min {:.4f}) = {:.2f} Mprims/s; "
                    "process CPU median {:.4f} s; "
                    "{} nodes, {} leaves, depth {}, {:.1f} bytes/prim, "
                    "{:.2f} children per node, SAH cost {:.2f}\n",
                    bt, s[s.size() / 2], s[0], prims / s[s.size() / 2] * 1e-6, cpu[cpu.size() / 2],
                    nodes, leaves, depth, static_cast<double>(mem) / prims,
                    nodes ? static_cast<double>(nodes - 1 + leaves) / static_cast<double>(nodes)
                          : 0.0,
                    sah);
            }
        }
        if (isa_compare) {
            // Single thread, the same BVH traversed by both kernels, best of five passes each.
            const std::vector<candela::Ray> bounce =
                candela::make_bounce_rays(scene, opt.bounce_rays, opt.seed);
            const std::vector<candela::Ray> shadow =
                candela::make_shadow_rays(scene, opt.shadow_rays, opt.seed);
            std::vector<candela::BvhIsa> isas = {candela::BvhIsa::Sse2};
            if (candela::bvh_cpu_has_avx2()) isas.push_back(candela::BvhIsa::Avx2);
            for (candela::BvhIsa isa : isas) {
                const candela::BvhAccel bvh(scene, opt.triangle, 0, isa);
                double best[2] = {0.0, 0.0};
                std::size_t hits[2] = {0, 0};
                for (int round = 0; round < 5; ++round) {
                    for (int kind = 0; kind < 2; ++kind) {
                        const auto& rays = kind == 0 ? bounce : shadow;
                        std::size_t h = 0;
                        const candela::Stopwatch timer;
                        for (const candela::Ray& r : rays)
                            h += kind == 0 ? bvh.intersect(r).has_value() : bvh.occluded(r);
                        const double sec = timer.seconds();
                        best[kind] =
                            std::max(best[kind], static_cast<double>(rays.size()) / sec * 1e-6);
                        hits[kind] = h;
                    }
                }
                fmt::print("builtin {}: bounce {:.3f} Mrays/s ({} hits), shadow {:.3f} Mrays/s "
                           "({} occluded)\n",
                           isa == candela::BvhIsa::Avx2 ? "avx2" : "sse2", best[0], hits[0],
                           best[1], hits[1]);
            }
        }
        if (visits) {
            const candela::BvhAccel bvh(scene, opt.triangle, 0);
            const VisitCounts v =
                count_visits(bvh, candela::make_bounce_rays(scene, opt.bounce_rays, opt.seed));
            fmt::print("bounce rays: {:.2f} inner nodes and {:.2f} leaves entered before the hit, "
                       "per ray (depth {})\n",
                       v.nodes, v.leaves, bvh.depth());
        }
        if (build_only || isa_compare || visits) return 0;
        const candela::BenchReport rep = candela::run_bench(scene, opt);
        fmt::print("{}", rep.to_text());
    } catch (const candela::Error& e) {
        fmt::print(stderr, "bench_bvh: {}\n", e.what());
        return 1;
    }
    return 0;
}
