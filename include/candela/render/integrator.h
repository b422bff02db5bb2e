#pragma once
// Radiance estimators. One concrete Integrator whose estimate() switches on the settings once
// per camera sample; the bounce loop itself has no virtual calls except the accelerator's
// one-per-ray intersect/occluded.
#include "candela/accel/accel.h"
#include "candela/light/light_sampler.h"
#include "candela/render/film.h"
#include "candela/render/settings.h"
#include "candela/sampling/sampler.h"
#include "candela/scene/scene.h"

#include <cstdint>

namespace candela {

struct SurfaceInteraction;

/// Per-thread counters, summed by the renderer.
struct TraceCounters {
    std::uint64_t rays = 0;        ///< closest-hit queries
    std::uint64_t shadow_rays = 0; ///< occlusion queries
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
    /// Direct estimate by uniform hemisphere sampling (only emitters that rays can hit).
    Rgb sample_hemisphere(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                          TraceCounters& c) const;
    /// Radiance emitted by the surface at `si` toward -ray direction `wo`.
    Rgb emitted(const SurfaceInteraction& si) const;
    /// Whether light that scattered `order` times is written (-o, --light-paths).
    bool accept(int order) const;

    const Scene& scene_;
    const Accel& accel_;
    RenderSettings s_;
    LightSampler light_sampler_;
    float tan_half_h_ = 1.f, tan_half_v_ = 1.f;
    bool has_infinite_lights_ = false;
    int hemisphere_budget_ = 1;
};

} // namespace candela
