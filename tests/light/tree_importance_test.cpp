// The light tree's importance where the shading point is inside its nodes' bounds: on scenes
// built to put most shading points there (scene/procedural.h: make_near_wall_scene, a strong
// light near a wall among many lights on both sides of it, and make_panel_lights_scene, lights
// under a large dim panel whose bounds hold them all), the bvh choice must sample a point's
// unshadowed irradiance with no more variance than the choice by power alone. The variances are
// computed, not sampled: the probabilities are exact (pmf()) and each light's own estimator's
// moments come from a fixed grid of its samples, so the comparison has no noise to allow for.
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
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
double relative_variance(const LightChooser& sampler, const std::vector<Moments>& m, const Vec3& p,
                         const Vec3& n) {
    double mean = 0.0, second = 0.0;
    for (std::size_t k = 0; k < m.size(); ++k) {
        if (!(m[k].m2 > 0.0)) continue;
        const double pmf = sampler.pmf({p, n}, k);
        REQUIRE(pmf > 0.0); // a light that lights p must be reachable there
        mean += m[k].m1;
        second += m[k].m2 / pmf;
    }
    return second / (mean * mean) - 1.0;
}

/// bvh's and power's relative variances at each point of `points` (normal n).
struct Variances {
    std::vector<double> bvh, power;
};

Variances variances(const Scene& scene, const std::vector<Vec3>& points, const Vec3& n) {
    const LightChooser bvh(scene, LightSamplerKind::Bvh), power(scene, LightSamplerKind::Power);
    REQUIRE(bvh.kind() == LightSamplerKind::Bvh);
    Variances v;
    for (const Vec3& p : points) {
        const std::vector<Moments> m = light_moments(scene, p, n);
        v.bvh.push_back(relative_variance(bvh, m, p, n));
        v.power.push_back(relative_variance(power, m, p, n));
    }
    return v;
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
        const Variances v = variances(scene, points, Vec3(0.f, 0.f, 1.f));
        for (std::size_t i = 0; i < points.size(); ++i) {
            INFO(scene.source << " at (" << points[i].x << ", " << points[i].y << "): bvh "
                              << v.bvh[i] << ", power " << v.power[i]);
            CHECK(v.bvh[i] <= v.power[i]);
        }
    }
}

TEST_CASE("bvh light choice: lights under a large dim panel, inside its bounds", "[light][quick]") {
    // Floor points under a 6 x 6 m panel of radiance 0.05 with 60 lights between the two, every
    // one of them inside the panel's bounding sphere (and the floor points too).
    std::vector<Vec3> points;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i)
            points.push_back(Vec3(1.3f * float(i), 0.f, 1.3f * float(j)));
    // Here no single light dominates a point, and at a few points bvh's variance exceeds
    // power's (by 19 % at most of these 75): the claim is for the floor as a whole, the sum of
    // the variances over its points.
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const Scene scene = make_panel_lights_scene(60, seed);
        const Variances v = variances(scene, points, Vec3(0.f, 1.f, 0.f));
        double bvh = 0.0, power = 0.0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            bvh += v.bvh[i];
            power += v.power[i];
        }
        INFO(scene.source << ": summed relative variance, bvh " << bvh << ", power " << power);
        CHECK(bvh <= power);
    }
}

TEST_CASE("bvh light choice: inside a node's bounds the importance follows the point",
          "[light][quick]") {
    // A wall point p with a point light of intensity 4.4 1 m in front of it, paired in the tree
    // with a faint light 11 m away (their box holds p), and two lights of intensity 80 about 6 m
    // off (a box p is outside of). The near light gives p more than half its light (4.4 against
    // about 1.5 from each far one) but 2.7 % of the power. A node's importance inside its bounds
    // used to be power / radius^2 wherever p stood: the near pair then weighed 1.5 against the
    // far pair's 30 or more, and the near light got less than power alone gives it.
    Scene scene;
    scene.source = "near-pair";
    const auto point = [&](const Vec3& p, float intensity) {
        Light l;
        l.kind = LightKind::Point;
        l.p = p;
        l.L = Rgb(intensity);
        scene.lights.push_back(l);
    };
    point(Vec3(-8.f, 0.f, -8.f), 0.01f); // faint, far, behind the wall
    point(Vec3(0.f, 0.f, 1.f), 4.4f);    // the near light
    point(Vec3(4.f, 0.f, 5.f), 80.f);
    point(Vec3(6.f, 0.f, 5.f), 80.f);
    const Vec3 p(0.f), n(0.f, 0.f, 1.f);
    const LightChooser bvh(scene, LightSamplerKind::Bvh);
    // The baseline is the choice that knows nothing, each light 1/4: any estimate of where the
    // light comes from must do at least as well here, where one light dominates.
    const std::vector<Moments> m = light_moments(scene, p, n);
    double mean = 0.0, second = 0.0;
    for (const Moments& k : m) {
        mean += k.m1;
        second += k.m2 * double(m.size());
    }
    const double uniform = second / (mean * mean) - 1.0;
    const double tree = relative_variance(bvh, m, p, n);
    INFO("near light's probability " << bvh.pmf({p, n}, 1) << "; relative variance: bvh " << tree
                                     << ", uniform " << uniform);
    CHECK(tree <= uniform);
}
