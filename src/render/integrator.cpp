#include "candela/render/integrator.h"

#include "candela/bsdf/bsdf.h"
#include "candela/light/light_sampling.h"
#include "candela/sampling/mis.h"
#include "candela/sampling/warp.h"
#include "candela/scene/interaction.h"
#include "candela/util/error.h"

#include <cmath>
#include <string>

namespace candela {

namespace {

/// Russian roulette survival probability never drops below this, so that a path through a
/// dark region is not cut so often that its survivors carry huge weights (fireflies).
constexpr float kRouletteMinSurvival = 0.05f;

} // namespace

Integrator::Integrator(const Scene& scene, const Accel& accel, const RenderSettings& settings)
    : scene_(scene), accel_(accel), s_(settings), light_sampler_(scene) {
    // The estimators divide by the light sample count and the film size.
    if (s_.light_samples < 1)
        throw Error(ErrorKind::Usage, "integrator: light samples per vertex must be >= 1, got " +
                                          std::to_string(s_.light_samples));
    if (scene.camera.lens_radius > 0.f && !(scene.camera.focal_distance > 0.f))
        throw Error(ErrorKind::Usage, "integrator: a thin lens needs a positive focal distance");
    if (s_.width < 1 || s_.height < 1)
        throw Error(ErrorKind::Usage, "integrator: film size " + std::to_string(s_.width) + "x" +
                                          std::to_string(s_.height) + " is empty");
    const float deg = kPi / 180.f;
    tan_half_h_ = std::tan(0.5f * scene.camera.hfov_deg * deg);
    tan_half_v_ = tan_half_h_ * float(s_.height) / float(s_.width);
    for (const Light& l : scene.lights)
        has_infinite_lights_ |= l.is_infinite();
    // CS184: -H takes |lights| x ns_area_light hemisphere samples in total.
    hemisphere_budget_ = std::max<int>(1, int(scene.lights.size()) * s_.light_samples);
}

Ray Integrator::camera_ray(float fx, float fy, Vec2 u_lens) const {
    const Camera& cam = scene_.camera;
    // Camera space: x right, y up, looking down -z; film row 0 is the top of the image.
    Vec3 s((2.f * fx / float(s_.width) - 1.f) * tan_half_h_,
           (1.f - 2.f * fy / float(s_.height)) * tan_half_v_, -1.f);
    Ray r;
    if (cam.lens_radius > 0.f) {
        Vec2 d = square_to_uniform_disk_concentric(u_lens);
        Vec3 p_lens(cam.lens_radius * d.x, cam.lens_radius * d.y, 0.f);
        Vec3 p_focus = s * cam.focal_distance;
        Vec3 dir = p_focus - p_lens;
        r.o = cam.pos + cam.x * p_lens.x + cam.y * p_lens.y;
        r.d = normalize(cam.x * dir.x + cam.y * dir.y + cam.z * dir.z);
    } else {
        r.o = cam.pos;
        r.d = normalize(cam.x * s.x + cam.y * s.y + cam.z * s.z);
    }
    r.tmin = cam.znear;
    r.tmax = cam.zfar;
    return r;
}

bool Integrator::accept(int order) const {
    if (s_.accumulate ? order > s_.max_depth : order != s_.max_depth) return false;
    switch (s_.light_paths) {
    case LightPaths::All:
        return true;
    case LightPaths::Direct:
        return order <= 1;
    case LightPaths::Indirect:
        return order >= 2;
    }
    return true;
}

Rgb Integrator::emitted(const SurfaceInteraction& si) const {
    if (si.light < 0) return Rgb(0.f);
    return light_le(scene_.lights[std::size_t(si.light)], si.ng, si.wo);
}

FilmSample Integrator::estimate(float fx, float fy, Sampler& sampler,
                                TraceCounters& counters) const {
    Vec2 u_lens = scene_.camera.lens_radius > 0.f ? sampler.get_2d() : Vec2(0.5f, 0.5f);
    Ray ray = camera_ray(fx, fy, u_lens);
    switch (s_.integrator) {
    case IntegratorKind::Path:
        return path(ray, sampler, counters);
    case IntegratorKind::Direct:
        return direct(ray, sampler, counters);
    case IntegratorKind::Normals:
        return normals(ray, counters);
    }
    return {};
}

// ---------------------------------------------------------------------------------------------
// Normals: the shading normal of the first hit mapped from [-1, 1] to [0, 1].
// ---------------------------------------------------------------------------------------------
FilmSample Integrator::normals(const Ray& ray, TraceCounters& c) const {
    FilmSample out;
    ++c.rays;
    std::optional<Hit> hit = accel_.intersect(ray);
    if (!hit) return out;
    SurfaceInteraction si = make_interaction(scene_, ray, *hit);
    out.L = (si.ns + Vec3(1.f)) * 0.5f;
    out.normal = si.ns;
    out.depth = si.t;
    out.hit = true;
    out.albedo = bsdf_albedo_hint(scene_.materials[si.material]);
    return out;
}

// ---------------------------------------------------------------------------------------------
// Light sampling
// ---------------------------------------------------------------------------------------------
Rgb Integrator::sample_one_light(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                                 TraceCounters& c) const {
    float u_pick = sampler.get_1d();
    Vec2 u_light = sampler.get_2d();
    auto pick = light_sampler_.sample(u_pick);
    if (!pick) return Rgb(0.f);
    const Light& light = scene_.lights[pick->index];
    std::optional<LightSample> ls = sample_li(scene_, light, si.p, u_light);
    if (!ls || ls->pdf <= 0.f || is_black(ls->L)) return Rgb(0.f);
    Vec3 wo = si.frame.to_local(si.wo), wi = si.frame.to_local(ls->wi);
    Rgb f = bsdf_f(m, wo, wi);
    if (is_black(f)) return Rgb(0.f);
    Ray shadow = std::isfinite(ls->dist) ? spawn_ray_to(si, ls->p_light, ls->p_error, ls->n_light)
                                         : spawn_ray(si, ls->wi);
    ++c.shadow_rays;
    if (accel_.occluded(shadow)) return Rgb(0.f);
    float light_pdf = pick->pmf * ls->pdf;
    // Both factors are positive, but their product underflows for a rarely picked light seen
    // at a tiny solid-angle density; such a sample carries no usable weight.
    if (!(light_pdf > 0.f)) return Rgb(0.f);
    float weight = 1.f;
    if (!ls->is_delta && s_.mis) {
        float pdf_bsdf = bsdf_pdf(m, wo, wi);
        weight = power_heuristic(float(s_.light_samples), light_pdf, 1.f, pdf_bsdf);
    }
    return f * ls->L * (std::abs(wi.z) * weight / light_pdf);
}

Rgb Integrator::sample_all_lights(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                                  TraceCounters& c) const {
    Rgb total(0.f);
    Vec3 wo = si.frame.to_local(si.wo);
    for (const Light& light : scene_.lights) {
        int n = light.is_delta() ? 1 : s_.light_samples;
        Rgb sum(0.f);
        for (int k = 0; k < n; ++k) {
            Vec2 u = sampler.get_2d();
            std::optional<LightSample> ls = sample_li(scene_, light, si.p, u);
            if (!ls || ls->pdf <= 0.f || is_black(ls->L)) continue;
            Vec3 wi = si.frame.to_local(ls->wi);
            Rgb f = bsdf_f(m, wo, wi);
            if (is_black(f)) continue;
            Ray shadow = std::isfinite(ls->dist)
                             ? spawn_ray_to(si, ls->p_light, ls->p_error, ls->n_light)
                             : spawn_ray(si, ls->wi);
            ++c.shadow_rays;
            if (accel_.occluded(shadow)) continue;
            sum += f * ls->L * (std::abs(wi.z) / ls->pdf);
        }
        total += sum / float(n);
    }
    return total;
}

Rgb Integrator::sample_hemisphere(const SurfaceInteraction& si, const Material& m, Sampler& sampler,
                                  TraceCounters& c) const {
    Vec3 wo = si.frame.to_local(si.wo);
    float side = wo.z < 0.f ? -1.f : 1.f; // opaque surfaces are two-sided
    Rgb sum(0.f);
    for (int k = 0; k < hemisphere_budget_; ++k) {
        Vec3 wi = square_to_uniform_hemisphere(sampler.get_2d());
        const float pdf = square_to_uniform_hemisphere_pdf(wi);
        wi.z *= side;
        Rgb f = bsdf_f(m, wo, wi);
        if (is_black(f)) continue;
        Vec3 wi_world = si.frame.to_world(wi);
        Ray r = spawn_ray(si, wi_world);
        ++c.rays;
        std::optional<Hit> hit = accel_.intersect(r);
        Rgb Li(0.f);
        if (hit) {
            SurfaceInteraction next = make_interaction(scene_, r, *hit);
            Li = emitted(next);
        } else if (has_infinite_lights_) {
            Li = escaped_radiance(scene_, wi_world);
        }
        sum += f * Li * (std::abs(wi.z) / pdf);
    }
    return sum / float(hemisphere_budget_);
}

// ---------------------------------------------------------------------------------------------
// Direct lighting: emitters seen directly plus one scattering event, following delta bounces.
// ---------------------------------------------------------------------------------------------
FilmSample Integrator::direct(const Ray& camera, Sampler& sampler, TraceCounters& c) const {
    FilmSample out;
    Rgb L(0.f), beta(1.f);
    Ray ray = camera;
    for (int depth = 0;; ++depth) {
        ++c.rays;
        std::optional<Hit> hit = accel_.intersect(ray);
        if (!hit) {
            if (has_infinite_lights_ && accept(depth)) L += beta * escaped_radiance(scene_, ray.d);
            break;
        }
        SurfaceInteraction si = make_interaction(scene_, ray, *hit);
        const Material& m = scene_.materials[si.material];
        if (depth == 0) {
            out.normal = si.ns;
            out.depth = si.t;
            out.hit = true;
            out.albedo = bsdf_albedo_hint(m);
        }
        if (accept(depth)) L += beta * emitted(si);
        if (depth >= s_.max_depth) break;
        if (m.is_delta()) {
            auto bs = bsdf_sample(m, si.frame.to_local(si.wo), sampler.get_2d(), sampler.get_1d());
            if (!bs || bs->pdf <= 0.f) break;
            beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
            ray = spawn_ray(si, si.frame.to_world(bs->wi));
            continue;
        }
        if (accept(depth + 1))
            L += beta * (s_.hemisphere ? sample_hemisphere(si, m, sampler, c)
                                       : sample_all_lights(si, m, sampler, c));
        break;
    }
    out.L = L;
    return out;
}

// ---------------------------------------------------------------------------------------------
// Path tracing with next-event estimation and multiple importance sampling.
// ---------------------------------------------------------------------------------------------
FilmSample Integrator::path(const Ray& camera, Sampler& sampler, TraceCounters& c) const {
    FilmSample out;
    Rgb L(0.f), beta(1.f);
    Ray ray = camera;
    bool specular_bounce = true; // camera rays and delta bounces count emission fully
    float prev_bsdf_pdf = 0.f;
    Vec3 prev_p;
    float eta_scale = 1.f; // radiance scaling by refraction, undone for roulette
    const bool nee = !s_.hemisphere;

    for (int depth = 0;; ++depth) {
        // --- Find the next vertex ---------------------------------------------------------
        ++c.rays;
        std::optional<Hit> hit = accel_.intersect(ray);
        if (!hit) {
            if (has_infinite_lights_ && accept(depth)) {
                Rgb Le = escaped_radiance(scene_, ray.d);
                float w = 1.f;
                if (!specular_bounce) {
                    if (!nee || !s_.mis)
                        w = 0.f; // the direct estimator already counted it
                    else {
                        float light_pdf = 0.f;
                        for (std::size_t i = 0; i < scene_.lights.size(); ++i)
                            if (scene_.lights[i].is_infinite())
                                light_pdf += light_sampler_.pmf(i) *
                                             escaped_pdf(scene_, scene_.lights[i], ray.d);
                        w = power_heuristic(1.f, prev_bsdf_pdf, float(s_.light_samples), light_pdf);
                    }
                }
                L += beta * Le * w;
            }
            break;
        }
        SurfaceInteraction si = make_interaction(scene_, ray, *hit);
        const Material& m = scene_.materials[si.material];
        if (depth == 0) {
            out.normal = si.ns;
            out.depth = si.t;
            out.hit = true;
            out.albedo = bsdf_albedo_hint(m);
        }

        // --- Emission reached by the previous bounce --------------------------------------
        if (si.light >= 0 && accept(depth)) {
            Rgb Le = emitted(si);
            if (!is_black(Le)) {
                float w = 1.f;
                if (!specular_bounce) {
                    if (!nee || !s_.mis)
                        w = 0.f;
                    else {
                        const Light& light = scene_.lights[std::size_t(si.light)];
                        float light_pdf = light_sampler_.pmf(std::size_t(si.light)) *
                                          pdf_li(scene_, light, prev_p, ray.d, si.p, si.ng);
                        w = power_heuristic(1.f, prev_bsdf_pdf, float(s_.light_samples), light_pdf);
                    }
                }
                L += beta * Le * w;
            }
        }
        if (depth >= s_.max_depth) break;

        // --- Direct light at this vertex (scattering order depth + 1) ---------------------
        Vec3 wo = si.frame.to_local(si.wo);
        if (!m.is_delta() && accept(depth + 1)) {
            if (nee) {
                Rgb Ld(0.f);
                for (int k = 0; k < s_.light_samples; ++k)
                    Ld += sample_one_light(si, m, sampler, c);
                L += beta * Ld / float(s_.light_samples);
            } else {
                L += beta * sample_hemisphere(si, m, sampler, c);
            }
        }

        // --- Sample the BSDF for the next direction ---------------------------------------
        std::optional<BsdfSample> bs = bsdf_sample(m, wo, sampler.get_2d(), sampler.get_1d());
        if (!bs || bs->pdf <= 0.f || is_black(bs->f)) break;
        beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
        specular_bounce = (bs->flags & kSpecular) != 0;
        prev_bsdf_pdf = bs->pdf;
        prev_p = si.p;
        if (bs->flags & kTransmission) eta_scale *= bs->eta * bs->eta;
        ray = spawn_ray(si, si.frame.to_world(bs->wi));

        // --- Russian roulette on throughput ----------------------------------------------
        if (depth + 1 >= s_.rr_min_depth) {
            // Survival proportional to throughput (pbrt-v4 §13.4.2): paths that still carry
            // most of their energy are never cut; the estimate stays unbiased by dividing by
            // the survival probability.
            float carried = max_component(beta * eta_scale);
            if (carried < 1.f) {
                float survive = std::max(kRouletteMinSurvival, carried);
                if (sampler.get_1d() >= survive) break;
                beta /= survive;
            }
        }
    }
    out.L = L;
    return out;
}

} // namespace candela
