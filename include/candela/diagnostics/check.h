#pragma once
// Cross-checking accelerators against each other on the rays a renderer actually traces:
// camera rays, incoherent bounce rays, shadow rays, and rays aimed exactly at triangle edges
// and vertices. Every disagreement is classified; the worst ones can be replayed.
#include "candela/accel/accel.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

enum class CheckRayKind { Camera = 0, Bounce, Shadow, Edge, Count };
constexpr int kCheckRayKindCount = static_cast<int>(CheckRayKind::Count);
const char* check_ray_kind_name(CheckRayKind k);

/// How two accelerators' answers for one ray compare.
///  - Agree:     both miss, or both hit the same primitive at t within kTieRelTolerance.
///  (Hits at an end of the ray's interval also count as Graze: in or out is decided there by
///  rounding.)
///  - Tie:       different primitives at t within kTieRelTolerance (e.g. a shared edge).
///  - Graze:     different answers where the hit that one backend reports and the other lacks
///               lies within kGrazeBarycentric (or kGrazeRelDistance) of a triangle edge or
///               vertex, or grazes a sphere within kGrazeSphereCos: an edge decision taken
///               differently in float.
///  - Precision: the same primitive at t differing beyond kTieRelTolerance.
///  - Leak:      one backend hits a primitive well inside its edges (or nearer than the
///               other's hit) that the other backend misses: a genuine traversal or test fault.
enum class HitClass { Agree = 0, Tie, Graze, Precision, Leak, Count };
constexpr int kHitClassCount = static_cast<int>(HitClass::Count);
const char* hit_class_name(HitClass c);

/// Relative t difference that still counts as "the same distance": float triangle tests round
/// t with a relative error of a few ulps (~1e-7) that grows with the conditioning of the
/// hit; 1e-5 (about 80 ulps) separates rounding from a genuinely different surface. It is
/// relative to t + (|o|_inf + |o + t d|_inf) / |d|, the magnitudes t is computed from, and
/// divided by |cos(d, ng)| (floored at 1e-3), which amplifies those errors at grazing angles.
constexpr float kTieRelTolerance = 1e-5f;
/// A hit whose smallest barycentric is below this is "on an edge": float barycentrics of
/// different but correct triangle tests differ by ~1e-7 relative; two orders of magnitude of
/// margin keep true interior misses (leaks) out of this class.
constexpr float kGrazeBarycentric = 1e-4f;
/// A hit closer to a triangle edge than this times (|o|_inf + |p|_inf) is "on an edge" too:
/// on small triangles a few ulps of the coordinates (~6e-8 relative each) are many
/// barycentric units; 1e-5 is ~170 ulps, the scale at which float tests that compute the
/// edge functions differently (Embree vs candela) were seen to decide an edge differently.
/// Also divided by |cos(d, ng)| (floored at 1e-3): at grazing angles a position error along
/// the ray moves the hit across the surface by 1 / |cos| as much.
constexpr float kGrazeRelDistance = 1e-5f;
/// A sphere hit with |cos(d, n)| below this is tangent: the discriminant is then tiny and its
/// sign is decided by rounding.
constexpr float kGrazeSphereCos = 1e-3f;

/// Classifies the answers `a` (reference) and `b` of two backends for `ray`. When non-null,
/// `abs_dt` receives |t_a - t_b| (0 when both miss, +inf when exactly one hits).
HitClass classify_hits(const Scene& scene, const Ray& ray, const std::optional<Hit>& a,
                       const std::optional<Hit>& b, float* abs_dt = nullptr);

// ---- ray generation (shared with the benchmark and the tests) --------------------------------

/// The render camera's rays (CameraProjection, lens centre) through the pixel centres of a
/// width x height grid of scene.camera, row-major from the top row as in the rendered image;
/// interval [znear, zfar], unit directions.
std::vector<Ray> make_camera_rays(const Scene& scene, int width, int height);
/// Rays leaving random surface points (uniform over primitives, then over the primitive) in
/// random directions of the hemisphere of +ng or -ng (chosen at random, so rays both leave and
/// enter closed meshes), with robustly offset origins; [0, inf).
std::vector<Ray> make_bounce_rays(const Scene& scene, std::size_t count, std::uint64_t seed);
/// Shadow rays from random surface points to sample points of rect, point, spot, mesh and
/// sphere lights (random pairs of surface points when the scene has none), built with
/// spawn_ray_between(): a hit means occlusion.
std::vector<Ray> make_shadow_rays(const Scene& scene, std::size_t count, std::uint64_t seed);
/// Rays aimed exactly at a triangle vertex (one in three) or a point on an edge, from a random
/// point at a random distance off the surface on either side; [0, inf). Empty without
/// triangles.
std::vector<Ray> make_edge_rays(const Scene& scene, std::size_t count, std::uint64_t seed);

// ---- the check -----------------------------------------------------------------------------

struct CheckOptions {
    /// Backends to compare. The reference is brute when listed and affordable, else builtin
    /// when listed, else the first one.
    std::vector<AccelKind> accels = {AccelKind::Embree, AccelKind::Builtin, AccelKind::Brute};
    TriangleTest triangle = TriangleTest::MollerTrumbore; ///< for builtin and brute
    bool embree_robust = false;
    int camera_width = 320; ///< camera rays: a width x height pixel-centre grid
    int camera_height = 240;
    std::size_t bounce_rays = 200000;
    std::size_t shadow_rays = 200000;
    std::size_t edge_rays = 100000;
    std::uint64_t seed = 1;
    int threads = 0; ///< 0 = all available
    /// Brute is dropped when triangles x rays exceeds this many triangle tests (about a
    /// minute of one core).
    double brute_max_tests = 2e10;
    std::string worst_cases_path; ///< when set, the worst cases are written there
    /// Worst cases kept, printed and written: a handful to replay; `check --worst-cases N` asks
    /// for more.
    std::size_t worst_cases = 5;
};

/// One disagreement, replayable as the line "ox oy oz dx dy dz tmin tmax".
struct CheckCase {
    CheckRayKind kind = CheckRayKind::Camera;
    HitClass cls = HitClass::Agree;
    std::string other; ///< the backend compared against the reference
    Ray ray;
    float abs_dt = 0.f;
    std::string line() const;
};

/// Results of comparing the reference with one other backend.
struct CheckPair {
    std::string reference, other;
    /// counts[kind][class]
    std::array<std::array<std::uint64_t, kHitClassCount>, kCheckRayKindCount> counts{};
    std::uint64_t disagreements() const;
    std::uint64_t rays() const;
};

struct CheckReport {
    std::string scene;
    std::size_t triangles = 0, spheres = 0;
    std::vector<std::string> accels; ///< the backends actually run, reference first
    std::vector<std::string> notes;  ///< e.g. why brute was dropped
    std::array<std::uint64_t, kCheckRayKindCount> rays{};
    std::vector<CheckPair> pairs;
    /// Per backend (same order as accels): rays where occluded(r) != intersect(r).has_value().
    std::vector<std::uint64_t> occlusion_mismatches;
    std::vector<CheckCase> worst; ///< leaks first, then by |dt|
    double seconds = 0.0;

    /// True when no pair has a Leak and no backend's occluded() contradicts its intersect().
    bool ok() const;
    std::string to_text() const; ///< a table: kind x class per pair
    std::string to_json() const;
};

/// Runs the cross-check. Throws Error(Io) when the worst-case file cannot be written and
/// Error(Usage) for an empty backend list.
CheckReport run_check(const Scene& scene, const CheckOptions& opt);

} // namespace candela
