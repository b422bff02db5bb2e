// The light tree's importance where the shading point is inside its nodes' bounds: on scenes
// built to put most shading points there (scene/procedural.h: make_near_wall_scene, a strong
// light near a wall among many lights on both sides of it, and make_panel_lights_scene, lights
// under a large dim panel whose bounds hold them all), the bvh choice must sample a point's
// unshadowed irradiance with no more variance than the choice by power alone. The variances are
// computed, not sampled: the probabilities are exact (pmf()) and each light's own estimator's
// moments come from a fixed grid of its samples, so the comparison has no noise to allow for.
#include "candela/light/light_sampler.h"
#include "candela/light/light_sampling.h"
#include "candela/scene/procedural.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;

namespace {

/// Light samples per axis of the grid that gives each light's moments at a point (delta lights
/// need one; the grid's error is the same for both choices, which are compared with each other).
constexpr int kGrid = 8;

/// First and second moments of a light's one-sample estimate of the irradiance at p (unit normal
/// n, no occlusion): L cos / pdf over a kGrid x kGrid grid of its samples.
struct Moments {
    double m1 = 0.0, m2 = 0.0;
};

std::vector<Moments> light_moments(const Scene& scene, const Vec3& p, const Vec3& n) {
    std::vector<Moments> out(scene.lights.size());
    for (std::size_t k = 0; k < scene.lights.size(); ++k) {
        for (int j = 0; j < kGrid; ++j)
            for (int i = 0; i < kGrid; ++i) {
                const Vec2 u((float(i) + 0.5f) / kGrid, (float(j) + 0.5f) / kGrid);
                const auto s = sample_li(scene, scene.lights[k], p, u);
                if (!s || !(s->pdf > 0.f)) continue;
                const double f =
                    double(luminance(s->L)) * std::max(0.0, double(dot(s->wi, n))) / s->pdf;
                out[k].m1 += f;
                out[k].m2 += f * f;
            }
        out[k].m1 /= kGrid * kGrid;
        out[k].m2 /= kGrid * kGrid;
    }
    return out;
}

/// Variance of one next-event sample relative to the squared irradiance,
/// sum_k E_k[f^2] / pmf_k / E^2 - 1, for the choice `sampler` makes at (p, n).
double relative_variance(const LightSampler& sampler, const std::vector<Moments>& m, const Vec3& p,
                         const Vec3& n) {
    double mean = 0.0, second = 0.0;
    for (std::size_t k = 0; k < m.size(); ++k) {
        if (!(m[k].m2 > 0.0)) continue;
        const double pmf = sampler.pmf(p, n, k);
        REQUIRE(pmf > 0.0); // a light that lights p must be reachable there
        mean += m[k].m1;
        second += m[k].m2 / pmf;
    }
    return second / (mean * mean) - 1.0;
}

/// Checks, at each point of `points` (normal n), that bvh's relative variance is at most
/// power's; returns the largest ratio of the two.
double worst_ratio(const Scene& scene, const std::vector<Vec3>& points, const Vec3& n) {
    const LightSampler bvh(scene, LightSamplerKind::Bvh), power(scene, LightSamplerKind::Power);
    REQUIRE(bvh.kind() == LightSamplerKind::Bvh);
    double worst = 0.0;
    for (const Vec3& p : points) {
        const std::vector<Moments> m = light_moments(scene, p, n);
        const double vb = relative_variance(bvh, m, p, n), vp = relative_variance(power, m, p, n);
        INFO(scene.source << " at (" << p.x << ", " << p.y << ", " << p.z << "): bvh " << vb
                          << ", power " << vp);
        CHECK(vb <= vp);
        worst = std::max(worst, vb / vp);
    }
    return worst;
}

} // namespace

TEST_CASE("bvh light choice: a strong light near a wall keeps its samples among 200 others",
          "[light][quick]") {
    // Wall points from the near light's foot out to 2 m, where its share of the light falls
    // from most of it to a small part: inside the bounds of most of the tree's nodes (the
    // lights surround the wall), where a node's importance used to be power / radius^2 wherever
    // the point was, so the near light's subtree lost to siblings with more power per volume at
    // every level and got a probability 10x below power's.
    std::vector<Vec3> points;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i)
            points.push_back(Vec3(0.6f + 0.5f * float(i), 0.4f + 0.5f * float(j), 0.f));
    for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
        const Scene scene = make_near_wall_scene(200, seed);
        const double worst = worst_ratio(scene, points, Vec3(0.f, 0.f, 1.f));
        INFO(scene.source << ": bvh's variance at most " << worst << " of power's");
        CHECK(worst <= 1.0);
    }
}

TEST_CASE("bvh light choice: lights under a large dim panel, inside its bounds", "[light][quick]") {
    // Floor points under a 6 x 6 m panel of radiance 0.05 with 60 lights between the two, every
    // one of them inside the panel's bounding sphere (and the floor points too).
    std::vector<Vec3> points;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i)
            points.push_back(Vec3(1.3f * float(i), 0.f, 1.3f * float(j)));
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const Scene scene = make_panel_lights_scene(60, seed);
        const double worst = worst_ratio(scene, points, Vec3(0.f, 1.f, 0.f));
        INFO(scene.source << ": bvh's variance at most " << worst << " of power's");
        CHECK(worst <= 1.0);
    }
}
