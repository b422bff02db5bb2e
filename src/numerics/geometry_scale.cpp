// Self-intersection and light leaking across scales and translations: ray-level counts for
// several ray-origin offset methods, and path-traced renders compared with the unit scene.
#include "candela/accel/accel.h"
#include "candela/accel/triangle.h"
#include "candela/light/light_sample.h"
#include "candela/numerics/geometry_cases.h"
#include "candela/render/film.h"
#include "candela/render/renderer.h"
#include "candela/scene/interaction.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene.h"
#include "candela/scene/scene_editor.h"
#include "geometry_support.h"

#include <fmt/format.h>
#include <memory>

namespace candela::numerics {

using namespace detail;

namespace {

/// The naive alternative to offset_ray_origin (scene/interaction.h), for the comparisons here: p
/// moved by the fixed distance `eps` (world units) along ng to the side of w, with no error
/// analysis. It fails both ways: at large coordinates p + eps rounds back onto the surface
/// (re-hits, acne) and in small scenes eps can exceed the thickness of an occluder (light leaks).
Vec3 offset_ray_origin_fixed(const Vec3& p, const Vec3& ng, const Vec3& w, float eps) {
    return dot(w, ng) < 0.f ? p - ng * eps : p + ng * eps;
}

const char* const kSelfGroup = "self-intersection and leaks";
const char* const kRenderGroup = "scale invariance of renders";

// Local geometry of the wall scene (see make_wall_scene).
constexpr float kFloorHalf = 1.5f;
constexpr float kWallHalfThickness = 0.05f;
constexpr float kWallHeight = 0.5f;
/// The wall reaches this far below the floor, so the floor passes through it (no crack).
constexpr float kWallDepth = 0.02f;
constexpr float kLightHeight = 0.3f;
constexpr float kLightX = 0.5f;
constexpr float kLightSize = 0.3f;
constexpr float kLightRadiance = 10.f;
/// The fixed offset of the naive method, in world units (a typical hard-coded epsilon).
constexpr float kFixedEpsilon = 1e-4f;
/// Shortest distance from any measured surface point to the light, local units: floor points
/// at x >= 0.2 and wall points at x = -0.05 are at least this far from the light's plane.
constexpr float kMinLightDistance = 0.3f;

/// The fixed rotation of the scene: 0.5 rad about (1, 2, 3) / |(1, 2, 3)|.
struct Placement {
    double r[3][3];
    Vec3d t;
    double s;
    Placement(float scale, float translation) : t(translation, translation, translation), s(scale) {
        const Vec3d a = normalize(Vec3d(1.0, 2.0, 3.0));
        const double c = std::cos(0.5), sn = std::sin(0.5), k = 1.0 - c;
        r[0][0] = c + a.x * a.x * k;
        r[0][1] = a.x * a.y * k - a.z * sn;
        r[0][2] = a.x * a.z * k + a.y * sn;
        r[1][0] = a.y * a.x * k + a.z * sn;
        r[1][1] = c + a.y * a.y * k;
        r[1][2] = a.y * a.z * k - a.x * sn;
        r[2][0] = a.z * a.x * k - a.y * sn;
        r[2][1] = a.z * a.y * k + a.x * sn;
        r[2][2] = c + a.z * a.z * k;
    }
    Vec3d rotate(const Vec3& v) const {
        const Vec3d d(v);
        return Vec3d(r[0][0] * d.x + r[0][1] * d.y + r[0][2] * d.z,
                     r[1][0] * d.x + r[1][1] * d.y + r[1][2] * d.z,
                     r[2][0] * d.x + r[2][1] * d.y + r[2][2] * d.z);
    }
    /// A point: computed in double, rounded once.
    Vec3 point(const Vec3& p) const { return Vec3(t + rotate(p) * s); }
    /// A direction (unit stays unit).
    Vec3 dir(const Vec3& v) const { return Vec3(rotate(v)); }
    /// A vector scaled with the scene.
    Vec3 vec(const Vec3& v) const { return Vec3(rotate(v) * s); }
};

/// Mesh ids of the wall scene.
constexpr std::uint32_t kFloorId = 0, kWallId = 1;

/// The largest float coordinate magnitude of the transformed scene.
float max_coordinate(const Scene& s) {
    const Vec3 lo = vabs(s.bounds.lo), hi = vabs(s.bounds.hi);
    return std::max({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
}

/// Where the robust offset is expected to hold: the offset of a surface point is at most
/// sqrt(3) gamma(7) max|coordinate| (interaction.h), and must stay below the wall's thickness
/// so that an origin cannot cross it (an origin left inside the closed wall still sees it).
bool offset_predicted_safe(const Scene& s, float scale) {
    const float offset = std::sqrt(3.f) * float_gamma(7) * max_coordinate(s);
    return offset < 2.f * kWallHalfThickness * scale;
}

/// Shadow rays built with a zero error bound for the light point stop kShadowEpsilon short of
/// it, which covers the light point's own rounding (about 3 ulps of its coordinates per axis)
/// only while that is below kShadowEpsilon times the shortest light distance.
bool light_end_predicted_safe(const Scene& s, float scale) {
    const float light_point_error = std::sqrt(3.f) * float_gamma(3) * max_coordinate(s);
    return light_point_error < kShadowEpsilon * kMinLightDistance * scale;
}

enum class OffsetMethod { Renderer, ZeroLightError, Fixed, None };
const char* method_name(OffsetMethod m) {
    switch (m) {
    case OffsetMethod::Renderer:
        return "robust offsets, light sample with its error bound (as the renderer)";
    case OffsetMethod::ZeroLightError:
        return "robust offsets, light point error taken as 0";
    case OffsetMethod::Fixed:
        return "fixed offset 1e-4 along the normal";
    case OffsetMethod::None:
        return "no offset";
    }
    return "?";
}

/// A shadow ray from si to the light point pl (normal nl) built by `method`; a hit means
/// occluded.
Ray shadow_ray(OffsetMethod method, const SurfaceInteraction& si, const Vec3& pl,
               const Vec3& pl_error, const Vec3& nl) {
    switch (method) {
    case OffsetMethod::Renderer:
        return spawn_ray_to(si, pl, pl_error, nl);
    case OffsetMethod::ZeroLightError:
        return spawn_ray_to(si, pl, Vec3(0.f), nl);
    case OffsetMethod::Fixed: {
        const Vec3 o = offset_ray_origin_fixed(si.p, si.ng, pl - si.p, kFixedEpsilon);
        const Vec3 d = pl - o;
        const float dist = length(d);
        return Ray{o, d / dist, 0.f, dist - kFixedEpsilon};
    }
    case OffsetMethod::None: {
        const Vec3 d = pl - si.p;
        const float dist = length(d);
        return Ray{si.p, d / dist, 0.f, dist * (1.f - kShadowEpsilon)};
    }
    }
    return Ray{};
}

Ray bounce_ray(OffsetMethod method, const SurfaceInteraction& si, const Vec3& w) {
    switch (method) {
    case OffsetMethod::Renderer:
    case OffsetMethod::ZeroLightError:
        return spawn_ray(si, w);
    case OffsetMethod::Fixed:
        return Ray{offset_ray_origin_fixed(si.p, si.ng, w, kFixedEpsilon), w, 0.f, kInf};
    case OffsetMethod::None:
        return Ray{si.p, w, 0.f, kInf};
    }
    return Ray{};
}

struct Config {
    float scale, translation;
};
std::string config_name(const Config& c) {
    if (c.translation == 0.f) return fmt::format("scale {:g} at the origin", c.scale);
    return fmt::format("scale {:g} translated {:g}", c.scale, c.translation);
}
const Config kConfigs[] = {{1e-4f, 0.f}, {1e-2f, 0.f}, {1.f, 0.f},  {1e2f, 0.f}, {1e4f, 0.f},
                           {1.f, 1e1f},  {1.f, 1e2f},  {1.f, 1e3f}, {1.f, 1e5f}, {1.f, 1e6f}};

} // namespace

Scene make_wall_scene(float s, float t) {
    const Placement P(s, t);
    Scene scene;
    SceneEditor editor(scene);
    Material diffuse;
    diffuse.kind = BsdfKind::Diffuse;
    diffuse.albedo = Rgb(0.6f);
    diffuse.name = "wall_scene_diffuse";
    editor.add_material(diffuse);
    {
        Mesh floor;
        floor.name = "floor";
        const float h = kFloorHalf;
        for (const Vec3& p : {Vec3(-h, 0, -h), Vec3(-h, 0, h), Vec3(h, 0, h), Vec3(h, 0, -h)}) {
            floor.positions.push_back(P.point(p));
            floor.normals.push_back(P.dir(Vec3(0, 1, 0)));
        }
        floor.indices = {0, 1, 2, 0, 2, 3};
        editor.add_mesh(std::move(floor));
    }
    {
        Scene tmp;
        add_grid_cube_mesh(tmp, Vec3(-kWallHalfThickness, -kWallDepth, -kFloorHalf),
                           Vec3(kWallHalfThickness, kWallHeight, kFloorHalf), 1);
        Mesh wall = std::move(tmp.meshes[0]);
        wall.name = "wall";
        for (Vec3& p : wall.positions)
            p = P.point(p);
        // Flat faces: the geometric normal is the shading normal.
        wall.normals.clear();
        wall.material = 0;
        editor.add_mesh(std::move(wall));
    }
    add_rect_light(scene, P.point(Vec3(kLightX, kLightHeight, 0.f)),
                   P.vec(Vec3(kLightSize, 0.f, 0.f)), P.vec(Vec3(0.f, 0.f, kLightSize)),
                   Rgb(kLightRadiance));
    const Vec3 eye(-1.f, 2.f, 0.f), target(0.5f, 0.f, 0.f);
    const Vec3 z = normalize(eye - target);
    const Vec3 x = normalize(cross(Vec3(0.f, 1.f, 0.f), z));
    const Vec3 y = cross(z, x);
    scene.camera.pos = P.point(eye);
    scene.camera.x = P.dir(x);
    scene.camera.y = P.dir(y);
    scene.camera.z = P.dir(z);
    scene.camera.hfov_deg = 70.f;
    scene.camera.znear = 1e-3f * s;
    scene.camera.zfar = 100.f * s;
    scene.camera.target = P.point(target);
    scene.source = "wall scene, " + config_name(Config{s, t});
    editor.finalize();
    return scene;
}

std::vector<StressResult> run_self_intersection_cases(StressSize size) {
    std::vector<StressResult> out;
    const std::size_t n = size == StressSize::Quick ? 3000 : 20000;
    struct NamedBackend {
        const char* name;
        AccelOptions opt;
    };
    std::vector<NamedBackend> backends;
    {
        AccelOptions e;
        e.kind = AccelKind::Embree;
        e.build_threads = 1;
        backends.push_back({"embree", e});
        AccelOptions b;
        b.kind = AccelKind::Builtin;
        b.triangle = TriangleTest::MollerTrumbore;
        b.build_threads = 1;
        backends.push_back({"builtin Moller-Trumbore", b});
    }
    for (const Config& c : kConfigs) {
        const Scene scene = make_wall_scene(c.scale, c.translation);
        const Placement P(c.scale, c.translation);
        const Light& light = scene.lights.at(0);
        const bool safe_offset = offset_predicted_safe(scene, c.scale);
        const bool safe_light = light_end_predicted_safe(scene, c.scale);
        for (const NamedBackend& nb : backends) {
            const std::unique_ptr<Accel> accel = make_accel(scene, nb.opt);
            for (OffsetMethod method : {OffsetMethod::Renderer, OffsetMethod::ZeroLightError,
                                        OffsetMethod::Fixed, OffsetMethod::None}) {
                SplitMix64 rng = case_rng(31);
                std::size_t lit = 0, blocked = 0, bounces = 0, self_hits = 0, dark = 0, leaks = 0,
                            non_finite = 0;
                // The light sample exactly as the path integrator draws it (sample_li), with
                // its error bound and normal; the reference point is the shading point.
                auto light_point = [&](const Vec3& ref, Vec3& err, Vec3& nl) {
                    const Vec2 u(rng.next_float(), rng.next_float());
                    const std::optional<LightSample> ls = sample_li(scene, light, ref, u);
                    if (!ls) return std::optional<Vec3>();
                    err = ls->p_error;
                    nl = ls->n_light;
                    return std::optional<Vec3>(ls->p_light);
                };
                for (std::size_t i = 0; i < n; ++i) {
                    // Lit floor point (local x in [0.2, 1.4]) seen from above the lit side.
                    const Vec3 tl(0.2f + 1.2f * rng.next_float(), 0.f,
                                  2.8f * rng.next_float() - 1.4f);
                    const Vec3 from_l = P.point(tl + Vec3(0.4f, 1.f, 0.3f));
                    const Vec3 to_l = P.point(tl);
                    const Ray rl{from_l, normalize(to_l - from_l), 0.f, kInf};
                    const std::optional<Hit> hl = accel->intersect(rl);
                    if (hl && hl->geom_id == kFloorId) {
                        const SurfaceInteraction si = make_interaction(scene, rl, *hl);
                        Vec3 err, nl;
                        if (const std::optional<Vec3> pl = light_point(si.p, err, nl)) {
                            ++lit;
                            if (accel->occluded(shadow_ray(method, si, *pl, err, nl))) ++blocked;
                        }
                        // Bounce into the hemisphere the ray came from (the open side).
                        Vec3 w = square_to_uniform_sphere(rng.next_vec2());
                        if (dot(w, si.ng) * dot(si.wo, si.ng) < 0.f) w = -w;
                        const std::optional<Hit> hb = accel->intersect(bounce_ray(method, si, w));
                        ++bounces;
                        if (hb && hb->geom_id == kFloorId) ++self_hits;
                        if (non_finite_hit(hb)) ++non_finite;
                    }
                    // Point of the wall's dark face (local x = -0.05), seen from the dark side.
                    const Vec3 td(-kWallHalfThickness, 0.02f + 0.43f * rng.next_float(),
                                  2.8f * rng.next_float() - 1.4f);
                    const Vec3 from_d = P.point(td + Vec3(-1.f, 0.3f, 0.2f));
                    const Ray rd{from_d, normalize(P.point(td) - from_d), 0.f, kInf};
                    const std::optional<Hit> hd = accel->intersect(rd);
                    if (hd && hd->geom_id == kWallId) {
                        const SurfaceInteraction si = make_interaction(scene, rd, *hd);
                        Vec3 err, nl;
                        if (const std::optional<Vec3> pl = light_point(si.p, err, nl)) {
                            ++dark;
                            if (!accel->occluded(shadow_ray(method, si, *pl, err, nl))) ++leaks;
                        }
                    }
                }
                const bool required =
                    safe_offset && (method == OffsetMethod::Renderer ||
                                    (method == OffsetMethod::ZeroLightError && safe_light));
                // Most probe rays must reach their surface, or the counts mean nothing.
                const bool enough = lit >= n / 2 && dark >= n / 2;
                const std::string measured = fmt::format("acne: {} of {} shadow rays blocked, {} of {} bounces re-hit the "
                    "floor; leaks: {} of {}; non-finite {}",
                    blocked, lit, self_hits, bounces, leaks, dark, non_finite);
                out.push_back(make_row(
                    kSelfGroup, config_name(c), std::string(nb.name) + ", " + method_name(method),
                    "0 acne, 0 leaks", measured, required,
                    enough && blocked == 0 && self_hits == 0 && leaks == 0 && non_finite == 0));
            }
        }
    }
    return out;
}

namespace {

/// Mean pixel luminance over a band of film rows, with its standard error.
struct RegionEstimate {
    double mean = 0.0, std_err = 0.0;
};

/// Whole film, upper half (film rows from the top: beyond the wall, the lit floor) and lower
/// half (the wall's dark face and the dark floor): acne darkens the first, leaks brighten
/// the second, and the whole-image mean alone could let them cancel.
constexpr int kRegions = 3;
const char* const kRegionNames[kRegions] = {"image", "upper half", "lower half"};

struct FilmFigures {
    RegionEstimate region[kRegions];
    std::size_t non_finite_pixels = 0;
    std::uint64_t dropped = 0;
};

/// Renders the wall scene with the default backend and the path integrator and returns the
/// mean pixel luminance of each region with its standard error (from the per-pixel variance of
/// the mean, channels treated as fully correlated, which bounds the luminance variance from
/// above).
FilmFigures render_wall(const Scene& scene, StressSize size, std::uint64_t seed) {
    RenderSettings rs;
    rs.width = size == StressSize::Quick ? 32 : 64;
    rs.height = rs.width;
    rs.spp = size == StressSize::Quick ? 64 : 256;
    rs.max_depth = 4;
    rs.seed = seed;
    rs.quiet = true;
    rs.aovs = AovSet{};
    rs.aovs.variance = true;
    const std::unique_ptr<Accel> accel = make_accel(scene, rs.accel);
    const Renderer r(scene, *accel, rs);
    RenderStats stats;
    const Film f = r.render(stats);
    FilmFigures ff;
    ff.dropped = stats.dropped;
    double sum[kRegions] = {}, var[kRegions] = {}, count[kRegions] = {};
    for (int y = 0; y < f.height(); ++y)
        for (int x = 0; x < f.width(); ++x) {
            const Rgb m = f.mean(x, y);
            const int band = 2 * y < f.height() ? 1 : 2;
            count[0] += 1.0;
            count[band] += 1.0;
            if (!(std::isfinite(m.x) && std::isfinite(m.y) && std::isfinite(m.z))) {
                ++ff.non_finite_pixels;
                continue;
            }
            const Rgb v = f.variance_of_mean(x, y);
            const double sd =
                0.2126 * std::sqrt(v.x) + 0.7152 * std::sqrt(v.y) + 0.0722 * std::sqrt(v.z);
            for (int k : {0, band}) {
                sum[k] += luminance(m);
                var[k] += sd * sd;
            }
        }
    for (int k = 0; k < kRegions; ++k) {
        ff.region[k].mean = sum[k] / count[k];
        ff.region[k].std_err = std::sqrt(var[k]) / count[k];
    }
    return ff;
}

/// |z| bound of the render comparisons: 4 standard errors make a false failure of a correct
/// renderer a 6e-5 event per comparison (the same bound as the render tests).
constexpr double kRenderZBound = 4.0;

} // namespace

std::vector<StressResult> run_scale_render_cases(StressSize size) {
    std::vector<StressResult> out;
    const FilmFigures ref = render_wall(make_wall_scene(1.f, 0.f), size, 1);
    std::uint64_t seed = 2;
    for (const Config& c : kConfigs) {
        const Scene scene = make_wall_scene(c.scale, c.translation);
        const FilmFigures f = render_wall(scene, size, seed++);
        // The renderer offsets both ends of shadow rays by their error bounds, so only the
        // offset itself limits it.
        const bool predicted = offset_predicted_safe(scene, c.scale);
        std::string measured;
        double worst_z = 0.0;
        for (int k = 0; k < kRegions; ++k) {
            const RegionEstimate& a = f.region[k];
            const RegionEstimate& b = ref.region[k];
            const double z =
                (a.mean - b.mean) / std::sqrt(a.std_err * a.std_err + b.std_err * b.std_err);
            if (!(std::abs(z) <= std::abs(worst_z))) worst_z = z;
            measured += fmt::format("{}: z = {:.2f} ({:.5g} vs {:.5g}, {:+.1f}%); ", kRegionNames[k], z,
                                     a.mean, b.mean, 100.0 * (a.mean - b.mean) / b.mean);
        }
        measured += fmt::format("non-finite pixels {}, dropped samples {}", f.non_finite_pixels,
                                 f.dropped);
        const bool finite = f.non_finite_pixels == 0 && f.dropped == 0;
        StressResult r =
            make_row(kRenderGroup, config_name(c), "path, embree, robust offsets",
                     fmt::format("|z| < {:.0f} in each region, no non-finite sample", kRenderZBound),
                     measured, predicted, std::abs(worst_z) < kRenderZBound && finite);
        if (!predicted && !finite) {
            r.reported_only = false;
            r.pass = false;
        }
        out.push_back(r);
    }
    return out;
}

std::vector<StressResult> run_geometry_cases(StressSize size, const std::string& shared_scenes) {
    std::vector<StressResult> out = run_watertight_cases(size, shared_scenes);
    for (auto* f : {&run_degenerate_cases, &run_self_intersection_cases, &run_scale_render_cases}) {
        std::vector<StressResult> more = f(size);
        out.insert(out.end(), more.begin(), more.end());
    }
    return out;
}

} // namespace candela::numerics
