#pragma once
// BSDF evaluation and sampling for the closed set of material kinds (scene/material.h).
//
// CONVENTIONS (the one place they are written down):
//  * Local shading frame: the shading normal is +z. `wo` and `wi` are unit vectors in that frame
//    and both point AWAY from the surface (wo towards the viewer / previous vertex).
//  * `f` EXCLUDES the cosine factor: the path throughput update is f * |cos(theta_i)| / pdf with
//    cos(theta_i) = wi.z.
//  * `pdf` is per unit solid angle of wi, except for delta lobes.
//  * Delta lobes (Mirror, and Glass and Refraction below kMinDielectricRoughness, i.e.
//    Material::is_delta()): bsdf_sample returns f such that the path weight is
//    f * |wi.z| / pdf, where pdf is the discrete probability of having chosen that lobe (a mirror
//    has f = reflectance / |wi.z| and pdf = 1). Such samples carry kSpecular. bsdf_f and bsdf_pdf
//    return 0 for delta materials: a delta lobe cannot be hit by a direction chosen elsewhere.
//  * Opaque kinds (Diffuse, Mirror, Microfacet, Emission) are two-sided: the hemisphere of wo is
//    "above"; they reflect only when wo.z * wi.z > 0 (evaluation mirrors z when wo.z < 0).
//  * Dielectrics (Glass, Refraction) take +z as the outside (the side the stored normal points
//    to); the interior has index Material::ior, the exterior is vacuum.
//  * Transmission scales radiance by 1/eta^2, where eta = n(side of wi) / n(side of wo) is the
//    relative index crossed, reported in BsdfSample::eta (1 for reflection). This is the
//    radiance-transport (camera-path) form. Consequence for energy checks: a lossless dielectric
//    conserves power, R + T = 1, not radiance: its one-sided directional albedo
//    integral of f |cos(theta_i)| over wi is R + T / eta^2, and it is R + T = 1 after each
//    transmitted direction's contribution is multiplied by eta^2 (the integrator's roulette
//    does the same with its eta_scale).
//  * Glass: exact dielectric Fresnel F; reflection (probability F, weight reflectance) or
//    transmission (probability 1 - F, weight transmittance / eta^2); total internal reflection
//    gives F = 1. The lobe is chosen with `uc`.
//  * Refraction: transmits everything that is not totally internally reflected, path weight
//    transmittance / eta^2 (no Fresnel loss); total internal reflection -> nullopt (absorbed).
//  * Microfacet: rough conductor, f = F(wi.h) G(wo, wi) D(h) / (4 |wo.z| |wi.z|), Beckmann D,
//    textbook Smith Lambda, height-correlated G, exact per-channel conductor Fresnel at the
//    microfacet normal h. Sampling draws h from the distribution of visible normals of wo,
//    D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z (Heitz & d'Eon 2014, for Beckmann; see
//    microfacet.h), and reflects wo; pdf(wi) = D_wo(h) / (4 wo.h) = G1(wo) D(h) / (4 wo.z)
//    (Walter et al. 2007, eq. 14). Reflections below the horizon fail (nullopt); their
//    probability is exactly the mass missing from the pdf.
//  * Rough dielectric (Glass or Refraction with roughness >= kMinDielectricRoughness; Beckmann
//    alpha = roughness): Walter et al. 2007 with the conductor's D and G. In the frame where wo
//    is up (wo.z > 0; the evaluation mirrors z for wo inside, swapping the indices) with
//    eta = n(wi side) / n(wo side):
//      reflection   (wi.z > 0): h = normalize(wo + wi),
//                   f = reflectance F(wo.h) D G / (4 wo.z wi.z)                      (eq. 20)
//      transmission (wi.z < 0): h = normalize(wo + eta wi), flipped to h.z > 0,
//                   f = transmittance (1 - F) D G |wi.h| wo.h / (wo.z |wi.z| (wo.h + eta wi.h)^2)
//                   (eq. 21 divided through by n(wo side)^2, which is the 1/eta^2 convention)
//    and f = 0 unless wo.h > 0 and wi.h has the sign of wi.z (the chi+ factors of Walter's
//    masking function G1).
//    Sampling draws h from D_wo, then reflects with probability F(wo.h) (chosen with `uc`) or
//    refracts through h; pdf(wi) = F D_wo(h) / (4 wo.h) for reflection (Jacobian eq. 14) and
//    (1 - F) D_wo(h) eta^2 |wi.h| / (wo.h + eta wi.h)^2 for transmission (eq. 17).
//    Rough Refraction is the transmission-only analogue: the transmission lobe above without
//    the factor (1 - F) in f and pdf; a microfacet that totally reflects absorbs (nullopt).
//    Samples carry kGlossy; transmission reports eta as for smooth glass.
//  * Emission: f = 0 and sampling returns nullopt (the path is absorbed).
//  * Shading normals: the functions above know only the shading frame. The renderer evaluates
//    and samples through bsdf_f_folded, bsdf_pdf_folded and bsdf_sample_folded (below), which
//    also take the geometric normal and fold the part of a lobe that would leave on the wrong
//    geometric side back across the geometric plane.
//  * No function returns NaN or Inf; degenerate configurations return 0 / nullopt.
#include "candela/bsdf/fresnel.h"
#include "candela/bsdf/microfacet.h"
#include "candela/math/vec.h"
#include "candela/sampling/warp.h"
#include "candela/scene/material.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

namespace candela {

enum BsdfFlags : std::uint8_t {
    kReflection = 1,
    kTransmission = 2,
    kDiffuse = 4,
    kGlossy = 8,
    kSpecular = 16
};

/// One sampled scattering direction. For non-delta lobes, f == bsdf_f(wo, wi) and pdf ==
/// bsdf_pdf(wo, wi) (solid angle); for delta lobes see the conventions above.
struct BsdfSample {
    Rgb f;
    Vec3 wi;
    float pdf = 0.f;
    std::uint8_t flags = 0;
    float eta = 1.f; ///< relative IOR crossed, n(wi side) / n(wo side); 1 for reflection
    /// The path weight f |wi.z| / pdf. Where it simplifies (Lambertian: the albedo; the smooth
    /// lobes: their reflectance or transmittance / eta^2) it is the simplified value, so that a
    /// path's throughput does not wait for the direction's square root and divisions.
    Rgb weight;
};

namespace bsdf_detail {
/// f |wi.z| / pdf for lobes whose weight does not simplify.
inline Rgb path_weight(const Rgb& f, const Vec3& wi, float pdf) {
    return f * (std::abs(wi.z) / pdf);
}
} // namespace bsdf_detail

/// |cos theta| below which a direction is treated as grazing: divisions by cosines are skipped
/// and the configuration contributes nothing (float cannot resolve the geometry there anyway).
constexpr float kMinCosTheta = 1e-6f;

namespace bsdf_detail {

inline bool same_hemisphere(const Vec3& a, const Vec3& b) {
    return a.z * b.z > 0.f;
}

/// Microfacet f for wo.z > 0, wi.z > 0 (already flipped into the upper hemisphere).
inline Rgb microfacet_f_upper(const Material& m, const Vec3& wo, const Vec3& wi) {
    if (wo.z < kMinCosTheta || wi.z < kMinCosTheta) return Rgb(0.f);
    float alpha = std::max(m.alpha, kMinBeckmannAlpha);
    Vec3 h = normalize(wo + wi);
    float d = beckmann_d(h, alpha);
    if (d == 0.f) return Rgb(0.f);
    float g = beckmann_g(wo, wi, alpha);
    Rgb F = fresnel_conductor(dot(wi, h), m.eta, m.k);
    Rgb f = F * (d * g / (4.f * wo.z * wi.z));
    return is_finite(f) ? f : Rgb(0.f);
}

/// Microfacet pdf (solid angle) for wo.z > 0, wi.z > 0: visible normals, then reflection.
inline float microfacet_pdf_upper(const Material& m, const Vec3& wo, const Vec3& wi) {
    if (wo.z < kMinCosTheta || wi.z < kMinCosTheta) return 0.f;
    float alpha = std::max(m.alpha, kMinBeckmannAlpha);
    Vec3 h = normalize(wo + wi);
    float wo_h = dot(wo, h);
    if (wo_h < kMinCosTheta) return 0.f;
    float p = beckmann_visible_pdf(h, wo, alpha) / (4.f * wo_h);
    return std::isfinite(p) ? p : 0.f;
}

inline Vec3 flip_z(const Vec3& w) {
    return {w.x, w.y, -w.z};
}

/// f and pdf of a rough dielectric (Material::is_rough_dielectric()) for wo, wi in the shading
/// frame; both 0 outside the lobes (see the conventions above).
struct RoughDielectricEval {
    Rgb f{0.f};
    float pdf = 0.f;
};

inline RoughDielectricEval rough_dielectric_eval(const Material& m, Vec3 wo, Vec3 wi) {
    RoughDielectricEval r;
    if (std::abs(wo.z) < kMinCosTheta || std::abs(wi.z) < kMinCosTheta) return r;
    // The frame where wo is up; the indices swap when wo is inside.
    const bool inside = wo.z < 0.f;
    if (inside) {
        wo = flip_z(wo);
        wi = flip_z(wi);
    }
    const float eta = inside ? 1.f / m.ior : m.ior; // n(wi side of a transmission) / n(wo side)
    const float alpha = std::max(m.roughness, kMinBeckmannAlpha);
    const bool reflection = wi.z > 0.f;
    if (reflection && m.kind == BsdfKind::Refraction) return r;
    Vec3 h = reflection ? wo + wi : wo + wi * eta;
    const float h_len = length(h);
    if (!(h_len > 0.f) || !std::isfinite(h_len)) return r;
    h = h / h_len;
    if (h.z < 0.f) h = -h;
    const float wo_h = dot(wo, h), wi_h = dot(wi, h);
    // wo must see the microfacet from its front, wi must leave on the side its z says.
    if (wo_h <= 0.f || wi_h * wi.z <= 0.f) return r;
    const float d = beckmann_d(h, alpha);
    if (!(d > 0.f)) return r;
    const float g = beckmann_g(wo, wi, alpha);
    const float F = fresnel_dielectric(wo_h, eta);
    const float vis = beckmann_visible_pdf(h, wo, alpha);
    if (reflection) {
        r.f = m.reflectance * (F * d * g / (4.f * wo.z * wi.z));
        r.pdf = F * vis / (4.f * wo_h);
    } else {
        // Lobe weight: 1 - F for glass. The transmission-only material transmits through every
        // microfacet that does not reflect totally, and a pair (wo, wi) joined by refraction
        // through h never does, so its weight is 1 (testing F < 1 instead would let float
        // rounding at the critical angle switch the lobe off from one side only).
        const float T = m.kind == BsdfKind::Glass ? 1.f - F : 1.f;
        const float denom = wo_h + eta * wi_h;
        const float denom2 = denom * denom;
        if (!(denom2 > 0.f)) return r;
        const float abs_wi_h = std::abs(wi_h);
        r.f = m.transmittance * (T * d * g * abs_wi_h * wo_h / (wo.z * std::abs(wi.z) * denom2));
        r.pdf = T * vis * eta * eta * abs_wi_h / denom2;
    }
    if (!is_finite(r.f) || !std::isfinite(r.pdf)) return RoughDielectricEval{};
    return r;
}

/// Samples a rough dielectric (see the conventions above).
inline std::optional<BsdfSample> rough_dielectric_sample(const Material& m, const Vec3& wo, Vec2 u,
                                                         float uc) {
    const bool inside = wo.z < 0.f;
    const Vec3 wo_u = inside ? flip_z(wo) : wo;
    const float eta = inside ? 1.f / m.ior : m.ior;
    const float alpha = std::max(m.roughness, kMinBeckmannAlpha);
    const Vec3 h = sample_beckmann_visible(wo_u, alpha, u);
    const float wo_h = dot(wo_u, h);
    if (!(wo_h > 0.f)) return std::nullopt;
    const float F = fresnel_dielectric(wo_h, eta);
    Vec3 wi_u;
    bool reflection;
    if (m.kind == BsdfKind::Glass && uc < F) {
        wi_u = normalize(reflect(wo_u, h));
        if (wi_u.z < kMinCosTheta) return std::nullopt; // below the horizon: absorbed
        reflection = true;
    } else {
        if (!refract(wo_u, h, eta, &wi_u)) return std::nullopt; // total reflection (Refraction)
        wi_u = normalize(wi_u);
        if (wi_u.z > -kMinCosTheta) return std::nullopt; // refracted back above the surface
        reflection = false;
    }
    const Vec3 wi = inside ? flip_z(wi_u) : wi_u;
    // f and pdf from the evaluation, so that they equal bsdf_f and bsdf_pdf for this wi exactly.
    const RoughDielectricEval e = rough_dielectric_eval(m, wo, wi);
    if (!(e.pdf > 0.f)) return std::nullopt;
    const Rgb weight = path_weight(e.f, wi, e.pdf);
    if (reflection) return BsdfSample{e.f, wi, e.pdf, kReflection | kGlossy, 1.f, weight};
    return BsdfSample{e.f, wi, e.pdf, kTransmission | kGlossy, eta, weight};
}

} // namespace bsdf_detail

/// BSDF value f(wo, wi) without the cosine, per unit solid angle of wi. 0 for delta materials
/// (smooth dielectrics included), for Emission, and for configurations outside the lobe.
inline Rgb bsdf_f(const Material& m, const Vec3& wo, const Vec3& wi) {
    using namespace bsdf_detail;
    switch (m.kind) {
    case BsdfKind::Diffuse:
        if (!same_hemisphere(wo, wi)) return Rgb(0.f);
        return m.albedo * kInvPi;
    case BsdfKind::Microfacet:
        if (!same_hemisphere(wo, wi)) return Rgb(0.f);
        return wo.z > 0.f ? microfacet_f_upper(m, wo, wi)
                          : microfacet_f_upper(m, flip_z(wo), flip_z(wi));
    case BsdfKind::Glass:
    case BsdfKind::Refraction:
        if (!m.is_rough_dielectric()) return Rgb(0.f);
        return rough_dielectric_eval(m, wo, wi).f;
    case BsdfKind::Mirror: // a delta lobe: no value per unit solid angle
    case BsdfKind::Emission:
    case BsdfKind::Count:
        return Rgb(0.f);
    }
    return Rgb(0.f); // not reached: every kind returns above
}

/// Density (per unit solid angle of wi) with which bsdf_sample produces wi given wo. 0 for delta
/// materials and Emission.
inline float bsdf_pdf(const Material& m, const Vec3& wo, const Vec3& wi) {
    using namespace bsdf_detail;
    switch (m.kind) {
    case BsdfKind::Diffuse:
        if (!same_hemisphere(wo, wi)) return 0.f;
        return std::abs(wi.z) * kInvPi;
    case BsdfKind::Microfacet:
        if (!same_hemisphere(wo, wi)) return 0.f;
        return wo.z > 0.f ? microfacet_pdf_upper(m, wo, wi)
                          : microfacet_pdf_upper(m, flip_z(wo), flip_z(wi));
    case BsdfKind::Glass:
    case BsdfKind::Refraction:
        if (!m.is_rough_dielectric()) return 0.f;
        return rough_dielectric_eval(m, wo, wi).pdf;
    case BsdfKind::Mirror: // a delta lobe: no density per unit solid angle
    case BsdfKind::Emission:
    case BsdfKind::Count:
        return 0.f;
    }
    return 0.f; // not reached: every kind returns above
}

/// Whether bsdf_sample reads its lobe-choice number `uc` for material m (only Glass, smooth or
/// rough, chooses between reflection and transmission); callers may skip drawing it otherwise.
inline bool bsdf_uses_lobe_choice(const Material& m) {
    return m.kind == BsdfKind::Glass;
}

/// Samples wi given wo with u in [0,1)^2 (direction) and uc in [0,1) (lobe choice). Returns
/// nullopt when the path is absorbed or the sample is invalid (Emission, a microfacet reflection
/// below the horizon or refraction back above it, total internal reflection of a Refraction
/// material, grazing wo). A caller that computed square_to_cosine_hemisphere(u) already (for a
/// whole batch at once, sample_batch.h) passes it as `cosine_u`, which must be that value;
/// the Lambertian lobe then takes it instead of computing it again.
inline std::optional<BsdfSample> bsdf_sample(const Material& m, const Vec3& wo, Vec2 u, float uc,
                                             const Vec3* cosine_u = nullptr) {
    using namespace bsdf_detail;
    if (std::abs(wo.z) < kMinCosTheta) return std::nullopt;
    switch (m.kind) {
    case BsdfKind::Diffuse: {
        Vec3 wi = cosine_u ? *cosine_u : square_to_cosine_hemisphere(u);
        if (wo.z < 0.f) wi = flip_z(wi);
        float pdf = std::abs(wi.z) * kInvPi;
        if (pdf <= 0.f) return std::nullopt;
        return BsdfSample{m.albedo * kInvPi, wi, pdf, kReflection | kDiffuse, 1.f, m.albedo};
    }
    case BsdfKind::Mirror: {
        Vec3 wi(-wo.x, -wo.y, wo.z);
        return BsdfSample{m.reflectance / std::abs(wi.z), wi,  1.f,
                          kReflection | kSpecular,        1.f, m.reflectance};
    }
    case BsdfKind::Microfacet: {
        bool flipped = wo.z < 0.f;
        Vec3 wo_u = flipped ? flip_z(wo) : wo;
        float alpha = std::max(m.alpha, kMinBeckmannAlpha);
        Vec3 h = sample_beckmann_visible(wo_u, alpha, u);
        if (dot(wo_u, h) <= 0.f) return std::nullopt;
        Vec3 wi_u = normalize(reflect(wo_u, h));
        if (wi_u.z < kMinCosTheta) return std::nullopt;
        float pdf = microfacet_pdf_upper(m, wo_u, wi_u);
        if (pdf <= 0.f) return std::nullopt;
        Rgb f = microfacet_f_upper(m, wo_u, wi_u);
        return BsdfSample{f,   flipped ? flip_z(wi_u) : wi_u, pdf, kReflection | kGlossy,
                          1.f, path_weight(f, wi_u, pdf)};
    }
    case BsdfKind::Glass:
    case BsdfKind::Refraction: {
        if (m.is_rough_dielectric()) return rough_dielectric_sample(m, wo, u, uc);
        // A non-positive or non-finite index has no refraction law (the loaders reject it;
        // scenes built in code might not): absorb rather than divide by it.
        if (!(m.ior > 0.f) || !std::isfinite(m.ior)) return std::nullopt;
        bool entering = wo.z > 0.f;
        // eta = n(wi side) / n(wo side) for transmission.
        float eta = entering ? m.ior : 1.f / m.ior;
        Vec3 n(0.f, 0.f, entering ? 1.f : -1.f);
        float F = fresnel_dielectric(wo.z, m.ior);
        if (m.kind == BsdfKind::Glass && (F >= 1.f || uc < F)) {
            Vec3 wi(-wo.x, -wo.y, wo.z);
            return BsdfSample{m.reflectance * (F / std::abs(wi.z)),
                              wi,
                              F,
                              kReflection | kSpecular,
                              1.f,
                              m.reflectance};
        }
        Vec3 wi;
        if (!refract(wo, n, eta, &wi)) return std::nullopt; // TIR (Refraction only)
        if (std::abs(wi.z) < kMinCosTheta) return std::nullopt;
        float pdf = m.kind == BsdfKind::Glass ? 1.f - F : 1.f;
        float weight = m.kind == BsdfKind::Glass ? (1.f - F) : 1.f;
        Rgb f = m.transmittance * (weight / (eta * eta * std::abs(wi.z)));
        return BsdfSample{
            f, wi, pdf, kTransmission | kSpecular, eta, m.transmittance * (1.f / (eta * eta))};
    }
    case BsdfKind::Emission: // reflects nothing: the path is absorbed
    case BsdfKind::Count:
        return std::nullopt;
    }
    return std::nullopt; // not reached: every kind returns above
}

// ---- Shading normals: folding across the geometric surface ---------------------------------
//
// With a shading normal ns (+z of the local frame) that differs from the geometric normal ng, a
// lobe can send a direction to the other geometric side than it says: a reflection below the
// geometric surface or a transmission above it. Such a direction would carry light through the
// surface; instead of dropping it, the *_folded functions mirror it across the geometric plane
// (w -> w - 2 (w.ng) ng), which puts it on the side its lobe says. With s(w) the side test
// lobe_side_agrees and R the mirror, the folded lobe of a non-delta material is
//     f'(wi) |wi.z| = f(wi) |wi.z| + f(R wi) |R wi.z| [R wi disagrees],
//     pdf'(wi)      = pdf(wi)      + pdf(R wi)      [R wi disagrees],
// for wi that agrees, and 0 for wi that does not. R is its own inverse and swaps the two
// geometric sides, so the mirror takes the directions that disagree one to one onto directions
// that agree: f' |cos| integrates to what f |cos| integrates to over the whole sphere (no energy
// lost, none created), and pdf' is the exact density of "sample the lobe, mirror a direction
// that disagrees". Both terms of a sum belong to one lobe (reflection or transmission), so each
// sampled path weight f' |wi.z| / pdf' is a mean of two weights of that lobe and exceeds neither
// (a Lambertian one is its albedo). Where R wi disagrees, |R wi.z| < |wi.z| (ng.z > 0: ng is on
// ns's side), so f' stays bounded. Delta lobes are left alone (the shading-normal bend keeps a
// mirror direction above the surface), and so is a surface whose ns is ng: nothing disagrees.

namespace bsdf_detail {

/// Whether wi leaves on the geometric side (of the plane normal to ng) that its lobe says: the
/// side of wo for a reflection (wo and wi on one side of ns), the other for a transmission.
inline bool lobe_side_agrees(const Vec3& wo, const Vec3& wi, const Vec3& ng) {
    const bool geometric_reflection = dot(wi, ng) * dot(wo, ng) > 0.f;
    const bool shading_reflection = wi.z * wo.z > 0.f;
    return geometric_reflection == shading_reflection;
}

/// w mirrored across the plane through the origin normal to the unit vector n.
inline Vec3 mirror_across(const Vec3& w, const Vec3& n) {
    return w - n * (2.f * dot(w, n));
}

} // namespace bsdf_detail

/// bsdf_f of the folded lobe (above) for the geometric normal ng in the shading frame (unit, on
/// +z's side); with ng null, bsdf_f itself. 0 for a wi that leaves on the other geometric side
/// than its lobe says.
inline Rgb bsdf_f_folded(const Material& m, const Vec3& wo, const Vec3& wi, const Vec3* ng) {
    using namespace bsdf_detail;
    if (!ng) return bsdf_f(m, wo, wi);
    if (!lobe_side_agrees(wo, wi, *ng)) return Rgb(0.f);
    Rgb f = bsdf_f(m, wo, wi);
    const Vec3 r = mirror_across(wi, *ng);
    const float wi_cos = std::abs(wi.z);
    // |r.z| < |wi.z| where r disagrees; the clamp only holds rounding to that.
    if (!lobe_side_agrees(wo, r, *ng) && wi_cos > 0.f)
        f += bsdf_f(m, wo, r) * std::min(1.f, std::abs(r.z) / wi_cos);
    return f;
}

/// bsdf_pdf of the folded lobe: the density with which bsdf_sample_folded returns wi.
inline float bsdf_pdf_folded(const Material& m, const Vec3& wo, const Vec3& wi, const Vec3* ng) {
    using namespace bsdf_detail;
    if (!ng) return bsdf_pdf(m, wo, wi);
    if (!lobe_side_agrees(wo, wi, *ng)) return 0.f;
    float pdf = bsdf_pdf(m, wo, wi);
    const Vec3 r = mirror_across(wi, *ng);
    if (!lobe_side_agrees(wo, r, *ng)) pdf += bsdf_pdf(m, wo, r);
    return pdf;
}

/// bsdf_sample, with a non-delta sample that leaves on the other geometric side than its lobe
/// says mirrored across the geometric plane; f and pdf are the folded lobe's (bsdf_f_folded,
/// bsdf_pdf_folded) at the returned direction. With ng null, or a sample (and its mirror) that
/// needs no folding, bsdf_sample's sample unchanged. A delta sample is returned as drawn.
inline std::optional<BsdfSample> bsdf_sample_folded(const Material& m, const Vec3& wo, Vec2 u,
                                                    float uc, const Vec3* ng,
                                                    const Vec3* cosine_u = nullptr) {
    using namespace bsdf_detail;
    std::optional<BsdfSample> bs = bsdf_sample(m, wo, u, uc, cosine_u);
    if (!bs || !ng || (bs->flags & kSpecular)) return bs;
    const Vec3 r = mirror_across(bs->wi, *ng);
    const bool wi_agrees = lobe_side_agrees(wo, bs->wi, *ng);
    if (wi_agrees && lobe_side_agrees(wo, r, *ng)) return bs; // its density has no second term
    const Vec3 wi = wi_agrees ? bs->wi : r;
    const float pdf = bsdf_pdf_folded(m, wo, wi, ng);
    if (!(pdf > 0.f)) return std::nullopt; // the mirror image disagrees too (rounding at ng)
    bs->wi = wi;
    bs->f = bsdf_f_folded(m, wo, wi, ng);
    bs->pdf = pdf;
    // Lambertian: (a/pi) (|wi.z| + |r.z|) / ((|wi.z| + |r.z|) / pi), the albedo exactly.
    bs->weight = m.kind == BsdfKind::Diffuse ? m.albedo : path_weight(bs->f, wi, pdf);
    return bs;
}

/// A colour for the albedo AOV: diffuse albedo, mirror reflectance, dielectric transmittance,
/// conductor Fresnel reflectance at normal incidence, or the emitted colour scaled to a maximum
/// component of 1 for Emission. Components are in [0, 1] for physically plausible inputs.
inline Rgb bsdf_albedo_hint(const Material& m) {
    switch (m.kind) {
    case BsdfKind::Diffuse:
        return m.albedo;
    case BsdfKind::Mirror:
        return m.reflectance;
    case BsdfKind::Glass:
    case BsdfKind::Refraction:
        return m.transmittance;
    case BsdfKind::Microfacet:
        return fresnel_conductor(1.f, m.eta, m.k);
    case BsdfKind::Emission: {
        float mx = max_component(m.radiance);
        return mx > 0.f && std::isfinite(mx) ? m.radiance / mx : Rgb(0.f);
    }
    case BsdfKind::Count:
        return Rgb(0.f);
    }
    return Rgb(0.f); // not reached: every kind returns above
}

} // namespace candela
