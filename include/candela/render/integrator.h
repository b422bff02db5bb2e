#pragma once
// Radiance estimators, run a batch of camera samples at a time (a wavefront): every path of the
// batch advances one vertex per step, and each step's rays go to the accelerator together — the
// camera rays of a tile as one coherent batch, the bounce rays and the shadow rays of a step as
// incoherent batches. The shading between two traversals is one loop over the live paths with
// their state in arrays, no virtual calls, and no allocation once the workspace has grown to the
// batch size. Each path's arithmetic and the order in which its contributions are added do not
// depend on the other paths in the batch, so images stay bit-identical for any batch grouping
// that traces the same rays (any thread count, a resumed render).
#include "candela/accel/accel.h"
#include "candela/light/light_choice.h"
#include "candela/light/light_sample.h"
#include "candela/render/counters.h"
#include "candela/render/film.h"
#include "candela/render/path_state.h"
#include "candela/render/settings.h"
#include "candela/render/step_queues.h"
#include "candela/render/vertex_draws.h"
#include "candela/sampling/sample_batch.h"
#include "candela/sampling/sampler.h"
#include "candela/scene/camera.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace candela {

struct BsdfSample;
struct SurfaceInteraction;

/// One camera sample to render: a pixel of the frame (row 0 at the top) and a sample index.
using SampleRequest = SamplePoint;

/// A rendered camera sample. `fs.L` may be non-finite; the caller drops such samples.
struct SampleResult {
    FilmSample fs;
    std::uint32_t queries = 0; ///< ray queries it made, its camera ray included (relative sampler)
};

/// Where the light of every camera sample of a batch came from, as Integrator::render reports it
/// when asked (`candela probe`): each surface a path hit, how it scattered there, and each
/// contribution to its radiance with its scattering order and light. `request` is the index
/// into the batch's requests; one request's events come in path order, and its contributions
/// add up (in that order, in float) to its radiance.
struct PathEvents {
    /// A light that is not one of Scene::lights: the infinite lights a path escaped to, together.
    static constexpr std::int32_t kEscaped = -1;
    struct Hit {
        std::uint32_t request;
        int depth; ///< 0 = the camera ray's hit
        std::uint32_t material;
        std::uint32_t object; ///< mesh index, or meshes.size() + sphere index
        std::int32_t light;   ///< the light the surface emits as, -1 for none
    };
    struct Scatter {
        std::uint32_t request;
        int depth;
        std::uint8_t flags; ///< the BSDF sample's lobe (bsdf.h: kReflection, kDiffuse, ...)
    };
    struct Contribution {
        std::uint32_t request;
        int order;          ///< scattering events before the light (0: an emitter seen directly)
        std::int32_t light; ///< index into Scene::lights, or kEscaped
        Rgb value;          ///< added to the sample's radiance
    };
    std::vector<Hit> hits;
    std::vector<Scatter> scatters;
    std::vector<Contribution> contributions;
    /// Scratch of the integrator: the light of each queued shadow ray of the current step.
    std::vector<std::int32_t> shadow_light;
    void clear() {
        hits.clear();
        scatters.clear();
        contributions.clear();
    }
};

/// The memory a batch needs, kept by one thread from batch to batch so that rendering does not
/// allocate. Its contents are the integrator's business.
class BatchWorkspace {
  public:
    BatchWorkspace() = default;

  private:
    friend class Integrator;
    /// Grows every array to hold n paths with `shadow` occlusion and `probe` closest-hit
    /// direct-light queries per path.
    void reserve(std::size_t n, std::size_t shadow, std::size_t probe);

    PathArrays paths;                ///< the state of each live path (render/path_state.h)
    std::vector<std::uint8_t> alive; ///< the path continues after this step
    // The step's queues (render/step_queues.h): direct-light queries and next rays.
    ShadowQueue shadow;
    ProbeQueue probe;
    BounceQueue bounce;
    // Sampler values of one step, computed for the whole batch before its paths are shaded.
    SampleBatch draws;
    std::vector<PlannedDraw> plan;    ///< the step's requests (absolute dimensions)
    std::vector<std::uint8_t> no_hit; ///< the path's ray left the scene: it draws nothing
    // Triangle hits of one chunk of paths: corners, vertex normals, barycentrics and ray
    // direction gathered per hit, then the surfaces of all of them computed in one vectorised
    // loop.
    std::vector<std::int32_t> surface_row; ///< per path: its row of `surfaces`, or -1
    ColumnTable surfaces;
    std::vector<float> film_x, film_y;      ///< camera samples' film positions
    std::vector<float> dir_x, dir_y, dir_z; ///< and their pinhole directions
    /// The shares of the vertex being shaded where it weighs its split by its BSDF
    /// (Integrator::vertex_shares; ShadingPoint::split points here).
    InfiniteShares vertex_split;
};

class Integrator {
  public:
    Integrator(const Scene& scene, const Accel& accel, const RenderSettings& settings);

    /// Renders requests[0, n) into results[0, n), in the same order. The requests of one batch
    /// are best a tile's pixels with their samples next to each other (coherent camera rays).
    /// Each result depends only on its own request. With `events`, also appends where each
    /// sample's light came from (the same results; a separate instantiation of the batch, so
    /// a render without it does no recording work at all).
    void render(const SampleRequest* requests, std::size_t n, SampleResult* results,
                BatchWorkspace& ws, RenderCounters& counters, PathEvents* events = nullptr) const;

    /// The camera ray through film position (fx, fy) with lens sample u_lens.
    Ray camera_ray(float fx, float fy, Vec2 u_lens) const;

    /// The dimensions of a camera sample's draws (render/vertex_draws.h).
    const DimensionLayout& dimensions() const { return dims_; }

    /// Most occlusion and closest-hit queries one path makes for its direct light at one vertex.
    std::size_t shadow_queries_per_vertex() const { return shadow_per_vertex_; }
    std::size_t probe_queries_per_vertex() const { return probe_per_vertex_; }

  private:
    /// render() with recorder `rec`: NoEvents (nothing) or EventLog (PathEvents), both in
    /// integrator.cpp. Every function below that takes a `Rec& rec` reports to it.
    template <class Rec>
    void render_batch(const SampleRequest* requests, std::size_t n, SampleResult* results,
                      BatchWorkspace& ws, RenderCounters& counters, Rec& rec) const;
    /// Declares the draws of a path vertex (dims_), in dimension order: the one list of them.
    /// `all_light_samples` is the direct integrator's count per vertex (-l per non-delta light,
    /// one per delta light).
    void declare_vertex_draws(std::uint32_t all_light_samples);
    /// The camera ray of every request, traced as one coherent batch.
    void start_paths(const SampleRequest* requests, std::size_t n, SampleResult* results,
                     BatchWorkspace& ws, Sampler& sampler, RenderCounters& c) const;
    /// Gathers the triangle hits among paths [begin, end) and computes their surfaces
    /// (ws.surfaces), prefetching the triangles' memory ahead of the gathering.
    void triangle_surfaces(BatchWorkspace& ws, std::size_t begin, std::size_t end) const;
    /// make_interaction of path i's hit with adapt_shading_normal applied, from ws.surfaces
    /// when it is a triangle hit; *ns_interpolated receives the shading normal before the
    /// adaptation (the normal AOV's).
    SurfaceInteraction interaction(std::size_t i, const BatchWorkspace& ws,
                                   Vec3* ns_interpolated) const;
    /// The sampler requests path vertex `depth` may make (DimensionLayout), into ws.plan.
    void plan_vertex(int depth, std::vector<PlannedDraw>& plan) const;
    /// Shades path i at its current hit (or miss): the light it arrived at, the first hit's
    /// auxiliary values (and the normals integrator), then the estimator's work at the vertex.
    /// Returns whether the path continues.
    template <class Rec>
    bool shade(std::size_t i, int depth, SampleResult& result, BatchWorkspace& ws,
               PathSampler& sampler, Rec& rec) const;
    /// What the direct-light and scattering steps at one vertex read: the interaction (after
    /// adapt_shading_normal), its material and wo in its shading frame, transformed once.
    struct ShadingPoint {
        const SurfaceInteraction& si;
        const Material& m;
        Vec3 wo; ///< si.wo in si.frame
        /// The orientation the light choice takes here (receiving_normal()), for the choice and
        /// for the MIS weight of the ray the vertex scatters.
        Vec3 receive_n;
        /// The infinite lights' shares weighed by the BSDF (vertex_shares()) where
        /// weighs_directional(m), for the light choice and the MIS weight of the scattered ray;
        /// null elsewhere.
        const InfiniteShares* split = nullptr;
        /// si.ng in si.frame, and whether the BSDF folds across it (bsdf_f_folded): a non-delta
        /// material where the shading normal is not the geometric one.
        Vec3 ng{0.f};
        bool fold = false;
        /// The geometric normal the *_folded BSDF functions take: null where nothing folds.
        const Vec3* fold_ng() const { return fold ? &ng : nullptr; }
    };
    /// A path of the batch at one of its vertices.
    struct PathVertex {
        std::size_t path;
        int depth; ///< 0: the camera ray's hit
    };
    /// The shared arrival of both estimators: adds to path i's radiance what its ray found, the
    /// sky it escaped to (si null) or the emitter it hit, counted fully after the camera or a
    /// delta lobe, MIS weighted against next-event estimation after any other BSDF sample, and
    /// not at all when next-event estimation alone counts it (--no-mis, -H).
    template <class Rec>
    void arrive(std::size_t i, int depth, const SurfaceInteraction* si, BatchWorkspace& ws,
                Rec& rec) const;
    /// The BSDF sample of the vertex (its draws bsdf_direction, bsdf_lobe), with its world
    /// direction in *wi_world; nullopt when the material absorbs, the density is zero or the
    /// direction leaves on the other geometric side than its lobe says.
    std::optional<BsdfSample> sample_bsdf(const ShadingPoint& sp, VertexSamples& samples,
                                          Vec3* wi_world) const;
    /// The direct integrator at a hit: follows a delta bounce, or queues the direct-light
    /// estimate of every light (or -H's) and ends. Returns whether the path continues.
    template <class Rec>
    bool direct_vertex(const ShadingPoint& sp, PathVertex v, BatchWorkspace& ws,
                       VertexSamples& samples, Rec& rec) const;
    /// The path integrator at a hit: the roulette test the previous vertex deferred, next-event
    /// estimation (or -H's), then scatter(). Returns whether the path continues.
    template <class Rec>
    bool path_vertex(const ShadingPoint& sp, PathVertex v, BatchWorkspace& ws,
                     VertexSamples& samples, Rec& rec) const;
    /// BSDF sampling for the next ray and Russian roulette on the throughput it leaves
    /// (`beta`, after this vertex's roulette). Returns whether the path continues.
    template <class Rec>
    bool scatter(const ShadingPoint& sp, const Rgb& beta, PathVertex v, BatchWorkspace& ws,
                 VertexSamples& samples, Rec& rec) const;
    /// -H: traces the step's probe rays and adds the emission they find to their paths.
    template <class Rec>
    void trace_probes(int depth, ProbeQueue& probe, SampleResult* results, PathArrays& paths,
                      RenderCounters& c, Rec& rec) const;
    /// Queues path i's next ray, from `si` along wi_world; bounce_rays() writes it.
    static void queue_bounce(const SurfaceInteraction& si, const Vec3& wi_world, std::size_t i,
                             BounceQueue& bounce);
    /// Computes the step's queued bounce rays and writes those of the paths that continue
    /// (alive[i] != 0) into their records.
    static void bounce_rays(BounceQueue& bounce, const std::uint8_t* alive, PathArrays& paths);
    /// Computes the step's shadow segments and writes them into their rays.
    static void shadow_segments(ShadowQueue& shadow);
    /// Traces the step's shadow rays (next-event estimation, delta lights under -H) and adds the
    /// value of each unoccluded one to its path.
    template <class Rec>
    void trace_shadows(int depth, ShadowQueue& shadow, SampleResult* results, PathArrays& paths,
                       RenderCounters& c, Rec& rec) const;
    /// Finished paths among the first `live` hand in their radiance; the others move up, in
    /// order. Returns how many continue.
    std::size_t finish_paths(std::size_t live, SampleResult* results, BatchWorkspace& ws) const;
    /// The direct-light estimate at vertex v (scattering order depth + 1) from its dimensions:
    /// -H's hemisphere rays, every light (direct integrator) or one chosen light (path).
    template <class Rec>
    void queue_direct_light(const ShadingPoint& sp, const Rgb& beta, PathVertex v,
                            BatchWorkspace& ws, VertexSamples& samples, Rec& rec) const;
    /// Next-event estimation with one light chosen by power: queues the shadow ray of each of
    /// the -l samples, valued f * Li * cos / pdf, MIS weighted against BSDF sampling when MIS is
    /// on, times beta / -l.
    template <class Rec>
    void queue_one_light(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                         ShadowQueue& shadow, VertexSamples& samples, Rec& rec) const;
    /// The direct integrator's estimate: every light, -l samples per non-delta light.
    template <class Rec>
    void queue_all_lights(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                          ShadowQueue& shadow, VertexSamples& samples, Rec& rec) const;
    /// -H: hemisphere rays (the whole sphere for a material that transmits) that find the
    /// emitters rays can hit, plus one shadow ray per point, spot and directional light, which
    /// hemisphere sampling cannot find.
    template <class Rec>
    void queue_hemisphere(const ShadingPoint& sp, const Rgb& beta, std::uint32_t path,
                          ShadowQueue& shadow, ProbeQueue& probe, VertexSamples& samples,
                          Rec& rec) const;
    /// Queues the shadow ray of light sample `ls` of light `light` with value `value` (already
    /// weighted).
    template <class Rec>
    static void queue_shadow(const SurfaceInteraction& si, const LightSample& ls, const Rgb& value,
                             std::uint32_t light, std::uint32_t path, ShadowQueue& shadow,
                             Rec& rec);
    /// f * Li * |cos| / pdf of one light sample, or 0 when the BSDF does not scatter toward it
    /// or the sample leaves on the wrong geometric side; wi_local receives the local direction.
    Rgb light_sample_value(const ShadingPoint& sp, const LightSample& ls, float pdf,
                           Vec3* wi_local) const;
    /// Radiance emitted by the surface at `si` toward -ray direction `wo`.
    Rgb emitted(const SurfaceInteraction& si) const;
    /// Radiance of the infinite area lights seen by a BSDF-sampled ray that left the scene
    /// along `dir`, MIS weighted against light sampling light by light (each infinite light is
    /// its own light-sampling strategy). `prev_bsdf_pdf` is the density of the BSDF sample,
    /// `prev_p` and `prev_n` the point it left and the orientation its light choice took.
    Rgb escaped_mis(const Vec3& dir, float prev_bsdf_pdf, const Vec3& prev_p, const Vec3& prev_n,
                    double prev_split_total) const;
    /// Whether the infinite lights' split weighs its directional lights by the BSDF at a vertex
    /// of material m (vertex_shares()).
    bool weighs_directional(const Material& m) const {
        return weigh_directional_ && m.kind == BsdfKind::Microfacet;
    }
    /// The infinite lights' shares at a vertex (at its orientation sp.receive_n), with each
    /// directional light weighed by what the BSDF reflects of it (weighs_directional()).
    InfiniteShares vertex_shares(const ShadingPoint& sp) const;
    /// Whether light that scattered `order` times is written (-o, --light-paths): a bit of
    /// accepted_orders_ for the orders it holds, accept_order() beyond them.
    bool accept(int order) const {
        return order < kCachedOrders ? ((accepted_orders_ >> order) & 1u) != 0
                                     : accept_order(order);
    }
    /// The rule accept() caches, from the settings.
    bool accept_order(int order) const;

    const Scene& scene_;
    const Accel& accel_;
    RenderSettings s_;
    LightChooser light_chooser_;
    CameraProjection camera_;
    bool has_infinite_lights_ = false;
    bool weigh_directional_ = false; ///< light_chooser_.split().has_directional()
    int hemisphere_budget_ = 1;
    std::vector<std::uint32_t> infinite_area_lights_; ///< Ambient and Environment lights
    std::vector<std::uint32_t> delta_lights_;         ///< Point, Spot and Directional lights
    /// Per scene light: 1 when a ray can meet it (light_found_by_rays), so that next-event
    /// estimation of it is MIS weighted against BSDF sampling.
    std::vector<std::uint8_t> found_by_rays_;
    DimensionLayout dims_;
    /// The path integrator's roulette number is drawn from vertex rr_min_depth - 1 on (at the
    /// next vertex when the test was deferred past a specular or glossy lobe).
    bool has_roulette_ = false;
    /// Some material scatters through a specular or glossy lobe, after which the roulette test
    /// waits for the next hit.
    bool has_deferred_roulette_ = false;
    std::size_t shadow_per_vertex_ = 0, probe_per_vertex_ = 0;
    /// Orders whose accept() answer is a bit of accepted_orders_: the settings' rule is a few
    /// branches on three settings, asked two or three times per path vertex.
    static constexpr int kCachedOrders = 64;
    std::uint64_t accepted_orders_ = 0; ///< bit k: accept_order(k)
};

} // namespace candela
