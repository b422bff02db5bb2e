// What the wavefront integrator leans on (render/integrator.h): the sampler plan of every path
// vertex covers every random number the estimators draw, so no draw falls back to computing its
// value on its own; and the image does not depend on how the camera samples are grouped into
// batches, only on the samples themselves.
#include "../support/cs184.h"
#include "render_support.h"

#include "candela/app/cli.h"
#include "candela/render/integrator.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <string>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// One estimator setting over the project's scenes (always in the clone) that between them
/// draw every kind of number: a light pick among several lights, delta and infinite lights
/// (lights.dae), a lobe choice and roulette deferred past specular lobes (glass.dae), glossy
/// lobes (glossy.dae), Lambertian directions (every scene).
struct Case {
    const char* name;
    RenderSettings settings;
    float lens_radius = 0.f; ///< > 0: a thin lens (focal distance kFocalDistance)
};

constexpr float kFocalDistance = 3.5f; ///< any positive distance: only the draws matter here
const char* const kScenes[] = {"cornell-spheres.dae", "lights.dae", "glass.dae", "glossy.dae"};

/// The command line's defaults (the Owen-scrambled Sobol sampler among them, where the library's
/// RenderSettings keeps the independent one), at a small size.
RenderSettings base_settings() {
    RenderSettings s = command_line_settings();
    s.width = 32; // 3072 samples: two batches of at most 2048
    s.height = 24;
    s.spp = 4;
    s.seed = 5;
    s.quiet = true;
    return s;
}

std::vector<Case> cases() {
    std::vector<Case> c;
    const RenderSettings base = base_settings();
    c.push_back({"path", base});
    RenderSettings s = base;
    s.integrator = IntegratorKind::Direct;
    c.push_back({"direct", s});
    s = base;
    s.hemisphere = true;
    c.push_back({"path -H", s});
    s.integrator = IntegratorKind::Direct;
    c.push_back({"direct -H", s});
    s = base;
    s.light_samples = 4;
    c.push_back({"path -l 4", s});
    s.integrator = IntegratorKind::Direct;
    c.push_back({"direct -l 4", s});
    c.push_back({"thin lens", base, 0.05f});
    s = base;
    s.sampler = SamplerKind::Independent;
    c.push_back({"independent", s});
    return c;
}

/// Every sample of the film: pixels in order, each pixel's samples next to each other.
std::vector<SampleRequest> film_requests(const RenderSettings& s) {
    std::vector<SampleRequest> r;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x)
            for (int k = 0; k < s.spp; ++k)
                r.push_back({std::uint32_t(x), std::uint32_t(y), std::uint64_t(k)});
    return r;
}

struct Rendered {
    std::vector<SampleResult> results;
    std::uint64_t fallback_draws = 0;
};

/// Renders `requests` through one workspace in consecutive batches of at most `batch`.
Rendered render_in_batches(const Integrator& integrator, const std::vector<SampleRequest>& requests,
                           std::size_t batch) {
    Rendered out;
    out.results.resize(requests.size());
    BatchWorkspace ws;
    RenderCounters counters;
    for (std::size_t first = 0; first < requests.size(); first += batch) {
        const std::size_t n = std::min(batch, requests.size() - first);
        integrator.render(requests.data() + first, n, out.results.data() + first, ws, counters);
    }
    out.fallback_draws = counters.sampler_fallbacks;
    return out;
}

/// Runs `check(case name, scene name, integrator, requests)` over every case and scene.
template <class Check> void for_each_case(Check check) {
    for (const char* scene_name : kScenes) {
        Diagnostics diag;
        Scene scene = load_scene(project_scene(scene_name), BuildOptions{}, diag);
        for (const Case& c : cases()) {
            scene.camera.lens_radius = c.lens_radius;
            scene.camera.focal_distance = kFocalDistance;
            const std::unique_ptr<Accel> accel = make_accel(scene, c.settings.accel);
            const Integrator integrator(scene, *accel, c.settings);
            check(c.name, scene_name, integrator, film_requests(c.settings));
        }
    }
}

/// Whether two results are the same bits (every film value, the hit flag, the query count).
bool same_bits(const SampleResult& a, const SampleResult& b) {
    auto same = [](const Vec3& u, const Vec3& v) { return std::memcmp(&u, &v, sizeof u) == 0; };
    return same(a.fs.L, b.fs.L) && same(a.fs.albedo, b.fs.albedo) &&
           same(a.fs.normal, b.fs.normal) &&
           std::memcmp(&a.fs.depth, &b.fs.depth, sizeof a.fs.depth) == 0 && a.fs.hit == b.fs.hit &&
           a.queries == b.queries;
}

} // namespace

TEST_CASE("the sampler plan of every vertex covers every draw", "[render][wavefront][quick]") {
    for_each_case([](const char* name, const char* scene, const Integrator& integrator,
                     const std::vector<SampleRequest>& requests) {
        const Rendered r = render_in_batches(integrator, requests, 2048);
        INFO(name << " on " << scene << ": " << r.fallback_draws << " draws the plan did not hold");
        CHECK(r.fallback_draws == 0);
    });
}

TEST_CASE("batch grouping does not change a sample's bits", "[render][wavefront][quick]") {
    for_each_case([](const char* name, const char* scene, const Integrator& integrator,
                     const std::vector<SampleRequest>& requests) {
        const Rendered whole = render_in_batches(integrator, requests, 2048);
        for (std::size_t batch : {std::size_t(1), std::size_t(7)}) {
            const Rendered parts = render_in_batches(integrator, requests, batch);
            std::size_t differing = 0, first = requests.size();
            for (std::size_t k = 0; k < requests.size(); ++k)
                if (!same_bits(whole.results[k], parts.results[k])) {
                    ++differing;
                    first = std::min(first, k);
                }
            INFO(name << " on " << scene << ", batches of " << batch << " vs 2048: " << differing
                      << " of " << requests.size() << " samples differ (first: " << first << ")");
            CHECK(differing == 0);
        }
    });
}
