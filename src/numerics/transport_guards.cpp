// Guard cases of the stress suite (include/candela/numerics/transport_cases.h): extreme inputs
// into every BSDF, Fresnel, microfacet, warp, MIS and light function, counting outputs that are
// not finite (or negative where a density or radiance is meant), and a render with a poisoned
// material whose non-finite samples must be dropped and counted, never stored.
#include "candela/accel/accel.h"
#include "candela/bsdf/bsdf.h"
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
#include "candela/numerics/transport_cases.h"
#include "candela/sampling/mis.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/scene/envmap.h"
#include "candela/scene/interaction.h"
#include "transport_support.h"

#include <fmt/format.h>
#include <cmath>
#include <limits>
#include <memory>

namespace candela::numerics {

using namespace transport;

namespace {

/// Largest float below 1: the top of the half-open [0, 1) range samplers produce.
constexpr float kOneMinus = 0x1.fffffep-1f;
/// A returned direction must be unit length to this tolerance (a few ulps after normalisation
/// and frame changes, far below anything a real error would produce).
constexpr float kUnitTol = 1e-4f;

/// Counts checks and failures, remembering the first failure for the report.
struct Tally {
    std::uint64_t calls = 0, bad = 0;
    std::string first;
    void check(bool ok, const std::string& what) {
        ++calls;
        if (!ok) {
            if (bad < 3) first += (bad ? "; " : "") + what;
            ++bad;
        }
    }
};

bool nonneg_finite(const Rgb& c) {
    return is_finite(c) && c.x >= 0.f && c.y >= 0.f && c.z >= 0.f;
}
bool nonneg_finite(float v) {
    return std::isfinite(v) && v >= 0.f;
}
bool unit(const Vec3& w) {
    return is_finite(w) && std::abs(length(w) - 1.f) < kUnitTol;
}

StressResult tally_row(const std::string& name, const std::string& method, const Tally& t) {
    StressResult r;
    r.group = kGuardsGroup;
    r.name = name;
    r.method = method;
    r.expected = "0 non-finite or negative outputs";
    r.measured = fmt::format("{} of {} checks failed", t.bad,
                              t.calls) +
                 (t.bad ? " (first: " + t.first + ")" : std::string());
    r.pass = t.bad == 0;
    return r;
}

/// Directions at and near the degenerate configurations of the local shading frame.
std::vector<Vec3> extreme_directions() {
    std::vector<Vec3> d = {Vec3(0, 0, 1),
                           Vec3(0, 0, -1),
                           Vec3(1, 0, 0), // exactly tangent
                           Vec3(0, -1, 0),
                           normalize(Vec3(1, 0, 1e-8f)),
                           normalize(Vec3(1, 0, -1e-8f)),
                           normalize(Vec3(1, 0, kMinCosTheta)),
                           normalize(Vec3(1, 0, 2.f * kMinCosTheta)),
                           normalize(Vec3(-1, 0, -2.f * kMinCosTheta)),
                           normalize(Vec3(1, 1, 1e-4f)),
                           normalize(Vec3(1, 0, 1)),
                           normalize(Vec3(-1, 0, 1)),
                           normalize(Vec3(0.3f, -0.2f, -0.9f)),
                           Vec3(0.f)}; // zero-length
    return d;
}

std::vector<Material> extreme_materials() {
    std::vector<Material> mats;
    Material m;
    m.kind = BsdfKind::Diffuse;
    m.albedo = Rgb(0.5f);
    mats.push_back(m);
    m.albedo = Rgb(0.f);
    mats.push_back(m);
    const Rgb gold_eta(0.2f, 0.9f, 1.3f), gold_k(3.9f, 2.4f, 2.2f);
    for (float alpha : {0.f, 1e-6f, 1e-4f, 1e-3f, 0.5f, 1.f, 10.f})
        mats.push_back(conductor_material(alpha, gold_eta, gold_k));
    for (float eta : {0.5f, 1.f, 1.5f})
        mats.push_back(conductor_material(1e-3f, Rgb(eta), Rgb(0.f)));
    mats.push_back(conductor_material(0.3f, Rgb(1.f), Rgb(1e4f)));
    for (float ior : {0.f, 1.f, 1.0001f, 1.5f, 3.5f, 100.f}) {
        m = glass_material(ior);
        mats.push_back(m);
        m.kind = BsdfKind::Refraction;
        mats.push_back(m);
    }
    m = Material();
    m.kind = BsdfKind::Mirror;
    mats.push_back(m);
    mats.push_back(emission_material(1e8f));
    return mats;
}

std::string mat_label(const Material& m) {
    return fmt::format("{} (alpha {:g}, ior {:g}, eta {:g}, k {:g})", bsdf_kind_name(m.kind),
                        double(m.alpha), double(m.ior), double(m.eta.x), double(m.k.x));
}

Tally bsdf_guards() {
    Tally t;
    const std::vector<Vec3> dirs = extreme_directions();
    const Vec2 us[] = {Vec2(0.f, 0.f),       Vec2(kOneMinus, kOneMinus), Vec2(0.5f, 0.5f),
                       Vec2(kOneMinus, 0.f), Vec2(0.f, kOneMinus),       Vec2(1e-30f, 0.25f)};
    for (const Material& m : extreme_materials()) {
        const std::string ml = mat_label(m);
        t.check(nonneg_finite(bsdf_albedo_hint(m)), ml + ": albedo hint");
        for (const Vec3& wo : dirs) {
            std::vector<Vec3> wis = dirs;
            wis.push_back(-wo);                      // wi = -wo
            wis.push_back(Vec3(-wo.x, -wo.y, wo.z)); // mirror direction
            wis.push_back(Vec3(wo.x, wo.y, -wo.z));  // mirrored through the surface
            for (const Vec3& wi : wis) {
                t.check(nonneg_finite(bsdf_f(m, wo, wi)), ml + ": bsdf_f");
                t.check(nonneg_finite(bsdf_pdf(m, wo, wi)), ml + ": bsdf_pdf");
            }
            for (Vec2 u : us)
                for (float uc : {0.f, 0.5f, kOneMinus}) {
                    auto s = bsdf_sample(m, wo, u, uc);
                    ++t.calls;
                    if (!s) continue;
                    t.check(nonneg_finite(s->f), ml + ": sample f");
                    t.check(unit(s->wi), ml + ": sample wi");
                    t.check(std::isfinite(s->pdf) && s->pdf > 0.f, ml + ": sample pdf");
                    t.check(std::isfinite(s->eta) && s->eta > 0.f, ml + ": sample eta");
                    t.check(nonneg_finite(s->f * (std::abs(s->wi.z) / s->pdf)),
                            ml + ": sample weight");
                }
        }
    }
    return t;
}

Tally helper_guards() {
    Tally t;
    const float inf = std::numeric_limits<float>::infinity();
    const float cosines[] = {-1.f,  -0.5f, -1e-30f, 0.f,         1e-30f,
                             1e-7f, 0.5f,  1.f,     -1.0000001f, 1.0000001f};
    for (float c : cosines) {
        for (float eta : {1e-3f, 0.5f, 1.f, 1.0001f, 1.5f, 3.5f, 1e3f}) {
            const float F = fresnel_dielectric(c, eta);
            t.check(std::isfinite(F) && F >= 0.f && F <= 1.f,
                    fmt::format("fresnel_dielectric({:g}, {:g})", double(c), double(eta)));
            for (float k : {0.f, 1.f, 1e3f}) {
                const float Fc = fresnel_conductor(c, eta, k);
                t.check(std::isfinite(Fc) && Fc >= 0.f && Fc <= 1.f,
                        fmt::format("fresnel_conductor({:g}, {:g}, {:g})", double(c), double(eta),
                                     double(k)));
            }
        }
        Vec3 wt;
        for (float eta : {1e-3f, 1.f, 1.5f, 1e3f}) {
            const Vec3 w = normalize(Vec3(std::sqrt(std::max(0.f, 1.f - c * c)), 0.f,
                                          std::abs(std::clamp(c, -1.f, 1.f))));
            if (refract(w, Vec3(0, 0, 1), eta, &wt))
                t.check(unit(wt), fmt::format("refract(cos {:g}, eta {:g})", double(c), double(eta)));
        }
    }
    // Microfacet distribution, masking and the Beckmann warp at the smallest and largest
    // roughness the BSDF uses, and Lambda at alpha = 0.
    const std::vector<Vec3> dirs = extreme_directions();
    for (float alpha : {kMinBeckmannAlpha, 1e-3f, 1.f, 10.f}) {
        for (const Vec3& w : dirs) {
            t.check(nonneg_finite(beckmann_d(w, alpha)), "beckmann_d");
            // Lambda is +inf exactly at grazing (documented: G then goes to 0), never NaN.
            const float lambda = beckmann_lambda(w, alpha);
            t.check(lambda >= 0.f && (std::isfinite(lambda) || w.z == 0.f),
                    fmt::format("beckmann_lambda(z {:g}, alpha {:g})", double(w.z), double(alpha)));
            t.check(nonneg_finite(square_to_beckmann_pdf(w, alpha)), "square_to_beckmann_pdf");
            for (const Vec3& w2 : dirs) {
                const float g = beckmann_g(w, w2, alpha);
                t.check(std::isfinite(g) && g >= 0.f && g <= 1.f, "beckmann_g");
            }
        }
        for (Vec2 u : {Vec2(0.f, 0.f), Vec2(kOneMinus, kOneMinus), Vec2(kOneMinus, 0.5f)})
            t.check(unit(square_to_beckmann(u, alpha)),
                    fmt::format("square_to_beckmann(alpha {:g})", double(alpha)));
    }
    for (const Vec3& w : dirs) {
        const float lambda = beckmann_lambda(w, 0.f);
        t.check(lambda >= 0.f && (std::isfinite(lambda) || w.z == 0.f), "beckmann_lambda(alpha 0)");
    }
    // Warps at the corners and centre of the square.
    for (Vec2 u : {Vec2(0.f, 0.f), Vec2(0.5f, 0.5f), Vec2(kOneMinus, kOneMinus), Vec2(0.5f, 0.f),
                   Vec2(kOneMinus, 0.f)}) {
        t.check(is_finite(Vec3(square_to_uniform_disk_concentric(u).x,
                               square_to_uniform_disk_concentric(u).y, 0.f)),
                "concentric disk");
        const Vec3 c = square_to_cosine_hemisphere(u);
        t.check(unit(c) && nonneg_finite(square_to_cosine_hemisphere_pdf(c)), "cosine hemisphere");
        t.check(unit(square_to_uniform_hemisphere(u)), "uniform hemisphere");
        t.check(unit(square_to_uniform_sphere(u)), "uniform sphere");
        const Vec3 b = square_to_uniform_triangle(u);
        t.check(is_finite(b) && b.x >= 0.f && b.y >= 0.f && b.z >= 0.f, "uniform triangle");
        for (float cos_max : {-1.f, 0.f, 0.999999f, 1.f}) {
            const Vec3 w = square_to_uniform_cone(u, cos_max);
            t.check(unit(w) && nonneg_finite(square_to_uniform_cone_pdf(w, cos_max)),
                    fmt::format("uniform cone(cos_max {:g})", double(cos_max)));
        }
    }
    // MIS weights with zero, infinite and huge densities.
    const float pdfs[] = {0.f, 1e-38f, 1.f, 3e38f, inf};
    for (float f : pdfs)
        for (float g : pdfs)
            for (int nf : {0, 1, 4}) {
                const float p = power_heuristic(nf, f, 1, g), b = balance_heuristic(nf, f, 1, g);
                t.check(std::isfinite(p) && p >= 0.f && p <= 1.f, "power_heuristic");
                t.check(std::isfinite(b) && b >= 0.f && b <= 1.f, "balance_heuristic");
            }
    return t;
}

/// A scene holding one light of every kind, including degenerate ones (a zero-area rect, a
/// mesh with a collapsed triangle, a 1e-6 sphere, an environment map with one bright texel).
Scene light_zoo() {
    Scene scene;
    SceneEditor editor(scene);
    const std::uint32_t diffuse = add_material(scene, diffuse_material(0.5f));
    add_floor(scene, 5.f, 0.f, diffuse);
    add_rect_light(scene, Vec3(0, 2, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), Rgb(5.f));
    add_rect_light(scene, Vec3(1, 2, 0), Vec3(1e-3f, 0, 0), Vec3(0, 0, 1e-3f), Rgb(1e8f));
    {
        // Zero-area rect: a record only (the power is 0, so the sampler never picks it for
        // rendering, but the functions must still answer sanely).
        Light l;
        l.kind = LightKind::Area;
        l.L = Rgb(1.f);
        l.p = Vec3(0, 3, 0);
        l.n = Vec3(0, -1, 0);
        l.dx = Vec3(0.f);
        l.dy = Vec3(0, 0, 1);
        editor.add_light(l);
    }
    const std::uint32_t emit = add_material(scene, emission_material(3.f));
    add_sphere(scene, Vec3(-1, 1, 0), 0.5f, emit);
    add_sphere(scene, Vec3(2, 1, 2), 1e-6f, emit);
    {
        // An emitting mesh with a collapsed (zero-area) second triangle.
        Mesh mesh;
        mesh.name = "collapsed";
        mesh.material = emit;
        // Its Mesh light has the CDF {0.5, 0.5} and area 0.5.
        mesh.positions = {Vec3(0, 1, 1), Vec3(1, 1, 1), Vec3(0, 2, 1), Vec3(2, 1, 1)};
        mesh.normals = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)};
        mesh.indices = {0, 1, 2, 0, 1, 3};
        editor.add_mesh(std::move(mesh));
    }
    Light point;
    point.kind = LightKind::Point;
    point.L = Rgb(10.f);
    point.p = Vec3(0, 1, 0);
    editor.add_light(point);
    Light spot = point;
    spot.kind = LightKind::Spot;
    spot.n = Vec3(0, -1, 0);
    spot.cos_total = std::cos(0.3f);
    spot.falloff_exp = 50.f;
    editor.add_light(spot);
    spot.falloff_exp = 0.f;
    spot.cos_total = 1.f; // a zero-width cone
    editor.add_light(spot);
    Light dir;
    dir.kind = LightKind::Directional;
    dir.L = Rgb(2.f);
    dir.n = normalize(Vec3(1, 1, 0));
    editor.add_light(dir);
    add_sky(scene, 1.f);
    {
        // 8 x 4 map, black but for one texel next to the pole.
        std::vector<Rgb> texels(32, Rgb(0.f));
        texels[3] = Rgb(1e4f);
        scene.env = std::make_shared<EnvMap>(8, 4, texels, "guard-map");
        Light env;
        env.kind = LightKind::Environment;
        editor.add_light(env);
    }
    editor.finalize();
    return scene;
}

Tally light_guards() {
    Tally t;
    const Scene scene = light_zoo();
    for (LightSamplerKind kind : {LightSamplerKind::Power, LightSamplerKind::Bvh}) {
        const LightChooser chooser(scene, kind);
        const LightChoiceContext ctx{Vec3(0.2f, 0.f, 0.1f), Vec3(0.f, 1.f, 0.f)};
        for (std::size_t i = 0; i < scene.lights.size(); ++i)
            t.check(std::isfinite(chooser.pmf(ctx, i)) && chooser.pmf(ctx, i) >= 0.f,
                    "light choice pmf");
        for (std::uint32_t u : {0u, 0x80000000u, 0xffffffffu}) {
            auto pick = chooser.sample(ctx, u);
            t.check(!pick || (pick->pmf > 0.f && std::isfinite(pick->pmf) &&
                              pick->pmf == chooser.pmf(ctx, pick->index)),
                    "light choice pick");
        }
    }
    // Reference points: ordinary, on a rect light, at its centre, on a sphere light's surface
    // and centre, at the point light, in the plane of a rect, very far away.
    const std::vector<Vec3> refs = {Vec3(0.2f, 0.f, 0.1f), Vec3(0, 2, 0),   Vec3(0.3f, 2, 0.2f),
                                    Vec3(-1, 1.5f, 0),     Vec3(-1, 1, 0),  Vec3(0, 1, 0),
                                    Vec3(2, 1, 2),         Vec3(5, 2, 5),   Vec3(1e20f, 0, 0),
                                    Vec3(0, 1, 1),         Vec3(0.5f, 1, 1)};
    const Vec2 us[] = {Vec2(0.f, 0.f), Vec2(0.5f, 0.5f), Vec2(kOneMinus, kOneMinus),
                       Vec2(kOneMinus, 0.f), Vec2(0.f, kOneMinus)};
    const Vec3 dirs[] = {Vec3(0, 1, 0), Vec3(0, -1, 0), normalize(Vec3(1, 1, 1)), Vec3(0.f)};
    for (std::size_t li = 0; li < scene.lights.size(); ++li) {
        const Light& light = scene.lights[li];
        const std::string ll = fmt::format("light {} ({})", li, light_kind_name(light.kind));
        t.check(nonneg_finite(light_power(scene, light)), ll + ": power");
        for (const Vec3& n : dirs)
            for (const Vec3& w : dirs)
                t.check(nonneg_finite(light_le(light, n, w)), ll + ": light_le");
        for (const Vec3& ref : refs) {
            for (Vec2 u : us) {
                auto ls = sample_li(scene, light, ref, u);
                ++t.calls;
                if (!ls) continue;
                t.check(nonneg_finite(ls->L), ll + ": sample L");
                t.check(unit(ls->wi), ll + ": sample wi");
                t.check(std::isfinite(ls->pdf) && ls->pdf > 0.f, ll + ": sample pdf");
                t.check(ls->dist > 0.f && !std::isnan(ls->dist), ll + ": sample dist");
                t.check(is_finite(ls->p_light) && is_finite(ls->n_light), ll + ": sample point");
                t.check(nonneg_finite(ls->L * (1.f / ls->pdf)), ll + ": sample weight");
                t.check(nonneg_finite(
                            pdf_li(scene, light, ref, ls->wi, ls->p_light, ls->n_light, ls->prim)),
                        ll + ": pdf_li of its sample");
            }
            // pdf_li with degenerate arguments: zero normal, point at the reference, zero wi.
            for (const Vec3& w : dirs) {
                t.check(nonneg_finite(pdf_li(scene, light, ref, w, ref, Vec3(0.f), 0u)),
                        ll + ": pdf_li(point at ref, zero normal)");
                t.check(nonneg_finite(pdf_li(scene, light, ref, w, light.p, w, 0u)),
                        ll + ": pdf_li(light position)");
            }
        }
        for (const Vec3& w : dirs)
            t.check(nonneg_finite(escaped_pdf(scene, light, w)), ll + ": escaped_pdf");
    }
    for (const Vec3& w : dirs)
        t.check(nonneg_finite(escaped_radiance(scene, w)), "escaped_radiance");
    return t;
}

/// Two floors side by side under a sky, the left one with a NaN albedo: every sample that hits
/// it is non-finite. The renderer must drop and count those samples and store none of them.
StressResult poisoned_render() {
    Scene scene;
    Material bad = diffuse_material(0.5f);
    bad.albedo = Rgb(std::numeric_limits<float>::quiet_NaN());
    const std::uint32_t bad_mat = add_material(scene, bad);
    const std::uint32_t good_mat = add_material(scene, diffuse_material(0.5f));
    for (int side : {-1, 1}) {
        Mesh mesh;
        mesh.name = side < 0 ? "poisoned" : "clean";
        mesh.material = side < 0 ? bad_mat : good_mat;
        const float x0 = side < 0 ? -10.f : 0.f, x1 = side < 0 ? 0.f : 10.f;
        mesh.positions = {Vec3(x0, 0, -10), Vec3(x0, 0, 10), Vec3(x1, 0, 10), Vec3(x1, 0, -10)};
        mesh.normals = {Vec3(0, 1, 0), Vec3(0, 1, 0), Vec3(0, 1, 0), Vec3(0, 1, 0)};
        mesh.indices = {0, 1, 2, 0, 2, 3};
        SceneEditor(scene).add_mesh(std::move(mesh));
    }
    add_sky(scene, 1.f);
    scene.camera = look_at(Vec3(0, 1, 0), Vec3(0.f), Vec3(0, 0, -1), 60.f);
    SceneEditor(scene).finalize();
    RenderSettings s = case_settings(16, 16, 25);
    s.max_depth = 4;
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    Renderer renderer(scene, *accel, s);
    RenderStats stats;
    const Film film = renderer.render(stats);

    bool sums_finite = true;
    for (double v : film.raw_sum())
        sums_finite &= std::isfinite(v);
    // Columns well inside each half: the left ones see only the poisoned floor, the right ones
    // only the clean floor.
    std::uint64_t left_kept = 0, right_dropped = 0, left_dropped = 0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            if (x < film.width() / 2 - 1) {
                left_kept += film.count(x, y);
                left_dropped += film.dropped(x, y);
            }
            if (x > film.width() / 2) right_dropped += film.dropped(x, y);
        }
    const std::uint64_t taken = film.total_samples() + film.total_dropped();
    StressResult r;
    r.group = kGuardsGroup;
    r.name = "render with a NaN-albedo material on half the image";
    r.method = method_of(s, "path NEE+MIS");
    r.expected = "poisoned samples dropped and counted (renderer = film count), none stored; "
                 "clean half unaffected";
    r.measured =
        fmt::format("{} of {} samples dropped (renderer counted {}); film sums {}; "
                     "poisoned columns kept {}, clean columns dropped {}",
                     film.total_dropped(), taken,
                     stats.dropped, sums_finite ? "finite" : "NOT finite",
                     left_kept, right_dropped);
    r.pass = sums_finite && stats.dropped == film.total_dropped() && left_dropped > 0 &&
             left_kept == 0 && right_dropped == 0 && taken == stats.samples;
    return r;
}

/// Shadow rays of next-event estimation between two points of one closed emitter seen from
/// inside (a sphere; a box mesh, whose faces meet at concave edges): the ray runs along a chord
/// of the emitter, and neither end may hit the emitter itself. Counts occluded shadow rays.
StressResult self_occlusion(bool box, StressSize size) {
    Scene scene;
    const std::uint32_t mat = add_material(scene, diffuse_material(0.5f, 1.f));
    if (box)
        add_box(scene, Vec3(-1.f), Vec3(1.f), mat);
    else
        add_sphere(scene, Vec3(0.f), 1.f, mat);
    SceneEditor(scene).finalize();
    const Light& light = scene.lights.at(0);
    std::uint64_t tried = 0, occluded = 0;
    double shortest = INFINITY;
    const int n = size == StressSize::Full ? 2000000 : 200000;
    for (AccelKind kind : {AccelKind::Embree, AccelKind::Builtin}) {
        AccelOptions opt;
        opt.kind = kind;
        std::unique_ptr<Accel> accel = make_accel(scene, opt);
        Pcg32 rng(51, std::uint64_t(kind) + 1);
        for (int i = 0; i < n; ++i) {
            Ray r;
            r.o = Vec3(0.1f, -0.2f, 0.3f);
            r.d = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
            r.tmin = 0.f;
            r.tmax = INFINITY;
            std::optional<Hit> hit = accel->intersect(r);
            if (!hit) continue;
            const SurfaceInteraction si = make_interaction(scene, r, *hit);
            auto ls = sample_li(scene, light, si.p, Vec2(rng.next_float(), rng.next_float()));
            if (!ls) continue;
            ++tried;
            const Ray shadow = spawn_ray_to(si, ls->p_light, ls->p_error, ls->n_light);
            if (accel->occluded(shadow)) {
                ++occluded;
                shortest = std::min(shortest, double(ls->dist));
            }
        }
    }
    StressResult r;
    r.group = kGuardsGroup;
    r.name = box ? "NEE shadow rays inside a closed emitting box (12 triangles)"
                 : "NEE shadow rays inside a closed emitting sphere";
    r.method = fmt::format("light sample + spawn_ray_to, {} rays, embree and builtin", 2 * n);
    r.expected = "0 occluded (a chord of a convex emitter crosses nothing)";
    r.measured = fmt::format("{} of {} occluded", occluded,
                              tried) +
                 (occluded ? fmt::format(" (shortest {:.3g})", shortest) : std::string());
    r.pass = occluded == 0 && tried > 0;
    return r;
}

} // namespace

std::vector<StressResult> guard_cases() {
    std::vector<StressResult> out;
    out.push_back(tally_row("BSDF f, pdf, sample, albedo hint",
                            "every material kind x 14 extreme directions (tangent, |cos| at "
                            "and around 1e-6, zero vector) x wi = -wo, mirrored; u at corners",
                            bsdf_guards()));
    out.push_back(tally_row("Fresnel, refraction, Beckmann D/Lambda/G, warps, MIS weights",
                            "cos in {0, +-1e-30, +-1, slightly beyond}, eta in [1e-3, 1e3], "
                            "alpha in {0, 1e-4, 10}, pdfs in {0, 1e-38, 3e38, inf}",
                            helper_guards()));
    out.push_back(tally_row("light sample_li, pdf_li, light_le, power, escaped radiance",
                            "every light kind incl. zero-area rect, collapsed mesh triangle, "
                            "1e-6 sphere, zero-width spot; reference points on the lights",
                            light_guards()));
    out.push_back(self_occlusion(false, StressSize::Quick));
    out.push_back(self_occlusion(true, StressSize::Quick));
    out.push_back(poisoned_render());
    return out;
}

} // namespace candela::numerics
