#pragma once
// Radiance estimators. One concrete Integrator whose estimate() switches on the settings once
// per camera sample; the bounce loop itself has no virtual calls except the accelerator's
// one-per-ray intersect/occluded.
#include "candela/accel/accel.h"
#include "candela/light/light_sampler.h"
#include "candela/light/light_sampling.h"
#include "candela/render/film.h"
#include "candela/render/settings.h"
#include "candela/sampling/sampler.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <vector>

namespace candela {

struct SurfaceInteraction;

/// Per-thread counters, summed by the renderer.
struct TraceCounters {
    std::uint64_t rays = 0;        ///< closest-hit queries
    std::uint64_t shadow_rays = 0; ///< occlusion queries
};

/// The sample dimensions of one camera sample: every use of a random number has a fixed
/// dimension, the same in every sample of a pixel, so that a (0,2)-sequence stratifies each use
/// across the pixel's samples. Whether a bounce's next-event estimate, BSDF sample or roulette
/// test happens (a delta vertex skips next-event estimation, roulette starts late) never moves
/// the dimensions of the ones after it.
struct DimensionLayout {
    static constexpr std::uint32_t kFilm = 0;        ///< 2: position inside the pixel
    static constexpr std::uint32_t kLens = 2;        ///< 2: thin-lens aperture point
    static constexpr std::uint32_t kFirstVertex = 4; ///< first dimension of vertex 0
    std::uint32_t direct = 0; ///< dimensions of one vertex's direct-light estimate
    std::uint32_t stride = 0; ///< dimensions per vertex: direct, BSDF (3), roulette (path: 1)
    /// First dimension of path vertex `depth` (0 = the camera ray's hit).
    std::uint32_t vertex(int depth) const {
        return kFirstVertex + stride * static_cast<std::uint32_t>(depth);
    }
    std::uint32_t bsdf(int depth) const { return vertex(depth) + direct; }
    std::uint32_t roulette(int depth) const { return vertex(depth) + direct + 3; }
};

class Integrator {
  public:
    Integrator(const Scene& scene, const Accel& accel, const RenderSettings& settings);

    /// One camera sample through continuous film position (fx, fy) (pixels, row 0 at the top).
    /// Returns radiance and first-hit auxiliary values. The result may be non-finite; the
    /// caller drops such samples.
    FilmSample estimate(float fx, float fy, Sampler& sampler, TraceCounters& counters) const;

    /// The camera ray through film position (fx, fy) with lens sample u_lens.
    Ray camera_ray(float fx, float fy, Vec2 u_lens) const;

    const DimensionLayout& dimensions() const { return dims_; }

  private:
    FilmSample path(const Ray& ray, Sampler& sampler, TraceCounters& c) const;
    FilmSample direct(const Ray& ray, Sampler& sampler, TraceCounters& c) const;
    FilmSample normals(const Ray& ray, TraceCounters& c) const;

    /// Next-event estimate at `si` with one light chosen by power: f * Li * cos / pdf, MIS
    /// weighted against BSDF sampling when `mis_`.
    Rgb sample_one_light(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                         TraceCounters& c) const;
    /// Light-sampling direct estimate summed over every light (ns samples per non-delta light).
    Rgb sample_all_lights(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                          TraceCounters& c) const;
    /// Direct estimate by uniform hemisphere sampling (the whole sphere of directions for a
    /// material that transmits): sees only emitters that rays can hit.
    Rgb sample_hemisphere(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                          TraceCounters& c) const;
    /// Light from every point, spot and directional light, each sampled once (no random
    /// numbers). Hemisphere sampling cannot find a delta light, so `-H` adds this estimate.
    Rgb sample_delta_lights(const SurfaceInteraction& si, const Material& m,
                            TraceCounters& c) const;
    /// The direct-light estimate of `-H`: hemisphere sampling plus the delta lights.
    Rgb sample_hemisphere_and_delta(const SurfaceInteraction& si, const Material& m,
                                    Sampler& sampler, TraceCounters& c) const;
    /// f * Li * |cos| / pdf of one light sample whose shadow ray is still to be traced, or 0
    /// when the BSDF does not scatter toward it or the sample leaves on the wrong geometric side.
    Rgb light_sample_value(const SurfaceInteraction& si, const Material& m, const LightSample& ls,
                           float pdf, Vec3* wi_local) const;
    /// Radiance emitted by the surface at `si` toward -ray direction `wo`.
    Rgb emitted(const SurfaceInteraction& si) const;
    /// Radiance of the infinite area lights seen by a BSDF-sampled ray that left the scene
    /// along `dir`, MIS weighted against light sampling light by light (each infinite light is
    /// its own light-sampling strategy). `prev_bsdf_pdf` is the density of the BSDF sample.
    Rgb escaped_mis(const Vec3& dir, float prev_bsdf_pdf) const;
    /// Whether light that scattered `order` times is written (-o, --light-paths).
    bool accept(int order) const;

    const Scene& scene_;
    const Accel& accel_;
    RenderSettings s_;
    LightSampler light_sampler_;
    float tan_half_h_ = 1.f, tan_half_v_ = 1.f;
    bool has_infinite_lights_ = false;
    int hemisphere_budget_ = 1;
    std::vector<std::uint32_t> infinite_area_lights_; ///< Ambient and Environment lights
    std::vector<std::uint32_t> delta_lights_;         ///< Point, Spot and Directional lights
    DimensionLayout dims_;
};

} // namespace candela
