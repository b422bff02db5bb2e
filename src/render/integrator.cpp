// The wavefront integrator: a batch of camera samples advanced one path vertex per step
// (rendering.md).
#include "candela/render/integrator.h"

#include "candela/bsdf/bsdf.h"
#include "candela/light/light_sample.h"
#include "candela/sampling/mis.h"
#include "candela/sampling/warp.h"
#include "candela/scene/interaction.h"
#include "candela/util/batch_kernel.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

namespace {

/// Russian roulette survival probability never drops below this, so that a path through a
/// dark region is not cut so often that its survivors carry huge weights (fireflies).
constexpr float kRouletteMinSurvival = 0.05f;
/// The least albedo vertex_shares() divides by: a conductor that reflects almost nothing at
/// this angle would otherwise give its directional lights unbounded weights (any positive
/// weights keep the choice unbiased; this only bounds how far it leans).
constexpr float kMinSplitAlbedo = 1e-3f;

/// Whether the world direction wi leaves the surface on the side its lobe says: a reflection
/// (wo and wi on one side of the shading normal) on wo's geometric side, a transmission on the
/// other. Shading normals can disagree with the geometry; such directions would carry light
/// through an opaque surface (or reflect it from inside glass), so every strategy drops them.
/// (A non-delta lobe is folded across the geometric plane first, bsdf_f_folded, so that it
/// sends nothing there; this test, on the world direction, then only drops delta samples and
/// what rounding puts on the other side.)
inline bool leaves_on_lobe_side(const SurfaceInteraction& si, const Vec3& wi_world,
                                const Vec3& wo_local, const Vec3& wi_local) {
    const bool geometric_reflection = dot(wi_world, si.ng) * dot(si.wo, si.ng) > 0.f;
    const bool shading_reflection = wi_local.z * wo_local.z > 0.f;
    return geometric_reflection == shading_reflection;
}

/// How far ahead of the path being shaded its successors' triangle data is fetched: first the
/// index triple, then (once that has arrived) the vertices and normals it names. A traversal
/// leaves the hits of a whole batch at once, so their memory can be in flight together instead
/// of one cache miss after another.
constexpr std::size_t kPrefetchIndices = 16;
constexpr std::size_t kPrefetchVertices = 8;

inline void prefetch_triangle_indices(const Scene& scene, const BatchRayHit& rh) {
    if (rh.hit.geom_id >= scene.meshes.size()) return; // a miss or a sphere
    __builtin_prefetch(&scene.meshes[rh.hit.geom_id].indices[3 * std::size_t(rh.hit.prim_id)]);
}

inline void prefetch_triangle_vertices(const Scene& scene, const BatchRayHit& rh) {
    if (rh.hit.geom_id >= scene.meshes.size()) return;
    const Mesh& m = scene.meshes[rh.hit.geom_id];
    const std::uint32_t* idx = &m.indices[3 * std::size_t(rh.hit.prim_id)];
    const bool normals = m.normals.size() == m.positions.size();
    for (int k = 0; k < 3; ++k) {
        __builtin_prefetch(&m.positions[idx[k]]);
        if (normals) __builtin_prefetch(&m.normals[idx[k]]);
    }
}

/// A table of rows stored component-major (the batch stages' inputs and outputs): component k
/// of row j is at data[k * stride + j], and a Vec3 takes three consecutive components, so a
/// loop over the rows reads and writes each component contiguously (and vectorises).
template <class Float> struct Columns {
    Float* data;
    std::size_t stride;
    Float& at(int k, std::size_t j) const { return data[std::size_t(k) * stride + j]; }
    Vec3 vec3(int k, std::size_t j) const { return Vec3(at(k, j), at(k + 1, j), at(k + 2, j)); }
    void put(int k, std::size_t j, const Vec3& v) const {
        at(k, j) = v.x;
        at(k + 1, j) = v.y;
        at(k + 2, j) = v.z;
    }
};

/// Runs body(input, output, j) for every row j < rows of the component-major tables in and
/// out (Columns, `stride` apart): the loop of every batch kernel below. Rows are independent
/// and the components rows-apart never overlap (stride >= rows), which GCC cannot prove from a
/// run-time stride: without the pragma it gives up on the alias checks and does not vectorise.
template <class Body>
[[gnu::always_inline]] inline void for_each_row(std::size_t rows, std::size_t stride,
                                                const float* __restrict in, float* __restrict out,
                                                const Body& body) {
    const Columns<const float> input{in, stride};
    const Columns<float> output{out, stride};
#pragma GCC ivdep
    for (std::size_t j = 0; j < rows; ++j)
        body(input, output, j);
}

/// Paths whose triangle surfaces are computed together before they are shaded: the surfaces of
/// a chunk (24 floats per hit, one cache line apart per component) stay in the first-level
/// cache until the shading reads them, where a whole batch's were read back from the second.
constexpr std::size_t kSurfaceChunk = 256;

/// Component offsets of a gathered triangle hit (BatchWorkspace::surfaces.in): component k of
/// row j is in[k * stride + j], a Vec3 takes three consecutive components. Each offset
/// is the previous one plus its width, so components can neither overlap nor leave a gap.
struct SurfaceInput {
    static constexpr int p0 = 0, p1 = p0 + 3, p2 = p1 + 3; ///< corners
    /// Vertex normals (zero for a mesh without normals).
    static constexpr int n0 = p2 + 3, n1 = n0 + 3, n2 = n1 + 3;
    static constexpr int u = n2 + 3, v = u + 1; ///< barycentrics
    static constexpr int d = v + 1;             ///< ray direction
    static constexpr int count = d + 3;
};
static_assert(SurfaceInput::count == 7 * 3 + 2, "seven Vec3 and two floats per triangle hit");

/// Component offsets of a computed surface (BatchWorkspace::surfaces.out), laid out as
/// SurfaceInput's: make_interaction's p, p_error, ng, the adapted shading normal ns, wo, the
/// shading frame's s and t, and the interpolated shading normal before the adaptation.
struct SurfaceOutput {
    static constexpr int p = 0, p_error = p + 3, ng = p_error + 3;
    static constexpr int ns = ng + 3, wo = ns + 3, frame_s = wo + 3, frame_t = frame_s + 3;
    static constexpr int ns_interpolated = frame_t + 3;
    static constexpr int count = ns_interpolated + 3;
};
static_assert(SurfaceOutput::count == 8 * 3, "eight Vec3 per computed surface");

/// triangle_surface(), the adapted shading normal and its frame of `rows` gathered hits:
/// make_interaction's and adapt_shading_normal's arithmetic for triangles, branch-free, so that GCC
/// vectorises it (eight hits per instruction in the AVX2 clone, no FMA: the same bits as
/// make_interaction).
CANDELA_BATCH_KERNEL void compute_triangle_surfaces(std::size_t rows, std::size_t stride,
                                                    const float* __restrict in,
                                                    float* __restrict out) {
    // Not for_each_row: GCC does not vectorise this body as a lambda (it stays a call).
    const Columns<const float> input{in, stride};
    const Columns<float> output{out, stride};
#pragma GCC ivdep
    for (std::size_t j = 0; j < rows; ++j) {
        using In = SurfaceInput;
        using Out = SurfaceOutput;
        const Vec3 p0 = input.vec3(In::p0, j), p1 = input.vec3(In::p1, j);
        const Vec3 p2 = input.vec3(In::p2, j);
        const Vec3 n0 = input.vec3(In::n0, j), n1 = input.vec3(In::n1, j);
        const Vec3 n2 = input.vec3(In::n2, j);
        const Vec3 d = input.vec3(In::d, j);
        const float u = input.at(In::u, j), v = input.at(In::v, j);
        const Vec3 wo = outgoing_direction(d);
        const TriangleSurface t = triangle_surface(p0, p1, p2, n0, n1, n2, u, v, wo);
        const Vec3 ns = adapted_shading_normal(t.ns, t.ng, wo);
        const Frame frame(ns);
        output.put(Out::p, j, t.p);
        output.put(Out::p_error, j, t.p_error);
        output.put(Out::ng, j, t.ng);
        output.put(Out::ns, j, ns);
        output.put(Out::wo, j, wo);
        output.put(Out::frame_s, j, frame.s);
        output.put(Out::frame_t, j, frame.t);
        output.put(Out::ns_interpolated, j, t.ns);
    }
}

/// Component offsets of a queued shadow segment (ShadowQueue::segments.in), laid out as
/// SurfaceInput's: the shading point, its error bound and geometric normal, then the light
/// sample's point, error bound and normal (spawn_ray_between's arguments).
struct SegmentInput {
    static constexpr int p = 0, p_error = p + 3, ng = p_error + 3;
    static constexpr int target = ng + 3, target_error = target + 3, target_n = target_error + 3;
    static constexpr int count = target_n + 3;
};
static_assert(SegmentInput::count == 6 * 3, "six Vec3 per shadow segment");

/// Component offsets of a computed segment (ShadowQueue::segments.out): the ray's origin,
/// direction and batch interval.
struct SegmentOutput {
    static constexpr int o = 0, d = o + 3, tnear = d + 3, tfar = tnear + 1;
    static constexpr int count = tfar + 1;
};
static_assert(SegmentOutput::count == 2 * 3 + 2, "two Vec3 and two floats per segment");

/// spawn_ray_between() and batch_interval() of `rows` queued segments, branch-free, so that GCC
/// vectorises it as compute_triangle_surfaces (no FMA: the bits of the per-ray functions).
/// `tnear_open` is open_tnear(0): spawn_ray_between's tmin is 0 for every segment.
CANDELA_BATCH_KERNEL void compute_shadow_segments(std::size_t rows, std::size_t stride,
                                                  float tnear_open, const float* __restrict in,
                                                  float* __restrict out) {
    for_each_row(rows, stride, in, out, [&](const auto& input, const auto& output, std::size_t j) {
        using In = SegmentInput;
        using Out = SegmentOutput;
        const Ray r =
            spawn_ray_between(input.vec3(In::p, j), input.vec3(In::p_error, j),
                              input.vec3(In::ng, j), input.vec3(In::target, j),
                              input.vec3(In::target_error, j), input.vec3(In::target_n, j));
        const BatchInterval t = batch_interval(r, tnear_open);
        output.put(Out::o, j, r.o);
        output.put(Out::d, j, r.d);
        output.at(Out::tnear, j) = t.tnear;
        output.at(Out::tfar, j) = t.tfar;
    });
}

/// Component offsets of a queued bounce ray (BounceQueue::table.in): spawn_ray()'s
/// arguments, the point, its error bound, geometric normal and the ray's direction.
struct BounceInput {
    static constexpr int p = 0, p_error = p + 3, ng = p_error + 3, wi = ng + 3;
    static constexpr int count = wi + 3;
};
static_assert(BounceInput::count == 4 * 3, "four Vec3 per bounce ray");

/// Component offsets of a computed bounce ray (BounceQueue::table.out): its origin and
/// batch interval (its direction is the input's).
struct BounceOutput {
    static constexpr int o = 0, tnear = o + 3, tfar = tnear + 1;
    static constexpr int count = tfar + 1;
};
static_assert(BounceOutput::count == 3 + 2, "a Vec3 and two floats per bounce ray");

/// spawn_ray() and batch_interval() of `rows` queued bounce rays, vectorised as
/// compute_shadow_segments. `tnear_open` is open_tnear(0): spawn_ray's tmin is 0.
CANDELA_BATCH_KERNEL void compute_bounce_origins(std::size_t rows, std::size_t stride,
                                                 float tnear_open, const float* __restrict in,
                                                 float* __restrict out) {
    for_each_row(rows, stride, in, out, [&](const auto& input, const auto& output, std::size_t j) {
        using In = BounceInput;
        using Out = BounceOutput;
        const Ray r = spawn_ray(input.vec3(In::p, j), input.vec3(In::p_error, j),
                                input.vec3(In::ng, j), input.vec3(In::wi, j));
        const BatchInterval t = batch_interval(r, tnear_open);
        output.put(Out::o, j, r.o);
        output.at(Out::tnear, j) = t.tnear;
        output.at(Out::tfar, j) = t.tfar;
    });
}

/// The recorder of a render: records nothing, and every call compiles to nothing.
struct NoEvents {
    void hit(std::uint32_t, int, const SurfaceInteraction&) {}
    void scatter(std::uint32_t, int, std::uint8_t) {}
    void light(std::uint32_t, int, std::int32_t, const Rgb&) {}
    void queued_shadow(std::size_t, std::uint32_t) {}
    void shadow_arrived(std::uint32_t, int, std::size_t, const Rgb&) {}
};

/// The recorder of `candela probe`: appends every event to a PathEvents.
struct EventLog {
    PathEvents& events;
    std::uint32_t meshes; ///< Scene::meshes.size(): sphere objects are numbered after them
    void hit(std::uint32_t request, int depth, const SurfaceInteraction& si) {
        const std::uint32_t object = si.geom_id < meshes ? si.geom_id : meshes + si.prim_id;
        events.hits.push_back({request, depth, si.material, object, si.light});
    }
    void scatter(std::uint32_t request, int depth, std::uint8_t flags) {
        events.scatters.push_back({request, depth, flags});
    }
    void light(std::uint32_t request, int order, std::int32_t light, const Rgb& value) {
        events.contributions.push_back({request, order, light, value});
    }
    void queued_shadow(std::size_t slot, std::uint32_t light) {
        if (events.shadow_light.size() <= slot) events.shadow_light.resize(slot + 1);
        events.shadow_light[slot] = std::int32_t(light);
    }
    void shadow_arrived(std::uint32_t request, int order, std::size_t slot, const Rgb& value) {
        light(request, order, events.shadow_light[slot], value);
    }
};

} // namespace

Integrator::Integrator(const Scene& scene, const Accel& accel, const RenderSettings& settings)
    : scene_(scene), accel_(accel), s_(settings), light_chooser_(scene, settings.light_sampler) {
    // The estimators divide by the light sample count and the film size.
    if (s_.light_samples < 1)
        throw Error(ErrorKind::Usage, "integrator: light samples per vertex must be >= 1, got " +
                                          std::to_string(s_.light_samples));
    if (scene.camera.lens_radius > 0.f && !(scene.camera.focal_distance > 0.f))
        throw Error(ErrorKind::Usage, "integrator: a thin lens needs a positive focal distance");
    if (s_.width < 1 || s_.height < 1)
        throw Error(ErrorKind::Usage, "integrator: film size " + std::to_string(s_.width) + "x" +
                                          std::to_string(s_.height) + " is empty");
    camera_ = CameraProjection(scene.camera, s_.width, s_.height);
    std::uint32_t all_light_samples = 0; // the direct integrator's: -l per non-delta light
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        has_infinite_lights_ |= l.is_infinite();
        if (l.is_delta())
            delta_lights_.push_back(std::uint32_t(i));
        else if (l.is_infinite())
            infinite_area_lights_.push_back(std::uint32_t(i));
        all_light_samples += std::uint32_t(l.is_delta() ? 1 : s_.light_samples);
        found_by_rays_.push_back(light_found_by_rays(scene, i) ? 1u : 0u);
    }
    weigh_directional_ = light_chooser_.split().has_directional();
    // CS184: -H takes |lights| x ns_area_light hemisphere samples in total.
    hemisphere_budget_ = std::max<int>(1, int(scene.lights.size()) * s_.light_samples);
    declare_vertex_draws(all_light_samples);
    for (int order = 0; order < kCachedOrders; ++order)
        if (accept_order(order)) accepted_orders_ |= std::uint64_t(1) << order;
    // Direct-light queries one vertex can make (the workspace is sized by them).
    if (s_.integrator == IntegratorKind::Normals) {
        shadow_per_vertex_ = probe_per_vertex_ = 0;
    } else if (s_.hemisphere) {
        shadow_per_vertex_ = delta_lights_.size();
        probe_per_vertex_ = std::size_t(hemisphere_budget_);
    } else {
        shadow_per_vertex_ = s_.integrator == IntegratorKind::Direct
                                 ? all_light_samples
                                 : std::size_t(s_.light_samples);
        probe_per_vertex_ = 0;
    }
}

void Integrator::declare_vertex_draws(std::uint32_t all_light_samples) {
    bool lobe_choice = false, any_diffuse = false, any_other = false;
    for (const Material& m : scene_.materials) {
        lobe_choice |= bsdf_uses_lobe_choice(m);
        any_diffuse |= m.kind == BsdfKind::Diffuse;
        any_other |= m.kind != BsdfKind::Diffuse && m.kind != BsdfKind::Emission;
    }
    if (s_.integrator == IntegratorKind::Normals) return; // it draws nothing at its vertices
    using D = VertexDraw;
    const bool path = s_.integrator == IntegratorKind::Path;
    // The direct-light estimate: -H's directions, every light's samples (direct integrator),
    // or the -l samples of a chosen light, each a fill and the point (the fill is read only
    // when there is a choice to make).
    if (s_.hemisphere)
        dims_.repeat(std::uint32_t(hemisphere_budget_), {{D::hemisphere_direction}});
    else if (!path)
        dims_.repeat(all_light_samples, {{D::light_point}});
    else
        dims_.repeat(std::uint32_t(s_.light_samples),
                     {{D::light_fill, light_chooser_.size() > 1}, {D::light_point}});
    // The BSDF sample, with the cosine-weighted direction for Lambertian surfaces of the path
    // integrator (the direct integrator samples only delta BSDFs), and its lobe choice.
    dims_.add({D::bsdf_direction, true, any_diffuse && path});
    dims_.add({D::bsdf_lobe, lobe_choice});
    if (path) { // planned by plan_vertex where a path may draw it
        dims_.add({D::roulette, false});
        has_roulette_ = true;
        has_deferred_roulette_ = any_other;
    }
}

Ray Integrator::camera_ray(float fx, float fy, Vec2 u_lens) const {
    return camera_.ray(fx, fy, u_lens);
}

bool Integrator::accept_order(int order) const {
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

Rgb Integrator::escaped_mis(const Vec3& dir, float prev_bsdf_pdf, const Vec3& prev_p,
                            const Vec3& prev_n, double prev_split_total) const {
    Rgb L(0.f);
    // The infinite lights' irradiances at the vertex, once for all of them; where the vertex
    // weighed its directional lights by its BSDF, the total it divided by (an escaping ray
    // never finds a directional light, so their own weights are not needed).
    InfiniteShares shares = light_chooser_.split().shares(prev_n);
    if (prev_split_total >= 0.0) shares.total = prev_split_total;
    for (std::uint32_t index : infinite_area_lights_) {
        const Light& light = scene_.lights[index];
        float pdf = 0.f;
        const Rgb Le = escaped_le(scene_, light, dir, &pdf);
        if (is_black(Le)) continue;
        const float light_pdf = light_chooser_.pmf({prev_p, prev_n, &shares}, index) * pdf;
        L += Le * power_heuristic(1, prev_bsdf_pdf, s_.light_samples, light_pdf);
    }
    return L;
}

// ---------------------------------------------------------------------------------------------
// The workspace
// ---------------------------------------------------------------------------------------------
void BatchWorkspace::reserve(std::size_t n, std::size_t shadow_per, std::size_t probe_per) {
    auto grow = [](auto& v, std::size_t size) {
        if (v.size() < size) v.resize(size);
    };
    paths.reserve(n);
    grow(alive, n);
    grow(no_hit, n);
    grow(surface_row, n);
    surfaces.reserve(n, SurfaceInput::count, SurfaceOutput::count);
    bounce.table.reserve(n, BounceInput::count, BounceOutput::count);
    grow(film_x, n);
    grow(film_y, n);
    grow(dir_x, n);
    grow(dir_y, n);
    grow(dir_z, n);
    shadow.reserve(n * shadow_per);
    shadow.segments.reserve(n * shadow_per, SegmentInput::count, SegmentOutput::count);
    probe.reserve(n * probe_per);
}

// ---------------------------------------------------------------------------------------------
// Direct-light queries
// ---------------------------------------------------------------------------------------------
// Inline into the direct-light loops: a call would pass the light sample through memory.
[[gnu::always_inline]] inline Rgb Integrator::light_sample_value(const ShadingPoint& sp,
                                                                 const LightSample& ls, float pdf,
                                                                 Vec3* wi_local) const {
    const Vec3 wi = sp.si.frame.to_local(ls.wi);
    if (!leaves_on_lobe_side(sp.si, ls.wi, sp.wo, wi)) return Rgb(0.f);
    Rgb f = bsdf_f_folded(sp.m, sp.wo, wi, sp.fold_ng());
    if (is_black(f)) return Rgb(0.f);
    *wi_local = wi;
    return f * ls.L * (std::abs(wi.z) / pdf);
}

// Inline into the direct-light loops, like light_sample_value: a call would pass the light
// sample and the interaction through memory.
template <class Rec>
[[gnu::always_inline]] inline void
Integrator::queue_shadow(const SurfaceInteraction& si, const LightSample& ls, const Rgb& value,
                         std::uint32_t light, std::uint32_t path, ShadowQueue& shadow, Rec& rec) {
    const std::size_t k = shadow.add();
    if (std::isfinite(ls.dist)) { // a segment to the light's point, computed with the step's
        const std::size_t row = shadow.segments.rows++;
        const Columns<float> in{shadow.segments.in.data(), shadow.segments.stride};
        in.put(SegmentInput::p, row, si.p);
        in.put(SegmentInput::p_error, row, si.p_error);
        in.put(SegmentInput::ng, row, si.ng);
        in.put(SegmentInput::target, row, ls.p_light);
        in.put(SegmentInput::target_error, row, ls.p_error);
        in.put(SegmentInput::target_n, row, ls.n_light);
        shadow.segment[k] = std::int32_t(row);
    } else {
        set_batch_ray(shadow.ray[k], spawn_ray(si, ls.wi));
        shadow.segment[k] = -1;
    }
    shadow.path[k] = path;
    shadow.value[k] = value;
    rec.queued_shadow(k, light);
}

InfiniteShares Integrator::vertex_shares(const ShadingPoint& sp) const {
    InfiniteShares shares = light_chooser_.split().shares(sp.receive_n);
    // In irradiance units: a Lambertian surface reflects albedo / pi of any irradiance, so the
    // irradiance that it would reflect as the BSDF reflects the light is pi f |cos| L / albedo;
    // the conductor's albedo is estimated by its Fresnel reflectance at the outgoing angle.
    const float rho = std::max(kMinSplitAlbedo,
                               luminance(fresnel_conductor(std::abs(sp.wo.z), sp.m.eta, sp.m.k)));
    light_chooser_.split().weigh_directional(shares, [&](const Vec3& dir, float lum) {
        const Vec3 wi = sp.si.frame.to_local(dir);
        if (!leaves_on_lobe_side(sp.si, dir, sp.wo, wi)) return 0.f;
        return kPi * luminance(bsdf_f_folded(sp.m, sp.wo, wi, sp.fold_ng())) * std::abs(wi.z) *
               lum / rho;
    });
    return shares;
}

template <class Rec>
void Integrator::queue_one_light(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                                 ShadowQueue& shadow, VertexSamples& samples, Rec& rec) const {
    const SurfaceInteraction& si = sp.si;
    const Rgb scale = s_.light_samples == 1 ? beta : beta * (1.f / float(s_.light_samples));
    const bool pick_light = light_chooser_.size() > 1;
    const LightChoiceContext ctx{si.p, sp.receive_n, sp.split};
    for (std::uint32_t k = 0; k < std::uint32_t(s_.light_samples); ++k) {
        // One 2D point chooses the light (its first coordinate) and places the light's sample:
        // that coordinate's place within the chosen light's share, spread over the light with
        // the bits of the light_fill draw below, and the second coordinate. The points that
        // choose a light stay a stratified set over it. With one light there is nothing to
        // choose and the place is the coordinate itself: the fill is left unused.
        const std::uint32_t fill = pick_light ? samples.get_1d_bits(VertexDraw::light_fill, k) : 0;
        Bits2 u_light = samples.get_2d_bits(VertexDraw::light_point, k);
        auto pick = light_chooser_.sample(ctx, u_light.x);
        if (!pick) continue;
        if (pick_light) u_light.x = spread_within(pick->offset, pick->units, u_light.x, fill);
        const Light& light = scene_.lights[pick->index];
        // An Area light's sample is computed here, inline (the same function sample_li calls).
        std::optional<LightSample> ls = light.kind == LightKind::Area
                                            ? sample_rect(light, si.p, bits_to_unit_point(u_light))
                                            : sample_li(scene_, light, si.p, u_light);
        if (!ls || ls->pdf <= 0.f || is_black(ls->L)) continue;
        const float light_pdf = pick->pmf * ls->pdf;
        // Both factors are positive, but their product underflows for a rarely picked light
        // seen at a tiny solid-angle density; such a sample carries no usable weight.
        if (!(light_pdf > 0.f)) continue;
        Vec3 wi;
        Rgb value = light_sample_value(sp, *ls, light_pdf, &wi);
        if (is_black(value)) continue;
        // A light no ray can meet (a point, an Area record without a panel) is found by this
        // sample alone: MIS would give away a share that no BSDF-sampled ray brings back.
        if (!ls->is_delta && s_.mis && found_by_rays_[pick->index]) {
            const float pdf_bsdf = bsdf_pdf_folded(sp.m, sp.wo, wi, sp.fold_ng());
            value *= power_heuristic(s_.light_samples, light_pdf, 1, pdf_bsdf);
        }
        queue_shadow(si, *ls, value * scale, pick->index, path, shadow, rec);
    }
}

template <class Rec>
void Integrator::queue_all_lights(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                                  ShadowQueue& shadow, VertexSamples& samples, Rec& rec) const {
    const SurfaceInteraction& si = sp.si;
    std::uint32_t sample = 0; // light samples drawn so far, every light's in turn
    for (std::uint32_t index = 0; index < scene_.lights.size(); ++index) {
        const Light& light = scene_.lights[index];
        const int n = light.is_delta() ? 1 : s_.light_samples;
        const Rgb scale = beta / float(n);
        for (int k = 0; k < n; ++k) {
            const Bits2 u = samples.get_2d_bits(VertexDraw::light_point, sample++);
            std::optional<LightSample> ls = sample_li(scene_, light, si.p, u);
            if (!ls || ls->pdf <= 0.f || is_black(ls->L)) continue;
            Vec3 wi;
            const Rgb value = light_sample_value(sp, *ls, ls->pdf, &wi);
            if (is_black(value)) continue;
            queue_shadow(si, *ls, value * scale, index, path, shadow, rec);
        }
    }
}

template <class Rec>
void Integrator::queue_hemisphere(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                                  ShadowQueue& shadow, ProbeQueue& probe, VertexSamples& samples,
                                  Rec& rec) const {
    const SurfaceInteraction& si = sp.si;
    const Material& m = sp.m;
    const Vec3& wo = sp.wo;
    const float side = wo.z < 0.f ? -1.f : 1.f; // opaque surfaces are two-sided
    // A material that transmits scatters into both hemispheres: sample the whole sphere.
    const bool sphere = m.has_transmission();
    const Rgb scale = beta / float(hemisphere_budget_);
    for (int k = 0; k < hemisphere_budget_; ++k) {
        const Vec2 u = samples.get_2d(VertexDraw::hemisphere_direction, std::uint32_t(k));
        Vec3 wi;
        float pdf;
        if (sphere) {
            wi = square_to_uniform_sphere(u);
            pdf = square_to_uniform_sphere_pdf(wi);
        } else {
            wi = square_to_uniform_hemisphere(u);
            pdf = square_to_uniform_hemisphere_pdf(wi);
            wi.z *= side;
        }
        const Vec3 wi_world = si.frame.to_world(wi);
        if (!leaves_on_lobe_side(si, wi_world, wo, wi)) continue;
        const Rgb f = bsdf_f_folded(m, wo, wi, sp.fold_ng());
        if (is_black(f)) continue;
        const std::size_t q = probe.add();
        set_batch_ray(probe.ray[q], spawn_ray(si, wi_world));
        probe.path[q] = path;
        probe.weight[q] = f * scale * (std::abs(wi.z) / pdf);
    }
    // Point, spot and directional lights: one direction each, no random numbers.
    for (std::uint32_t index : delta_lights_) {
        std::optional<LightSample> ls =
            sample_li(scene_, scene_.lights[index], si.p, Vec2(0.5f, 0.5f));
        if (!ls || is_black(ls->L)) continue;
        Vec3 wi_local;
        const Rgb value = light_sample_value(sp, *ls, 1.f, &wi_local);
        if (is_black(value)) continue;
        queue_shadow(si, *ls, value * beta, index, path, shadow, rec);
    }
}

template <class Rec>
[[gnu::always_inline]] inline void
Integrator::queue_direct_light(const ShadingPoint& sp, const Rgb& beta, PathVertex v,
                               BatchWorkspace& ws, VertexSamples& samples, Rec& rec) const {
    const std::uint32_t path = std::uint32_t(v.path);
    if (s_.hemisphere)
        queue_hemisphere(sp, beta, path, ws.shadow, ws.probe, samples, rec);
    else if (s_.integrator == IntegratorKind::Direct)
        queue_all_lights(sp, beta, path, ws.shadow, samples, rec);
    else
        queue_one_light(sp, beta, path, ws.shadow, samples, rec);
}

// ---------------------------------------------------------------------------------------------
// The wavefront
// ---------------------------------------------------------------------------------------------
void Integrator::triangle_surfaces(BatchWorkspace& ws, std::size_t begin, std::size_t end) const {
    ColumnTable& table = ws.surfaces;
    table.start(end - begin);
    const Columns<float> in{table.in.data(), table.stride};
    std::size_t rows = 0; // counted here and stored once: a count in memory would stall the loop
    for (std::size_t i = begin; i < std::min(end, begin + kPrefetchIndices); ++i)
        prefetch_triangle_indices(scene_, ws.paths.rays[i]);
    for (std::size_t i = begin; i < std::min(end, begin + kPrefetchVertices); ++i)
        prefetch_triangle_vertices(scene_, ws.paths.rays[i]);
    for (std::size_t i = begin; i < end; ++i) {
        if (i + kPrefetchIndices < end)
            prefetch_triangle_indices(scene_, ws.paths.rays[i + kPrefetchIndices]);
        if (i + kPrefetchVertices < end)
            prefetch_triangle_vertices(scene_, ws.paths.rays[i + kPrefetchVertices]);
        const BatchRayHit& rh = ws.paths.rays[i];
        ws.surface_row[i] = -1; // a miss, a sphere, or a bad id make_interaction reports
        if (rh.hit.geom_id >= scene_.meshes.size()) continue;
        const Mesh& m = scene_.meshes[rh.hit.geom_id];
        if (rh.hit.prim_id >= m.triangle_count()) continue;
        const std::size_t row = rows++;
        ws.surface_row[i] = std::int32_t(row);
        const std::uint32_t* idx = &m.indices[3 * std::size_t(rh.hit.prim_id)];
        in.put(SurfaceInput::p0, row, m.positions[idx[0]]);
        in.put(SurfaceInput::p1, row, m.positions[idx[1]]);
        in.put(SurfaceInput::p2, row, m.positions[idx[2]]);
        const bool normals = m.normals.size() == m.positions.size();
        in.put(SurfaceInput::n0, row, normals ? m.normals[idx[0]] : Vec3(0.f));
        in.put(SurfaceInput::n1, row, normals ? m.normals[idx[1]] : Vec3(0.f));
        in.put(SurfaceInput::n2, row, normals ? m.normals[idx[2]] : Vec3(0.f));
        in.at(SurfaceInput::u, row) = rh.hit.u;
        in.at(SurfaceInput::v, row) = rh.hit.v;
        in.put(SurfaceInput::d, row, Vec3(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z));
    }
    table.rows = rows;
    compute_triangle_surfaces(rows, table.stride, in.data, table.out.data());
}

[[gnu::always_inline]] inline SurfaceInteraction
Integrator::interaction(std::size_t i, const BatchWorkspace& ws, Vec3* ns_interpolated) const {
    const BatchRayHit& rh = ws.paths.rays[i];
    const std::int32_t row = ws.surface_row[i];
    if (row < 0) {
        Ray ray;
        ray.o = Vec3(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z);
        ray.d = Vec3(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
        SurfaceInteraction si = make_interaction(scene_, ray, batch_hit(rh));
        *ns_interpolated = si.ns;
        adapt_shading_normal(si);
        return si;
    }
    const float* out = ws.surfaces.out.data() + row;
    const std::size_t stride = ws.surfaces.stride;
    auto get = [&](int k) {
        return Vec3(out[std::size_t(k) * stride], out[std::size_t(k + 1) * stride],
                    out[std::size_t(k + 2) * stride]);
    };
    const Mesh& m = scene_.meshes[rh.hit.geom_id];
    SurfaceInteraction si;
    si.t = rh.ray.tfar;
    si.geom_id = rh.hit.geom_id;
    si.prim_id = rh.hit.prim_id;
    si.p = get(SurfaceOutput::p);
    si.p_error = get(SurfaceOutput::p_error);
    si.ng = get(SurfaceOutput::ng);
    si.ns = get(SurfaceOutput::ns);
    si.wo = get(SurfaceOutput::wo);
    si.frame.s = get(SurfaceOutput::frame_s);
    si.frame.t = get(SurfaceOutput::frame_t);
    si.frame.n = si.ns;
    si.material = m.material;
    si.light = m.light;
    *ns_interpolated = get(SurfaceOutput::ns_interpolated);
    return si;
}

void Integrator::plan_vertex(int depth, std::vector<PlannedDraw>& plan) const {
    plan.clear();
    dims_.plan(depth, plan);
    if (has_roulette_ && depth + 1 >= s_.rr_min_depth)
        plan.push_back({dims_.dim(VertexDraw::roulette, depth), false});
    // A roulette test the previous vertex deferred to this hit (after a specular or glossy lobe).
    if (has_deferred_roulette_ && depth >= 1 && depth >= s_.rr_min_depth)
        plan.push_back({dims_.dim(VertexDraw::roulette, depth - 1), false});
}

void Integrator::start_paths(const SampleRequest* requests, std::size_t n, SampleResult* results,
                             BatchWorkspace& ws, Sampler& sampler, RenderCounters& c) const {
    const bool lens = scene_.camera.lens_radius > 0.f;
    ws.plan.clear();
    ws.plan.push_back({DimensionLayout::kFilm, true});
    if (lens) ws.plan.push_back({DimensionLayout::kLens, true});
    ws.draws.fill(sampler, requests, nullptr, nullptr, n, ws.plan);
    const int film_slot = ws.draws.slot_2d(DimensionLayout::kFilm);
    const int lens_slot = lens ? ws.draws.slot_2d(DimensionLayout::kLens) : -1;
    // Film positions, then the rays: a pinhole's directions come from one vectorised call for
    // the batch (its square roots and divisions would otherwise wait on each other).
    float* film_x = ws.film_x.data();
    float* film_y = ws.film_y.data();
    for (std::size_t i = 0; i < n; ++i) {
        film_x[i] = float(requests[i].px) + ws.draws.value(film_slot, i);
        film_y[i] = float(requests[i].py) + ws.draws.value(film_slot + 1, i);
    }
    if (!lens)
        camera_.pinhole_directions(n, film_x, film_y, ws.dir_x.data(), ws.dir_y.data(),
                                   ws.dir_z.data());
    for (std::size_t i = 0; i < n; ++i) {
        const Ray camera =
            lens ? camera_ray(film_x[i], film_y[i],
                              Vec2(ws.draws.value(lens_slot, i), ws.draws.value(lens_slot + 1, i)))
                 : camera_.pinhole_ray(Vec3(ws.dir_x[i], ws.dir_y[i], ws.dir_z[i]));
        ws.paths.start(i, camera);
        results[i] = SampleResult{};
        results[i].queries = 1;
    }
    accel_.intersect_batch(ws.paths.rays.data(), n, BatchCoherence::Coherent);
    c.camera_rays += n;
    c.rays += n;
}

// Inline into the batch loop (its one caller): a call would pass the path's sampler and
// counts through memory for every path vertex.
template <class Rec>
[[gnu::always_inline]] inline bool Integrator::shade(std::size_t i, int depth, SampleResult& result,
                                                     BatchWorkspace& ws, PathSampler& sampler,
                                                     Rec& rec) const {
    if (ws.paths.rays[i].hit.geom_id == kNoHit) {
        if (s_.integrator != IntegratorKind::Normals) arrive(i, depth, nullptr, ws, rec);
        return false;
    }
    Vec3 ns_interpolated;
    const SurfaceInteraction si = interaction(i, ws, &ns_interpolated);
    const Material& m = scene_.materials[si.material];
    rec.hit(ws.paths.request[i], depth, si);
    if (depth == 0) {
        result.fs.normal = ns_interpolated;
        result.fs.depth = si.t;
        result.fs.hit = true;
        result.fs.albedo = bsdf_albedo_hint(m);
        if (s_.integrator == IntegratorKind::Normals) {
            ws.paths.L[i] = (ns_interpolated + Vec3(1.f)) * 0.5f;
            return false;
        }
    }
    arrive(i, depth, &si, ws, rec);
    if (depth >= s_.max_depth) return false;
    ShadingPoint sp{si, m, si.frame.to_local(si.wo),
                    receiving_normal(si.ns, si.wo, m.is_rough_dielectric())};
    // Where the shading normal is the geometric one nothing leaves on the wrong side: the BSDF
    // is evaluated as it is, bit for bit.
    if (!m.is_delta() && !(si.ns.x == si.ng.x && si.ns.y == si.ng.y && si.ns.z == si.ng.z)) {
        sp.ng = si.frame.to_local(si.ng);
        sp.fold = true;
    }
    // A glossy vertex under several infinite lights, a directional one among them, weighs their
    // split by its BSDF once, for its light choice and for the MIS weight of the ray it scatters.
    if (s_.integrator == IntegratorKind::Path && weighs_directional(m)) {
        ws.vertex_split = vertex_shares(sp);
        sp.split = &ws.vertex_split;
    }
    const PathVertex v{i, depth};
    VertexSamples samples(sampler, dims_, depth);
    if (s_.integrator == IntegratorKind::Direct) return direct_vertex(sp, v, ws, samples, rec);
    return path_vertex(sp, v, ws, samples, rec);
}

template <class Rec>
[[gnu::always_inline]] inline void Integrator::arrive(std::size_t i, int depth,
                                                      const SurfaceInteraction* si,
                                                      BatchWorkspace& ws, Rec& rec) const {
    PathArrays& path = ws.paths;
    // Rays that left the camera or a delta lobe count what they find fully (next-event
    // estimation cannot sample it); so do all the direct integrator's, which follows nothing
    // else. Any other BSDF-sampled ray is MIS weighted against next-event estimation, or leaves
    // the light to it entirely (--no-mis, and -H whose hemisphere rays found it already).
    const bool full = path.specular[i] != 0;
    const bool weigh = !s_.hemisphere && s_.mis;
    if (!(full || weigh) || !accept(depth)) return;
    const BatchRay& ray = path.rays[i].ray;
    const Vec3 dir(ray.dir_x, ray.dir_y, ray.dir_z);
    const Rgb& beta = path.beta[i];
    if (!si) { // the ray left the scene
        if (!has_infinite_lights_) return;
        const Rgb Le =
            beta * (full ? escaped_radiance(scene_, dir)
                         : escaped_mis(dir, path.prev_bsdf_pdf[i], path.prev_p[i], path.prev_n[i],
                                       weigh_directional_ ? path.prev_split_total[i] : -1.0));
        path.L[i] += Le;
        rec.light(path.request[i], depth, PathEvents::kEscaped, Le);
        return;
    }
    if (si->light < 0) return;
    const Rgb Le = emitted(*si);
    if (is_black(Le)) return;
    float w = 1.f;
    if (!full) {
        const Light& light = scene_.lights[std::size_t(si->light)];
        const float light_pdf =
            light_chooser_.pmf({path.prev_p[i], path.prev_n[i]}, std::size_t(si->light)) *
            pdf_li(scene_, light, path.prev_p[i], dir, si->p, si->ng, si->prim_id);
        w = power_heuristic(1, path.prev_bsdf_pdf[i], s_.light_samples, light_pdf);
    }
    const Rgb value = beta * Le * w;
    path.L[i] += value;
    rec.light(path.request[i], depth, si->light, value);
}

[[gnu::always_inline]] inline std::optional<BsdfSample>
Integrator::sample_bsdf(const ShadingPoint& sp, VertexSamples& samples, Vec3* wi_world) const {
    Vec2 u_dir;
    Vec3 cosine;
    const bool has_cosine = samples.get_2d_cosine(VertexDraw::bsdf_direction, &u_dir, &cosine);
    const float uc = bsdf_uses_lobe_choice(sp.m) ? samples.get_1d(VertexDraw::bsdf_lobe) : 0.f;
    std::optional<BsdfSample> bs =
        bsdf_sample_folded(sp.m, sp.wo, u_dir, uc, sp.fold_ng(), has_cosine ? &cosine : nullptr);
    if (!bs || bs->pdf <= 0.f) return std::nullopt;
    *wi_world = sp.si.frame.to_world(bs->wi);
    // A direction on the other geometric side than its lobe says (possible with shading
    // normals) would leak light through the surface. The folded lobe mirrors the non-delta ones
    // onto the right side; a delta one, or one rounding leaves there, ends the path, as
    // next-event estimation drops the same directions.
    if (!leaves_on_lobe_side(sp.si, *wi_world, sp.wo, bs->wi)) return std::nullopt;
    return bs;
}

template <class Rec>
bool Integrator::direct_vertex(const ShadingPoint& sp, PathVertex v, BatchWorkspace& ws,
                               VertexSamples& samples, Rec& rec) const {
    const Rgb beta = ws.paths.beta[v.path];
    if (sp.m.is_delta()) { // follow the delta bounce to what it sees
        Vec3 wi_world;
        const std::optional<BsdfSample> bs = sample_bsdf(sp, samples, &wi_world);
        if (!bs) return false;
        ws.paths.beta[v.path] = beta * bs->weight;
        rec.scatter(ws.paths.request[v.path], v.depth, bs->flags);
        queue_bounce(sp.si, wi_world, v.path, ws.bounce);
        return true;
    }
    if (accept(v.depth + 1)) queue_direct_light(sp, beta, v, ws, samples, rec);
    return false;
}

template <class Rec>
[[gnu::always_inline]] inline bool Integrator::path_vertex(const ShadingPoint& sp, PathVertex v,
                                                           BatchWorkspace& ws,
                                                           VertexSamples& samples, Rec& rec) const {
    Rgb beta = ws.paths.beta[v.path];
    // --- Russian roulette decided by the previous vertex --------------------------------
    // The test comes after the arrival's emission: light the ray found is added with the
    // throughput it arrived with, and only what the path gathers from here on is divided by
    // the survival probability.
    const float survival = ws.paths.survival[v.path];
    if (survival < 1.f) {
        if (samples.previous().get_1d(VertexDraw::roulette) >= survival) return false;
        beta /= survival;
    }
    // --- Direct light at this vertex (scattering order depth + 1) -----------------------
    if (!sp.m.is_delta() && accept(v.depth + 1)) queue_direct_light(sp, beta, v, ws, samples, rec);
    return scatter(sp, beta, v, ws, samples, rec);
}

template <class Rec>
[[gnu::always_inline]] inline bool Integrator::scatter(const ShadingPoint& sp, const Rgb& beta,
                                                       PathVertex v, BatchWorkspace& ws,
                                                       VertexSamples& samples, Rec& rec) const {
    PathArrays& path = ws.paths;
    const std::size_t i = v.path;
    Vec3 wi_world;
    const std::optional<BsdfSample> bs = sample_bsdf(sp, samples, &wi_world);
    if (!bs || is_black(bs->f)) return false;
    Rgb next_beta = beta * bs->weight;
    path.specular[i] = (bs->flags & kSpecular) != 0;
    rec.scatter(path.request[i], v.depth, bs->flags);
    path.prev_bsdf_pdf[i] = bs->pdf;
    path.prev_p[i] = sp.si.p;
    // The orientation the light choice took here (queue_one_light), for the MIS weight of an
    // emitter this ray finds.
    path.prev_n[i] = sp.receive_n;
    if (weigh_directional_) path.prev_split_total[i] = sp.split ? sp.split->total : -1.0;
    if (bs->flags & kTransmission) path.eta_scale[i] *= bs->eta * bs->eta;

    // --- Russian roulette on throughput ------------------------------------------------
    // Survival √(throughput), as Cycles does: paths that still carry most of their energy are
    // never cut, and a survivor carries √ of its throughput instead of being raised to about
    // 1 (survival equal to the throughput), which made the heaviest samples of glossy and
    // mirror scenes. Never below the throughput rule's probability, so never an earlier
    // roulette. The estimate stays unbiased by dividing by the survival probability. After a
    // specular or glossy lobe the test waits for the next hit (path_vertex): there the light
    // the ray finds is mostly what the path brings in (next-event estimation cannot reach it
    // through such a lobe), and dividing it by the survival probability would turn a weak
    // path into a firefly.
    path.survival[i] = 1.f;
    if (v.depth + 1 >= s_.rr_min_depth) {
        const float carried = max_component(next_beta * path.eta_scale[i]);
        if (carried < 1.f) {
            const float survive = std::max(kRouletteMinSurvival, std::sqrt(carried));
            if (bs->flags & kDiffuse) {
                if (samples.get_1d(VertexDraw::roulette) >= survive) return false;
                next_beta /= survive;
            } else {
                path.survival[i] = survive;
            }
        }
    }
    path.beta[i] = next_beta;
    queue_bounce(sp.si, wi_world, i, ws.bounce);
    return true;
}

template <class Rec>
void Integrator::trace_probes(int depth, ProbeQueue& probe, SampleResult* results,
                              PathArrays& paths, RenderCounters& c, Rec& rec) const {
    accel_.intersect_batch(probe.ray.data(), probe.size, BatchCoherence::Incoherent);
    c.rays += probe.size;
    for (std::size_t k = 0; k < probe.size; ++k) {
        const BatchRayHit& rh = probe.ray[k];
        const Vec3 d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
        Rgb Li(0.f);
        std::int32_t light = PathEvents::kEscaped;
        if (rh.hit.geom_id != kNoHit) {
            Ray ray;
            ray.o = Vec3(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z);
            ray.d = d;
            const SurfaceInteraction emitter = make_interaction(scene_, ray, batch_hit(rh));
            Li = emitted(emitter);
            light = emitter.light;
        } else if (has_infinite_lights_) {
            Li = escaped_radiance(scene_, d);
        }
        const std::uint32_t p = probe.path[k];
        const Rgb value = probe.weight[k] * Li;
        paths.L[p] += value;
        if (!is_black(value)) rec.light(paths.request[p], depth + 1, light, value);
        ++results[paths.request[p]].queries;
    }
}

[[gnu::always_inline]] inline void Integrator::queue_bounce(const SurfaceInteraction& si,
                                                            const Vec3& wi_world, std::size_t i,
                                                            BounceQueue& bounce) {
    const Columns<float> in{bounce.table.in.data(), bounce.table.stride};
    in.put(BounceInput::p, i, si.p);
    in.put(BounceInput::p_error, i, si.p_error);
    in.put(BounceInput::ng, i, si.ng);
    in.put(BounceInput::wi, i, wi_world);
}

void Integrator::bounce_rays(BounceQueue& bounce, const std::uint8_t* alive, PathArrays& paths) {
    ColumnTable& table = bounce.table;
    // Every row is computed, those of paths that end too (BounceQueue).
    compute_bounce_origins(table.rows, table.stride, open_tnear(0.f), table.in.data(),
                           table.out.data());
    const Columns<const float> in{table.in.data(), table.stride};
    const Columns<const float> out{table.out.data(), table.stride};
    for (std::size_t i = 0; i < table.rows; ++i) {
        if (!alive[i]) continue;
        BatchRayHit& rh = paths.rays[i];
        write_batch_ray(rh.ray, out.vec3(BounceOutput::o, i), in.vec3(BounceInput::wi, i),
                        {out.at(BounceOutput::tnear, i), out.at(BounceOutput::tfar, i)});
        clear_batch_hit(rh.hit);
    }
}

void Integrator::shadow_segments(ShadowQueue& shadow) {
    ColumnTable& segments = shadow.segments;
    compute_shadow_segments(segments.rows, segments.stride, open_tnear(0.f), segments.in.data(),
                            segments.out.data());
    const Columns<const float> out{segments.out.data(), segments.stride};
    for (std::size_t k = 0; k < shadow.size; ++k) {
        const std::int32_t row = shadow.segment[k];
        if (row < 0) continue; // written by queue_shadow
        const std::size_t j = std::size_t(row);
        write_batch_ray(shadow.ray[k], out.vec3(SegmentOutput::o, j), out.vec3(SegmentOutput::d, j),
                        {out.at(SegmentOutput::tnear, j), out.at(SegmentOutput::tfar, j)});
    }
}

template <class Rec>
void Integrator::trace_shadows(int depth, ShadowQueue& shadow, SampleResult* results,
                               PathArrays& paths, RenderCounters& c, Rec& rec) const {
    shadow_segments(shadow);
    accel_.occluded_batch(shadow.ray.data(), shadow.size);
    c.shadow_rays += shadow.size;
    for (std::size_t k = 0; k < shadow.size; ++k) {
        const std::uint32_t p = shadow.path[k];
        if (!batch_occluded(shadow.ray[k])) {
            paths.L[p] += shadow.value[k];
            rec.shadow_arrived(paths.request[p], depth + 1, k, shadow.value[k]);
        }
        ++results[paths.request[p]].queries;
    }
}

std::size_t Integrator::finish_paths(std::size_t live, SampleResult* results,
                                     BatchWorkspace& ws) const {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < live; ++i) {
        if (!ws.alive[i]) {
            results[ws.paths.request[i]].fs.L = ws.paths.L[i];
            continue;
        }
        if (kept != i) ws.paths.move(kept, i);
        ++kept;
    }
    return kept;
}

void Integrator::render(const SampleRequest* requests, std::size_t n, SampleResult* results,
                        BatchWorkspace& ws, RenderCounters& c, PathEvents* events) const {
    // The choice is made once per batch: the render's instantiation records nothing.
    if (events) {
        EventLog log{*events, std::uint32_t(scene_.meshes.size())};
        render_batch(requests, n, results, ws, c, log);
    } else {
        NoEvents none;
        render_batch(requests, n, results, ws, c, none);
    }
}

template <class Rec>
void Integrator::render_batch(const SampleRequest* requests, std::size_t n, SampleResult* results,
                              BatchWorkspace& ws, RenderCounters& c, Rec& rec) const {
    if (n == 0) return;
    ws.reserve(n, shadow_per_vertex_, probe_per_vertex_);
    Sampler sampler(s_.sampler, s_.seed);
    start_paths(requests, n, results, ws, sampler, c);
    std::size_t live = n;
    for (int depth = 0; live > 0; ++depth) {
        // Shade every live path at its hit; queue its direct-light queries and next ray.
        ws.shadow.start(live * shadow_per_vertex_);
        ws.probe.start();
        ws.bounce.start(live);
        // The sampler values every hit may draw at this vertex, for the whole batch at once.
        for (std::size_t i = 0; i < live; ++i)
            ws.no_hit[i] = ws.paths.rays[i].hit.geom_id == kNoHit ? 1 : 0;
        plan_vertex(depth, ws.plan);
        ws.draws.fill(sampler, requests, ws.paths.request.data(), ws.no_hit.data(), live, ws.plan);
        // The surfaces of a chunk of hits, then its paths shaded while they are in the cache.
        for (std::size_t begin = 0; begin < live; begin += kSurfaceChunk) {
            const std::size_t end = std::min(live, begin + kSurfaceChunk);
            triangle_surfaces(ws, begin, end);
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t r = ws.paths.request[i];
                PathSampler path_sampler(ws.draws, i, requests[r], sampler);
                ws.alive[i] = shade(i, depth, results[r], ws, path_sampler, rec) ? 1 : 0;
                c.sampler_fallbacks += path_sampler.fallbacks();
            }
        }
        if (ws.probe.size > 0) trace_probes(depth, ws.probe, results, ws.paths, c, rec);
        if (ws.shadow.size > 0) trace_shadows(depth, ws.shadow, results, ws.paths, c, rec);
        bounce_rays(ws.bounce, ws.alive.data(), ws.paths);
        live = finish_paths(live, results, ws);
        if (live == 0) break;
        accel_.intersect_batch(ws.paths.rays.data(), live, BatchCoherence::Incoherent);
        c.rays += live;
        for (std::size_t i = 0; i < live; ++i)
            ++results[ws.paths.request[i]].queries;
    }
}

} // namespace candela
