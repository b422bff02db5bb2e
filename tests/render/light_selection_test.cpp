// Light selection seen in images: a lamp-lit room must render its closed-form radiance beside a
// sun over a ground of any width, with every estimator (the sun's selection weight does not grow
// with the scene, and no light's probability vanishes).
#include "candela/scene/camera.h"

#include "render_support.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// The film's standard error (from per-pixel sample variances, 64 samples in each of 192
/// pixels) against the one predicted from the closed form's moments (predicted_std_err): the
/// estimate spreads by about sqrt(2 / (64 * 192)) = 1.3 % and came within 1 % of the prediction
/// for every estimator here. A lamp chosen with half the probability it should be at least
/// doubles the variance E[L^2] / p - E[L]^2 (as E[L]^2 <= E[L^2]): 41 % more error, which this
/// bound catches.
constexpr double kNoiseFactor = 1.25;

/// The first two moments of one pixel's radiance over its box.
struct PixelMoments {
    double mean = 0.0, mean_square = 0.0;
};

/// The radiance of make_sunlit_room_scene at scattering order 1 (-m 1), pixel by pixel
/// (W x H), by the midpoint rule with n x n points per pixel.
///
/// Derivation. Every pixel's estimate is the mean over its box of the radiance its camera ray
/// brings (film.h), so its expectation is the integral over the pixel of L(x(f)), x(f) the
/// first wall point seen through film position f. At order 1 that radiance is the lamp's light
/// scattered once: the walls are flat and Lambertian of albedo rho = 0.7 (f = rho / pi), the
/// lamp an isotropic point of intensity I = 10 W/sr inside the convex room, which sees every
/// wall point unoccluded, so
///     L(x) = (rho / pi) I |cos theta| / d^2,  d = |l - x|,  cos theta = n(x) . (l - x) / d,
/// in luminance too, the room being grey. No light of the sun (E = 1 on the ground outside)
/// enters the closed room. The camera ray is the renderer's (CameraProjection) and its exit
/// from the box [-2, 2] x [0, 3] x [-2, 2] is closed-form, so the only approximation is the
/// quadrature over each pixel, whose error the caller measures by halving n.
std::vector<PixelMoments> room_order1(const Scene& scene, int W, int H, int n) {
    constexpr double kRho = 0.7, kIntensity = 10.0;
    const double lamp[3] = {0.3f, 2.6f, -0.4f}; // the floats of make_sunlit_room_scene, exactly
    const double lo[3] = {-2.0, 0.0, -2.0}, hi[3] = {2.0, 3.0, 2.0};
    const CameraProjection camera(scene.camera, W, H);
    std::vector<PixelMoments> pixels;
    for (int py = 0; py < H; ++py)
        for (int px = 0; px < W; ++px) {
            PixelMoments m;
            for (int b = 0; b < n; ++b)
                for (int a = 0; a < n; ++a) {
                    const Ray r =
                        camera.ray(float(px) + (float(a) + 0.5f) / float(n),
                                   float(py) + (float(b) + 0.5f) / float(n), Vec2(0.5f, 0.5f));
                    const double o[3] = {r.o.x, r.o.y, r.o.z}, d[3] = {r.d.x, r.d.y, r.d.z};
                    double t = std::numeric_limits<double>::infinity();
                    int axis = 0;
                    for (int k = 0; k < 3; ++k) {
                        if (d[k] == 0.0) continue;
                        const double tk = ((d[k] > 0.0 ? hi[k] : lo[k]) - o[k]) / d[k];
                        if (tk < t) {
                            t = tk;
                            axis = k;
                        }
                    }
                    double d2 = 0.0, to_lamp_axis = 0.0;
                    for (int k = 0; k < 3; ++k) {
                        const double c = lamp[k] - (o[k] + t * d[k]);
                        d2 += c * c;
                        if (k == axis) to_lamp_axis = c;
                    }
                    const double L =
                        kRho / kPiD * kIntensity * std::abs(to_lamp_axis) / (std::sqrt(d2) * d2);
                    m.mean += L;
                    m.mean_square += L * L;
                }
            m.mean /= double(n) * n;
            m.mean_square /= double(n) * n;
            pixels.push_back(m);
        }
    return pixels;
}

double film_mean(const std::vector<PixelMoments>& pixels) {
    double sum = 0.0;
    for (const PixelMoments& m : pixels)
        sum += m.mean;
    return sum / double(pixels.size());
}

/// The standard error of the film mean (film_estimate) of an estimator that takes `spp`
/// independent samples per pixel, each finding the lamp with probability p and then weighing it
/// 1 / p (next-event estimation choosing it among the lights), else nothing: a pixel's sample
/// has variance E[L^2] / p - E[L]^2.
double predicted_std_err(const std::vector<PixelMoments>& pixels, int spp, double p) {
    double var = 0.0;
    for (const PixelMoments& m : pixels)
        var += (m.mean_square / p - m.mean * m.mean) / spp;
    return std::sqrt(var) / double(pixels.size());
}

} // namespace

TEST_CASE("a lamp-lit room renders its closed-form radiance beside a sun over a 100 km ground",
          "[render][stat]") {
    RenderSettings s;
    s.width = 16;
    s.height = 12;
    s.spp = 64;
    s.max_depth = 1; // order 1: the lamp's light scattered once, in closed form
    s.quiet = true;
    s.aovs = AovSet::parse("variance");
    s.seed = 13;
    // Quadrature error: the midpoint rule's change on halving the points per pixel bounds it
    // (the error falls at least linearly where a wall edge crosses a pixel, quadratically
    // elsewhere).
    const Scene alone = make_sunlit_room_scene(0.f, false);
    const std::vector<PixelMoments> pixels = room_order1(alone, s.width, s.height, 128);
    const double expected = film_mean(pixels);
    const double quadrature_err =
        std::abs(expected - film_mean(room_order1(alone, s.width, s.height, 64)));
    INFO("closed form: " << expected << " (quadrature error < " << quadrature_err << ")");
    // Small beside the film's error, so that the test keeps its power.
    REQUIRE(quadrature_err < 0.25 * predicted_std_err(pixels, s.spp, 1.0));
    struct Variant {
        const char* name;
        IntegratorKind integrator;
        bool hemisphere;
        LightSamplerKind light_sampler;
    };
    const Variant variants[] = {
        {"path, power", IntegratorKind::Path, false, LightSamplerKind::Power},
        {"path, bvh", IntegratorKind::Path, false, LightSamplerKind::Bvh},
        {"path, auto", IntegratorKind::Path, false, LightSamplerKind::Auto},
        {"path -H", IntegratorKind::Path, true, LightSamplerKind::Auto},
        {"direct", IntegratorKind::Direct, false, LightSamplerKind::Auto},
        {"direct -H", IntegratorKind::Direct, true, LightSamplerKind::Auto},
    };
    for (const Variant& v : variants) {
        RenderSettings t = s;
        t.integrator = v.integrator;
        t.hemisphere = v.hemisphere;
        t.light_sampler = v.light_sampler;
        for (float width : {0.f, 20.f, 1e3f, 1e5f}) {
            const Scene scene = width > 0.f ? make_sunlit_room_scene(width, true) : alone;
            RenderStats stats;
            const Estimate e = film_estimate(render_film(scene, t, &stats));
            // A z-test on the film's standard error, the quadrature's error added in quadrature.
            const double z = (e.mean - expected) / std::hypot(e.std_err, quadrature_err);
            INFO((width > 0.f ? "ground " : "no sun, ground ")
                 << width << " m, " << v.name << ": " << e.mean << " +- " << e.std_err
                 << " against " << expected << ", z = " << z);
            CHECK(std::abs(z) < kZBound);
            // The lamp is chosen half the time beside the sun (its group's share, however wide
            // the ground), not 2^-25 of it: the film's error is the one predicted for that
            // probability. Direct and -H take every delta light at every vertex (p = 1), as
            // does the path estimator without the sun.
            const bool picks = width > 0.f && !v.hemisphere && v.integrator == IntegratorKind::Path;
            const double predicted = predicted_std_err(pixels, t.spp, picks ? 0.5 : 1.0);
            INFO("predicted standard error " << predicted);
            CHECK(e.std_err < kNoiseFactor * predicted);
            // Every sampler request of the render was in the integrator's plan.
            CHECK(stats.sampler_fallbacks == 0u);
        }
    }
}
