// Times scene loading: COLLADA parsing (load_collada) and scene building (build_scene)
// separately, over N repetitions; prints min and median in milliseconds.
//
//   bench_load [scene.dae] [N]      defaults: ../shared/scenes/cs184/CBbunny.dae, 10
//   bench_load --info [scene.dae]   also prints `describe_scene` for the loaded scene
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <string>
#include <vector>

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

} // namespace

int main(int argc, char** argv) {
    std::string path = "../shared/scenes/cs184/CBbunny.dae";
    int reps = 10;
    bool info = false;
    int pos = 0;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (a == "--info") {
            info = true;
        } else if (a == "-h" || a == "--help") {
            fmt::print("usage: bench_load [--info] [scene.dae] [repetitions]\n");
            return 0;
        } else if (pos == 0) {
            path = a;
            ++pos;
        } else {
            reps = std::max(1, std::atoi(a.c_str()));
        }
    }
    try {
        std::vector<double> parse_ms, build_ms;
        for (int r = 0; r < reps; ++r) {
            candela::Diagnostics diag;
            candela::Stopwatch timer;
            candela::SceneDesc desc = candela::load_collada(path, diag);
            parse_ms.push_back(timer.seconds() * 1e3);
            timer.restart();
            candela::Scene scene = candela::build_scene(desc, candela::BuildOptions{}, diag);
            build_ms.push_back(timer.seconds() * 1e3);
            if (r == 0 && info) fmt::print("{}", candela::describe_scene(scene, false));
            if (r > 0) diag.flush(); // warnings are printed once, by the first repetition
        }
        fmt::print("{}: {} repetitions\n", path, reps);
        fmt::print("  parse  min {:8.2f} ms  median {:8.2f} ms\n",
                   *std::min_element(parse_ms.begin(), parse_ms.end()), median(parse_ms));
        fmt::print("  build  min {:8.2f} ms  median {:8.2f} ms\n",
                   *std::min_element(build_ms.begin(), build_ms.end()), median(build_ms));
    } catch (const candela::Error& e) {
        fmt::print(stderr, "bench_load: {}\n", e.what());
        return static_cast<int>(e.kind());
    }
    return 0;
}
