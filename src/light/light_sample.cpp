// Sampling and evaluation of every light kind: sample_li, pdf_li, emitted radiance and power.
#include "candela/light/light_sample.h"

#include "candela/math/float_error.h"
#include "candela/math/frame.h"
#include "candela/math/sincos.h"
#include "candela/sampling/warp.h"
#include "candela/scene/envmap.h"
#include "candela/scene/interaction.h" // ellipsoid_point
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace candela {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
/// A reference point this close to a sphere light's surface (relative to r^2) is treated as on
/// it. Shading points on the emitter itself (a glowing sphere seen from inside) carry float
/// error of order 1e-7 r; cone sampling from such a point would cover only a sliver of what it
/// sees, while area sampling of the whole sphere is unbiased from both sides of the surface.
constexpr float kSphereSurfaceRel = 1e-4f;

/// sin^2(1.5 degrees). Below this half-angle the cone-sampling formulas 1 - cos(theta_max) and
/// 1 - cos^2(theta) lose most of their float precision to cancellation, so sphere sampling
/// switches to their second-order Taylor forms (as pbrt-v4 does).
constexpr float kSmallConeSin2 = 0.00068523f;

inline float safe_sqrt(float x) {
    return std::sqrt(std::max(x, 0.f));
}

/// 1 - cos(theta_max) of the cone subtended by a sphere of squared radius r2 seen from squared
/// distance d2 > r2, using the Taylor form for tiny cones. Also returns sin^2(theta_max).
inline float one_minus_cos_theta_max(float r2, float d2, float& sin2_max) {
    sin2_max = r2 / d2;
    if (sin2_max < kSmallConeSin2) return 0.5f * sin2_max;
    return 1.f - safe_sqrt(1.f - sin2_max);
}

/// Error bound of a point c + n r computed from a (nearly) unit n: the bound make_interaction
/// uses for re-projected sphere hits (pbrt-v4 eq. 6.29, one rounding more for the reciprocal), so
/// both ends of a shadow ray between two points of one sphere carry the same margin.
inline Vec3 sphere_point_error(const Vec3& n_times_r, const Vec3& p) {
    return vabs(n_times_r) * float_gamma(6) + vabs(p) * float_gamma(1);
}

/// Solid-angle density dist2 / (area |cos|) of an area-sampled point, 0 where it is undefined
/// or overflows (exactly the cases area_sample rejects).
inline float area_pdf(float dist2, float area, float abs_cos) {
    if (!(area > 0.f) || !(abs_cos > 0.f)) return 0.f;
    float pdf = dist2 / (area * abs_cos);
    return std::isfinite(pdf) ? pdf : 0.f;
}

/// Spot falloff factor cos^falloff_exp for a direction at cosine cos_theta from the axis
/// (caller checks the cone). A zero exponent means no falloff, even on the cone's equator.
inline float spot_falloff(const Light& light, float cos_theta) {
    if (light.falloff_exp == 0.f) return 1.f;
    return std::pow(std::max(cos_theta, 0.f), light.falloff_exp);
}

const EnvMap& env_of(const Scene& scene) {
    CANDELA_CHECK(scene.env != nullptr,
                  "environment light without an environment map in scene " + scene.source);
    return *scene.env;
}

/// Outward unit normal of the point where a direction drawn uniformly from the cone subtended
/// by a sphere (squared radius r2, centre c) at ref = c + to_ref (|to_ref|^2 = d2 > r2) first
/// meets it; *one_minus_cos_max receives 1 - cos(theta_max) of the cone (its solid angle over
/// 2 pi). False when the cone is too small for float.
bool sample_sphere_cone(const Vec3& to_ref, float r2, float d2, Vec2 u, Vec3* n_out,
                        float* one_minus_cos_max) {
    float sin2_max = 0.f;
    *one_minus_cos_max = one_minus_cos_theta_max(r2, d2, sin2_max);
    const float sin_max = std::sqrt(sin2_max);
    float cos_theta, sin2_theta;
    if (sin2_max < kSmallConeSin2) {
        sin2_theta = sin2_max * u.x;
        cos_theta = std::sqrt(1.f - sin2_theta);
    } else {
        cos_theta = 1.f - *one_minus_cos_max * u.x;
        sin2_theta = 1.f - cos_theta * cos_theta;
    }
    // Angle alpha at the centre between the axis toward ref_p and the point where the sampled
    // ray first meets the sphere (law of sines on triangle ref-centre-point, pbrt-v4 6.2.4);
    // computing the point from alpha avoids the cancellation of a ray-sphere intersection.
    float cos_alpha =
        sin2_theta / sin_max + cos_theta * safe_sqrt(1.f - sin2_theta / (sin_max * sin_max));
    float sin_alpha = safe_sqrt(1.f - cos_alpha * cos_alpha);
    float sin_phi, cos_phi;
    sincos_turns(u.y, &sin_phi, &cos_phi); // phi = 2 pi u.y
    const float dc = std::sqrt(d2);
    Frame frame(to_ref / dc);
    // Outward normal; renormalised so that the callers' error bounds (which assume a unit n,
    // as for re-projected hits) hold after the frame change.
    *n_out = normalize(frame.to_world(Vec3(sin_alpha * cos_phi, sin_alpha * sin_phi, cos_alpha)));
    return *one_minus_cos_max > 0.f;
}

/// The cone pdf 1 / (2 pi (1 - cos theta_max)), 0 where it overflows.
inline float cone_pdf(float one_minus_cos_max) {
    if (!(one_minus_cos_max > 0.f)) return 0.f;
    const float pdf = 1.f / (2.f * kPi * one_minus_cos_max);
    return std::isfinite(pdf) ? pdf : 0.f;
}

std::optional<LightSample> sample_sphere(const Light& light, const Vec3& ref_p, Vec2 u) {
    const Vec3 c = light.p;
    const float r = light.radius;
    const float r2 = r * r;
    // A sphere of zero (or underflowing) squared radius has no area to sample, and the cone
    // formulas below divide by sin(theta_max).
    if (!(r2 > 0.f)) return std::nullopt;
    const Vec3 to_ref = ref_p - c;
    const float d2 = length_squared(to_ref);
    if (d2 <= r2 * (1.f + kSphereSurfaceRel)) {
        // Inside (or on) the sphere: uniform area sampling of the whole surface.
        Vec3 n = square_to_uniform_sphere(u);
        const Vec3 p = c + n * r;
        return light_detail::area_sample(light.L, ref_p, p, sphere_point_error(n * r, p), n,
                                         4.f * kPi * r2);
    }
    // Outside: uniform sampling of the cone of directions subtended by the sphere.
    Vec3 n;
    float one_minus_cos_max = 0.f;
    if (!sample_sphere_cone(to_ref, r2, d2, u, &n, &one_minus_cos_max)) return std::nullopt;
    Vec3 p = c + n * r;
    Vec3 d = p - ref_p;
    float dist = length(d);
    if (!(dist > 0.f)) return std::nullopt;
    LightSample s;
    s.L = light.L;
    s.wi = d * (1.f / dist);
    s.dist = dist;
    s.pdf = cone_pdf(one_minus_cos_max);
    if (!(s.pdf > 0.f)) return std::nullopt; // cone too small for float
    s.p_light = p;
    s.p_error = sphere_point_error(n * r, p);
    s.n_light = n;
    s.is_delta = false;
    return s;
}

// ---- Ellipsoid lights ------------------------------------------------------------------------
// An ellipsoid is the unit sphere under p = c + A x (A = Sphere::to_world, B = A^-1 =
// Sphere::to_object). Its light is sampled in object space, where it is the unit sphere and the
// reference point is o' = B (ref - c): from outside by the cone the unit sphere subtends at o',
// from inside (or on it) uniformly by object-space area. Both densities are carried to world
// space exactly:
//  * A direction w' in object space is the world direction w = A w' / |A w'|; the map has
//    Jacobian dw'/dw = |det B| / |B w|^3 (the linear-transform rule of Heitz et al., "Real-Time
//    Polygonal-Light Shading with Linearly Transformed Cosines", 2016, eq. 3), so the cone's
//    constant pdf becomes cone_pdf |det B| / |B w|^3 per world steradian.
//  * A uniform unit-sphere point x (area density 1 / (4 pi)) maps to the point c + A x of
//    area density 1 / (4 pi |det A| |B^T x|) (Nanson's formula: an area element scales by
//    |det A| |A^-T n|); dist^2 / |cos| converts it to solid angle.
// The cone covers exactly the directions from ref that hit the ellipsoid (a linear map keeps
// lines and the order of their intersections), and each sampled point is the first hit along
// its direction, so sample_li and pdf_li agree with what BSDF rays find.

/// The scene's sphere record of a Sphere light when it is an ellipsoid, else nullptr (lights
/// built in code may name no sphere record; they are spheres of Light::p and Light::radius).
const Sphere* ellipsoid_of(const Scene& scene, const Light& light) {
    if (light.geom_id >= scene.spheres.size()) return nullptr;
    const Sphere& s = scene.spheres[light.geom_id];
    return s.is_ellipsoid() ? &s : nullptr;
}

/// World solid-angle pdf of the object-space cone sampling from outside: cone_pdf times the
/// direction Jacobian |det B| / |B w|^3.
float ellipsoid_cone_pdf(const Sphere& e, float one_minus_cos_max, const Vec3& wi) {
    const float bw = length(e.to_object * wi);
    const float pdf = cone_pdf(one_minus_cos_max) * std::abs(e.to_object.det()) / (bw * bw * bw);
    return std::isfinite(pdf) && pdf > 0.f ? pdf : 0.f;
}

/// 1 / (world area density) of a uniform object-space point x on the unit sphere.
inline float ellipsoid_inverse_area_density(const Sphere& e, const Vec3& x_unit) {
    return 4.f * kPi * std::abs(e.to_world.det()) * length(e.to_object.transpose_mul(x_unit));
}

std::optional<LightSample> sample_ellipsoid(const Sphere& e, const Light& light, const Vec3& ref_p,
                                            Vec2 u) {
    const Vec3 o = e.to_object * (ref_p - e.center);
    const float d2 = length_squared(o);
    if (d2 <= 1.f + kSphereSurfaceRel) {
        const Vec3 x = square_to_uniform_sphere(u);
        const EllipsoidPoint q = ellipsoid_point(e, x, x);
        return light_detail::area_sample(light.L, ref_p, q.p, q.p_error, q.n,
                                         ellipsoid_inverse_area_density(e, x));
    }
    Vec3 x;
    float one_minus_cos_max = 0.f;
    if (!sample_sphere_cone(o, 1.f, d2, u, &x, &one_minus_cos_max)) return std::nullopt;
    const EllipsoidPoint q = ellipsoid_point(e, x, x);
    const Vec3 d = q.p - ref_p;
    const float dist = length(d);
    if (!(dist > 0.f) || !std::isfinite(dist)) return std::nullopt;
    LightSample s;
    s.L = light.L;
    s.wi = d * (1.f / dist);
    s.dist = dist;
    s.pdf = ellipsoid_cone_pdf(e, one_minus_cos_max, s.wi);
    if (!(s.pdf > 0.f)) return std::nullopt;
    s.p_light = q.p;
    s.p_error = q.p_error;
    s.n_light = q.n;
    s.is_delta = false;
    return s;
}

float pdf_ellipsoid(const Sphere& e, const Vec3& ref_p, const Vec3& wi, const Vec3& p_light,
                    const Vec3& n_light) {
    const Vec3 o = e.to_object * (ref_p - e.center);
    const float d2 = length_squared(o);
    if (d2 <= 1.f + kSphereSurfaceRel) {
        const float n_len = length(n_light);
        const Vec3 x = e.to_object * (p_light - e.center);
        const float x_len = length(x);
        if (!(n_len > 0.f) || !(x_len > 0.f)) return 0.f;
        const float abs_cos = std::abs(dot(n_light, wi)) / n_len;
        return area_pdf(length_squared(p_light - ref_p),
                        ellipsoid_inverse_area_density(e, x / x_len), abs_cos);
    }
    float sin2_max = 0.f;
    const float one_minus_cos_max = one_minus_cos_theta_max(1.f, d2, sin2_max);
    return ellipsoid_cone_pdf(e, one_minus_cos_max, wi);
}

std::optional<LightSample> sample_mesh(const Scene& scene, const Light& light, const Vec3& ref_p,
                                       Bits2 u) {
    if (light.tri_choice.size() == 0) return std::nullopt;
    const Mesh& mesh = scene.meshes[light.geom_id];
    // Triangle k with probability tri_choice.pmf(k) exactly, from all 32 bits of u.x; the part
    // of u.x inside k's range is the first coordinate of the point on it.
    float u0 = 0.f;
    const std::size_t k = light.tri_choice.sample(u.x, &u0);
    const float area_per_pmf = light.tri_area_per_pmf[k];
    if (!(area_per_pmf > 0.f)) return std::nullopt;
    const Vec3& p0 = mesh.positions[mesh.indices[3 * k]];
    const Vec3& p1 = mesh.positions[mesh.indices[3 * k + 1]];
    const Vec3& p2 = mesh.positions[mesh.indices[3 * k + 2]];
    Vec3 b = square_to_uniform_triangle(Vec2(u0, bits_to_unit_float(u.y)));
    Vec3 p = p0 * b.x + p1 * b.y + p2 * b.z;
    // Barycentric interpolation: three products and two sums (pbrt-v4 Triangle::Sample).
    Vec3 p_error = (vabs(p0 * b.x) + vabs(p1 * b.y) + vabs(p2 * b.z)) * float_gamma(6);
    Vec3 ng = cross(p1 - p0, p2 - p0);
    float len = length(ng);
    if (!(len > 0.f)) return std::nullopt;
    // Area density on triangle k: pmf(k) / area(k).
    std::optional<LightSample> s =
        light_detail::area_sample(light.L, ref_p, p, p_error, ng / len, area_per_pmf);
    if (s) s->prim = std::uint32_t(k);
    return s;
}

} // namespace

std::optional<LightSample> sample_li(const Scene& scene, const Light& light, const Vec3& ref_p,
                                     Bits2 u_bits) {
    if (light.kind == LightKind::Mesh) return sample_mesh(scene, light, ref_p, u_bits);
    const Vec2 u = bits_to_unit_point(u_bits);
    switch (light.kind) {
    case LightKind::Area:
        return sample_rect(light, ref_p, u);
    case LightKind::Mesh:
        break; // above
    case LightKind::Sphere:
        if (const Sphere* e = ellipsoid_of(scene, light))
            return sample_ellipsoid(*e, light, ref_p, u);
        return sample_sphere(light, ref_p, u);
    case LightKind::Point:
    case LightKind::Spot: {
        Vec3 d = light.p - ref_p;
        float dist2 = length_squared(d);
        // At the light: no direction; ~1e19 away: the squared distance overflows.
        if (!(dist2 > 0.f) || !std::isfinite(dist2)) return std::nullopt;
        float dist = std::sqrt(dist2);
        Vec3 wi = d * (1.f / dist);
        float scale = 1.f;
        if (light.kind == LightKind::Spot) {
            float cos_theta = -dot(wi, light.n); // angle of the emitted direction to the axis
            if (cos_theta < light.cos_total) return std::nullopt;
            scale = spot_falloff(light, cos_theta);
            if (!(scale > 0.f)) return std::nullopt;
        }
        LightSample s;
        s.L = light.L * (scale / dist2);
        // A reference point within ~1e-19 of the light: the inverse-square factor overflows.
        // The irradiance there is unbounded; contributing nothing is the only finite answer.
        if (!is_finite(s.L)) return std::nullopt;
        s.wi = wi;
        s.dist = dist;
        s.pdf = 1.f;
        s.p_light = light.p;
        s.n_light = -wi;
        s.is_delta = true;
        return s;
    }
    case LightKind::Directional: {
        LightSample s;
        s.L = light.L;
        s.wi = light.n;
        s.dist = kInf;
        s.pdf = 1.f;
        s.p_light = ref_p;
        s.n_light = -light.n;
        s.is_delta = true;
        return s;
    }
    case LightKind::Ambient: {
        // Uniform on the open upper hemisphere around +Y: cos(theta) = 1 - u.x is in (0, 1].
        float cos_theta = 1.f - u.x;
        float sin_theta = safe_sqrt(1.f - cos_theta * cos_theta);
        float sin_phi, cos_phi;
        sincos_turns(u.y, &sin_phi, &cos_phi); // phi = 2 pi u.y
        LightSample s;
        s.L = light.L;
        s.wi = Vec3(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi);
        s.dist = kInf;
        s.pdf = kInv2Pi;
        s.p_light = ref_p;
        s.n_light = -s.wi;
        s.is_delta = false;
        return s;
    }
    case LightKind::Environment: {
        std::optional<EnvSample> es = env_of(scene).sample(u_bits);
        if (!es || is_black(es->L)) return std::nullopt;
        LightSample s;
        s.L = es->L;
        s.wi = es->wi;
        s.dist = kInf;
        s.pdf = es->pdf;
        s.p_light = ref_p;
        s.n_light = -es->wi;
        s.is_delta = false;
        return s;
    }
    case LightKind::Count:
        break;
    }
    return std::nullopt;
}

bool light_found_by_rays(const Scene& scene, std::size_t index) {
    const Light& light = scene.lights[index];
    if (light.is_delta()) return false;
    if (light.kind != LightKind::Area) return true;
    // The panel mesh names its light back (SceneEditor::add_rect_panel, check_scene).
    return light.geom_id < scene.meshes.size() &&
           scene.meshes[light.geom_id].light == std::int32_t(index);
}

float pdf_li(const Scene& scene, const Light& light, const Vec3& ref_p, const Vec3& wi,
             const Vec3& p_light, const Vec3& n_light, std::uint32_t prim) {
    switch (light.kind) {
    case LightKind::Area:
    case LightKind::Mesh: {
        if (light.kind == LightKind::Area) {
            // Directions arriving from the back side are never sampled (one-sided light).
            if (!(dot(wi, light.n) < 0.f)) return 0.f;
            if (!(dot(ref_p - light.p, light.n) > 0.f)) return 0.f;
        }
        // A mesh triangle's area density is its choice probability over its area.
        float area = light.kind == LightKind::Area          ? light_detail::rect_area(light)
                     : prim < light.tri_area_per_pmf.size() ? light.tri_area_per_pmf[prim]
                                                            : 0.f;
        const float n_len = length(n_light);
        if (!(n_len > 0.f)) return 0.f; // no normal: no area-to-solid-angle conversion
        float abs_cos = std::abs(dot(n_light, wi)) / n_len;
        return area_pdf(length_squared(p_light - ref_p), area, abs_cos);
    }
    case LightKind::Sphere: {
        if (const Sphere* e = ellipsoid_of(scene, light))
            return pdf_ellipsoid(*e, ref_p, wi, p_light, n_light);
        const float r2 = light.radius * light.radius;
        const float d2 = length_squared(ref_p - light.p);
        if (!(r2 > 0.f)) return 0.f; // sample_sphere never samples a point-like sphere
        if (d2 <= r2 * (1.f + kSphereSurfaceRel)) {
            const float n_len = length(n_light);
            if (!(n_len > 0.f)) return 0.f;
            float abs_cos = std::abs(dot(n_light, wi)) / n_len;
            return area_pdf(length_squared(p_light - ref_p), 4.f * kPi * r2, abs_cos);
        }
        float sin2_max = 0.f;
        float one_minus_cos_max = one_minus_cos_theta_max(r2, d2, sin2_max);
        if (!(one_minus_cos_max > 0.f)) return 0.f;
        float pdf = 1.f / (2.f * kPi * one_minus_cos_max);
        return std::isfinite(pdf) ? pdf : 0.f;
    }
    case LightKind::Ambient:
    case LightKind::Environment:
        return escaped_pdf(scene, light, wi);
    case LightKind::Point:
    case LightKind::Spot:
    case LightKind::Directional:
    case LightKind::Count:
        break;
    }
    return 0.f;
}

Rgb light_le(const Light& light, const Vec3& n_light, const Vec3& w_from_light) {
    switch (light.kind) {
    case LightKind::Area:
        // The Area's own emitting normal decides the side: its stand-in mesh may be wound
        // either way, so n_light is not trusted for orientation.
        (void)n_light;
        return dot(light.n, w_from_light) > 0.f ? light.L : Rgb(0.f);
    case LightKind::Mesh:
    case LightKind::Sphere:
        return light.L;
    default:
        return Rgb(0.f);
    }
}

Rgb escaped_le(const Scene& scene, const Light& light, const Vec3& dir) {
    if (light.kind == LightKind::Ambient) return dir.y > 0.f ? light.L : Rgb(0.f);
    if (light.kind == LightKind::Environment) return env_of(scene).eval(dir);
    return Rgb(0.f);
}

Rgb escaped_le(const Scene& scene, const Light& light, const Vec3& dir, float* pdf) {
    if (light.kind == LightKind::Environment) return env_of(scene).eval(dir, pdf);
    *pdf = escaped_pdf(scene, light, dir);
    return escaped_le(scene, light, dir);
}

Rgb escaped_radiance(const Scene& scene, const Vec3& dir) {
    Rgb L(0.f);
    for (const Light& light : scene.lights)
        if (light.is_infinite() && !light.is_delta()) L += escaped_le(scene, light, dir);
    return L;
}

float escaped_pdf(const Scene& scene, const Light& light, const Vec3& dir) {
    if (light.kind == LightKind::Ambient) return dir.y > 0.f ? kInv2Pi : 0.f;
    if (light.kind == LightKind::Environment) return env_of(scene).pdf(dir);
    return 0.f;
}

float light_power(const Scene& scene, const Light& light) {
    const float lum = luminance(light.L);
    switch (light.kind) {
    case LightKind::Area:
        return lum * kPi * light_detail::rect_area(light); // one-sided Lambertian emitter
    case LightKind::Mesh:
        return lum * 2.f * kPi * light.area;
    case LightKind::Sphere:
        // An ellipsoid's area has no closed form; the builder integrated it (sphere_area).
        if (ellipsoid_of(scene, light)) return lum * kPi * light.area;
        return lum * kPi * 4.f * kPi * light.radius * light.radius;
    case LightKind::Point:
        return lum * 4.f * kPi;
    case LightKind::Spot: {
        // Integral of cos^e over the cone cos(theta) >= cos_total, in steradians.
        float e = light.falloff_exp;
        if (e == 0.f) return lum * 2.f * kPi * (1.f - light.cos_total);
        float c0 = std::max(light.cos_total, 0.f);
        return lum * 2.f * kPi * (1.f - std::pow(c0, e + 1.f)) / (e + 1.f);
    }
    // Infinite lights: the power through a disc of unit area facing them, independent of the
    // scene's size (a ground plane 100 km wide must not outweigh a lamp in a room).
    case LightKind::Directional:
        return lum;
    case LightKind::Ambient:
        return lum * 2.f * kPi;
    case LightKind::Environment:
        return env_of(scene).luminance_integral();
    case LightKind::Count:
        break;
    }
    return 0.f;
}

InfiniteIrradiance infinite_irradiance_model(const Scene& scene, const Light& light) {
    InfiniteIrradiance m;
    m.kind = light.kind;
    switch (light.kind) {
    case LightKind::Directional:
        m.lum = luminance(light.L);
        m.dir = light.n;
        return m;
    case LightKind::Ambient:
        m.lum = luminance(light.L);
        return m;
    case LightKind::Environment:
        m.sh = env_of(scene).irradiance_sh();
        return m;
    default:
        break;
    }
    throw Error(ErrorKind::Internal, std::string("infinite_irradiance_model: a ") +
                                         light_kind_name(light.kind) + " light is not infinite");
}

} // namespace candela
