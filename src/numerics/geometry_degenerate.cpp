// Grazing and degenerate rays and triangles, judged against the exact answer or the
// double-precision brute force.
#include "candela/accel/brute.h"
#include "candela/accel/triangle.h"
#include "candela/diagnostics/check.h"
#include "candela/numerics/double_brute.h"
#include "candela/numerics/geometry_cases.h"
#include "candela/scene/interaction.h"
#include "candela/scene/scene.h"
#include "candela/scene/scene_editor.h"
#include "geometry_support.h"

#include <fmt/format.h>
#include <functional>
#include <memory>

namespace candela::numerics {

using namespace detail;

namespace {

const char* const kGroup = "grazing and degenerate";

/// Directions closer than this cosine to a triangle's plane are not "leaving" or "arriving":
/// they belong to the in-plane cases; 0.05 is about 3 degrees.
constexpr float kMinLeaveCos = 0.05f;

/// What a judge says about one backend's answer to one ray.
enum class Verdict { Ok, Bad };

/// judge(ray index, accel, hit) -> verdict.
using Judge = std::function<Verdict(std::size_t, const std::optional<Hit>&)>;

Scene scene_of(std::vector<Mesh> meshes) {
    Scene s;
    SceneEditor editor(s);
    editor.add_material(Material{});
    for (Mesh& m : meshes)
        editor.add_mesh(std::move(m));
    editor.finalize();
    return s;
}

Mesh mesh_of(const std::vector<Vec3>& p, const std::vector<std::uint32_t>& idx) {
    Mesh m;
    m.positions.assign(p.begin(), p.end());
    m.indices = idx;
    return m;
}

/// Runs `rays` through every backend; `required(backend)` says whether zero bad answers is a
/// requirement for it. A non-finite t, u or v is always bad and always a requirement.
void run_case(std::vector<StressResult>& out, const std::string& name, const std::string& expected,
              const Scene& scene, const std::vector<Ray>& rays, const Judge& judge,
              const std::function<bool(const Backend&)>& required) {
    for (const Backend& b : all_backends()) {
        const std::unique_ptr<Accel> accel = make_accel(scene, b.opt);
        std::size_t hits = 0, bad = 0, non_finite = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const std::optional<Hit> h = accel->intersect(rays[i]);
            if (h) ++hits;
            if (non_finite_hit(h)) ++non_finite;
            if (judge(i, h) == Verdict::Bad) ++bad;
        }
        const bool req = required(b);
        const std::string measured =
            fmt::format("{} wrong of {} rays ({} hits); non-finite hits {}", bad, rays.size(),
                         hits, non_finite);
        StressResult r = make_row(kGroup, name, b.name, expected + ", no non-finite hit", measured,
                                  req, bad == 0 && non_finite == 0);
        if (!req && non_finite > 0) {
            // Non-finite output is never acceptable, even where the answer itself is free.
            r.reported_only = false;
            r.pass = false;
            r.expected = "no non-finite hit; " + expected + " not required";
        }
        out.push_back(r);
    }
}

bool all_backends_required(const Backend&) {
    return true;
}
bool none_required(const Backend&) {
    return false;
}
bool not_watertight(const Backend& b) {
    return b.opt.kind == AccelKind::Embree || b.opt.triangle != TriangleTest::Watertight;
}

// ---- the double-precision ground truth --------------------------------------------------------

/// Where the ray as given (exact float inputs, evaluated in double) meets the plane of
/// triangle j of m: signed distance of that point from the triangle's nearest edge (negative
/// outside), |cos| of the ray with the plane, and the magnitude |o|_inf + |q|_inf the float
/// computation rounds against. Returns false when the ray is parallel to the plane.
struct PlaneHitD {
    double t = 0.0, edge_dist = 0.0, abs_cos = 0.0, magnitude = 0.0;
};
bool plane_hit_double(const Ray& ray, const Mesh& m, std::size_t j, PlaneHitD& out) {
    const Vec3d p0(m.positions[m.indices[3 * j]]), p1(m.positions[m.indices[3 * j + 1]]),
        p2(m.positions[m.indices[3 * j + 2]]);
    const Vec3d o(ray.o), d(ray.d);
    const Vec3d n = cross(p1 - p0, p2 - p0);
    const double nl = length(n), dn = dot(d, n);
    if (!(nl > 0.0) || dn == 0.0) return false;
    out.t = dot(p0 - o, n) / dn;
    const Vec3d q = o + d * out.t;
    const Vec3d ps[3] = {p0, p1, p2};
    double best = 1e300;
    for (int i = 0; i < 3; ++i) {
        const Vec3d& a = ps[(i + 1) % 3];
        const Vec3d& b = ps[(i + 2) % 3];
        // Barycentric of vertex i times its altitude = signed distance to the opposite edge.
        const double bi = dot(cross(a - q, b - q), n) / (nl * nl);
        best = std::min(best, bi * nl / length(b - a));
    }
    out.edge_dist = best;
    out.abs_cos = std::abs(dn) / (nl * length(d));
    const auto inf_norm = [](const Vec3d& v) {
        return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
    };
    out.magnitude = inf_norm(o) + inf_norm(q);
    return true;
}

/// The float answer may differ from the double one only for hits within the float error of an
/// edge: kGrazeRelDistance (check.h, ~170 ulps) of the magnitudes, divided by |cos| because a
/// position error along the ray moves the plane point by 1 / |cos| (not floored: for rays
/// within rounding of the plane no float answer is decisive).
double edge_margin(const PlaneHitD& p) {
    constexpr double kTinyCos = 1e-300; // only avoids a division by zero
    return static_cast<double>(kGrazeRelDistance) * p.magnitude / std::max(p.abs_cos, kTinyCos);
}

/// Judges a float answer against the double brute force on the same float ray. Wrong: the
/// double hit is clearly inside its triangle (beyond edge_margin) and the float answer misses
/// it or hits another mesh nearer/farther than the tie tolerance; or the float answer hits a
/// triangle the double ray clearly misses; or t differs beyond kTieRelTolerance (relative to
/// t + magnitudes, over |cos|, as in check.h).
Judge double_truth_judge(const Scene& scene, const std::vector<Ray>& rays) {
    auto truth = std::make_shared<std::vector<std::optional<HitD>>>();
    const DoubleBruteAccel ref(scene);
    for (const Ray& r : rays)
        truth->push_back(ref.intersect_double(r));
    return [truth, &scene, &rays](std::size_t i, const std::optional<Hit>& h) {
        const std::optional<HitD>& hd = (*truth)[i];
        const Ray& r = rays[i];
        if (hd) {
            PlaneHitD p;
            if (!plane_hit_double(r, scene.meshes[hd->geom_id], hd->prim_id, p)) return Verdict::Ok;
            const bool clear = p.edge_dist >= edge_margin(p);
            if (!h) return clear ? Verdict::Bad : Verdict::Ok;
            const double tol = static_cast<double>(kTieRelTolerance) *
                               (hd->t + p.magnitude / length(Vec3d(r.d))) /
                               std::max(p.abs_cos, 1e-3);
            if (std::abs(static_cast<double>(h->t) - hd->t) > tol) {
                // A different answer: wrong unless both are edge decisions.
                PlaneHitD pf;
                const bool f_clear =
                    plane_hit_double(r, scene.meshes[h->geom_id], h->prim_id, pf) &&
                    pf.edge_dist >= edge_margin(pf);
                return (clear || f_clear) ? Verdict::Bad : Verdict::Ok;
            }
            return Verdict::Ok;
        }
        if (!h) return Verdict::Ok;
        PlaneHitD pf;
        if (!plane_hit_double(r, scene.meshes[h->geom_id], h->prim_id, pf)) return Verdict::Ok;
        // The double ray misses: the float hit is wrong when it is clearly outside.
        return pf.edge_dist <= -edge_margin(pf) ? Verdict::Bad : Verdict::Ok;
    };
}

Verdict any_hit_is_bad(std::size_t, const std::optional<Hit>& h) {
    return h ? Verdict::Bad : Verdict::Ok;
}

/// A random direction with |dot(w, n)| >= kMinLeaveCos on the side `side` (+1 / -1) of unit n.
Vec3 leaving_direction(SplitMix64& rng, const Vec3& n, float side) {
    for (;;) {
        Vec3 w = square_to_uniform_sphere(rng.next_vec2());
        const float c = dot(w, n);
        if (std::abs(c) < kMinLeaveCos) continue;
        return c * side < 0.f ? -w : w;
    }
}

// The tilted quad used by several cases: p0 + a e1 + b e2 for a, b in [0, 1].
const Vec3 kTiltP0(0.1f, 0.2f, 0.3f), kTiltE1(1.2f, 0.2f, -0.5f), kTiltE2(0.1f, 0.9f, 0.6f);

Mesh tilted_quad() {
    return mesh_of({kTiltP0, kTiltP0 + kTiltE1, kTiltP0 + kTiltE1 + kTiltE2, kTiltP0 + kTiltE2},
                   {0, 1, 2, 0, 2, 3});
}

Mesh unit_quad_z0() {
    return mesh_of({Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)},
                   {0, 1, 2, 0, 2, 3});
}

} // namespace

std::vector<StressResult> run_degenerate_cases(StressSize size) {
    std::vector<StressResult> out;
    const std::size_t n = size == StressSize::Quick ? 4000 : 20000;

    // 1. Rays parallel to an axis-aligned quad, in its plane or just off it.
    {
        const Scene s = scene_of({unit_quad_z0()});
        SplitMix64 rng = case_rng(21);
        std::vector<Ray> rays;
        const float heights[3] = {0.f, 1e-7f, -1e-7f};
        for (std::size_t i = 0; i < n; ++i) {
            const float phi = 6.2831853f * rng.next_float();
            const float z = heights[i % 3];
            const Vec3 o(3.f * std::cos(phi), 3.f * std::sin(phi), z);
            const Vec3 target(2.f * rng.next_float() - 1.f, 2.f * rng.next_float() - 1.f, z);
            Vec3 d = target - o;
            d.z = 0.f;
            rays.push_back(Ray{o, normalize(d), 0.f, kInf});
        }
        run_case(out, "rays parallel to an axis-aligned quad (in its plane, or 1e-7 off it)",
                 "miss (the determinant / all edge functions are exactly 0)", s, rays,
                 any_hit_is_bad, all_backends_required);
    }
    // 2. Rays in the plane of a tilted quad, up to the rounding of their direction.
    {
        const Scene s = scene_of({tilted_quad()});
        SplitMix64 rng = case_rng(22);
        std::vector<Ray> rays;
        for (std::size_t i = 0; i < n; ++i) {
            const float a = -0.5f - rng.next_float(), b = 2.f * rng.next_float() - 0.5f;
            const Vec3 o = kTiltP0 + kTiltE1 * a + kTiltE2 * b;
            const Vec3 target = kTiltP0 + kTiltE1 * (0.1f + 0.8f * rng.next_float()) +
                                kTiltE2 * (0.1f + 0.8f * rng.next_float());
            rays.push_back(Ray{o, normalize(target - o), 0.f, kInf});
        }
        run_case(out, "rays in the plane of a tilted quad (in-plane up to rounding)",
                 "agree with double precision where the answer is not an edge decision", s, rays,
                 double_truth_judge(s, rays), none_required);
    }
    // 3. Rays starting exactly on an axis-aligned surface (t = 0 exactly).
    {
        const Scene s = scene_of({unit_quad_z0()});
        SplitMix64 rng = case_rng(23);
        std::vector<Ray> rays;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 o(1.8f * rng.next_float() - 0.9f, 1.8f * rng.next_float() - 0.9f, 0.f);
            const Vec3 w = leaving_direction(rng, Vec3(0, 0, 1), i % 2 ? 1.f : -1.f);
            rays.push_back(Ray{o, w, 0.f, kInf});
        }
        // Embree's robust mode accepts t == tnear; embree_accel.cpp passes the next float above
        // tmin, so this is required of every backend (before that, every such ray re-hit).
        run_case(out, "ray origins exactly on an axis-aligned quad, leaving either side",
                 "no hit (t = 0 is outside the open interval (tmin, tmax])", s, rays,
                 any_hit_is_bad, all_backends_required);
    }
    // 4. Origins on a tilted quad computed from barycentrics (off the plane by rounding), no
    //    offset; then the same surface points reached by a ray and left with spawn_ray().
    {
        const Scene s = scene_of({tilted_quad()});
        const Vec3 nrm = normalize(cross(kTiltE1, kTiltE2));
        SplitMix64 rng = case_rng(24);
        std::vector<Ray> rays;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 o = kTiltP0 + kTiltE1 * (0.05f + 0.9f * rng.next_float()) +
                           kTiltE2 * (0.05f + 0.9f * rng.next_float());
            rays.push_back(Ray{o, leaving_direction(rng, nrm, i % 2 ? 1.f : -1.f), 0.f, kInf});
        }
        run_case(out, "ray origins on a tilted quad (rounded barycentric point), no offset",
                 "no re-hit of the quad", s, rays, any_hit_is_bad, none_required);

        // The robust offset: per backend, hit the quad from a random side, build the
        // interaction, leave along a random direction of either side.
        for (const Backend& b : all_backends()) {
            const std::unique_ptr<Accel> accel = make_accel(s, b.opt);
            SplitMix64 r2 = case_rng(25);
            std::size_t spawned = 0, rehits = 0, non_finite = 0;
            for (std::size_t i = 0; i < n; ++i) {
                const Vec3 target = kTiltP0 + kTiltE1 * (0.05f + 0.9f * r2.next_float()) +
                                    kTiltE2 * (0.05f + 0.9f * r2.next_float());
                const Vec3 from = target + leaving_direction(r2, nrm, i % 2 ? 1.f : -1.f);
                const Ray in{from, normalize(target - from), 0.f, kInf};
                const std::optional<Hit> h = accel->intersect(in);
                if (!h) continue;
                const SurfaceInteraction si = make_interaction(s, in, *h);
                const Vec3 w = leaving_direction(r2, si.ng, (i / 2) % 2 ? 1.f : -1.f);
                const std::optional<Hit> h2 = accel->intersect(spawn_ray(si, w));
                ++spawned;
                if (h2) ++rehits;
                if (non_finite_hit(h2)) ++non_finite;
            }
            const bool enough = spawned >= n * 9 / 10;
            out.push_back(make_row(kGroup,
                                   "rays leaving a tilted quad via spawn_ray() (robust offset)",
                                   b.name, "no re-hit, >= 90% of aimed rays hit",
                                   fmt::format("{} re-hits of {} spawned rays; non-finite {}",
                                                rehits, spawned, non_finite),
                                   true, enough && rehits == 0 && non_finite == 0));
        }
    }
    // 5. A triangle collapsed to a point, rays aimed exactly at it.
    {
        const Vec3 p(0.3f, 0.2f, 0.1f);
        const Scene s = scene_of({mesh_of({p, p, p}, {0, 1, 2})});
        SplitMix64 rng = case_rng(26);
        std::vector<Ray> rays;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 o =
                p + square_to_uniform_sphere(rng.next_vec2()) * (0.5f + 2.f * rng.next_float());
            rays.push_back(Ray{o, normalize(p - o), 0.f, kInf});
        }
        run_case(out, "zero-area triangle: three equal vertices, rays aimed at it",
                 "miss (zero determinant / zero edge functions)", s, rays, any_hit_is_bad,
                 all_backends_required);
    }
    // 6. Collinear vertices on a coordinate axis and on a diagonal, rays aimed at the segment.
    {
        const Scene axis = scene_of({mesh_of(
            {Vec3(0.f, 0.f, 0.f), Vec3(1.f, 0.f, 0.f), Vec3(0.25f, 0.f, 0.f)}, {0, 1, 2})});
        const Scene diag = scene_of(
            {mesh_of({Vec3(1.f, 2.f, 3.f), Vec3(2.f, 4.f, 6.f), Vec3(3.f, 6.f, 9.f)}, {0, 1, 2})});
        SplitMix64 rng = case_rng(27);
        std::vector<Ray> ra, rd;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 ta(rng.next_float(), 0.f, 0.f);
            const Vec3 oa =
                ta + square_to_uniform_sphere(rng.next_vec2()) * (0.5f + 2.f * rng.next_float());
            ra.push_back(Ray{oa, normalize(ta - oa), 0.f, kInf});
            const float k = 1.f + 2.f * rng.next_float();
            const Vec3 td(k, 2.f * k, 3.f * k);
            const Vec3 od =
                td + square_to_uniform_sphere(rng.next_vec2()) * (0.5f + 2.f * rng.next_float());
            rd.push_back(Ray{od, normalize(td - od), 0.f, kInf});
        }
        run_case(out, "zero-area triangle: collinear vertices along the x axis",
                 "miss (Moller-Trumbore: determinant exactly 0)", axis, ra, any_hit_is_bad,
                 [](const Backend& b) {
                     return b.opt.kind != AccelKind::Embree &&
                            b.opt.triangle == TriangleTest::MollerTrumbore;
                 });
        run_case(out, "zero-area triangle: exactly collinear vertices on a diagonal", "miss", diag,
                 rd, any_hit_is_bad, none_required);
    }
    // 7. Needle triangles: height 1e-6 and 1e-4 of their length.
    for (float h : {1e-4f, 1e-6f}) {
        const Scene s = scene_of(
            {mesh_of({Vec3(0.f, 0.f, 0.f), Vec3(1.f, 0.f, 0.f), Vec3(0.5f, h, 0.f)}, {0, 1, 2})});
        SplitMix64 rng = case_rng(28);
        std::vector<Ray> rays;
        for (std::size_t i = 0; i < n; ++i) {
            // A point of the triangle away from its edges (barycentrics >= 0.05), in double.
            const double b1 = 0.05 + 0.45 * rng.next_double(), b2 = 0.05 + 0.45 * rng.next_double();
            const Vec3 target(Vec3d(1.0, 0.0, 0.0) * b1 + Vec3d(0.5, double(h), 0.0) * b2);
            Vec3 w = square_to_uniform_sphere(rng.next_vec2());
            if (std::abs(w.z) < 0.2f) w.z = w.z < 0.f ? -0.2f : 0.2f;
            const Vec3 o = target + normalize(w) * (0.5f + 2.f * rng.next_float());
            rays.push_back(Ray{o, normalize(target - o), 0.f, kInf});
        }
        // On a needle the watertight test's edge functions are of the order of the needle's
        // width, so their rounding moves t beyond the tolerance on a few rays: reported, not
        // required.
        run_case(out, fmt::format("needle triangle, height {:g} x length, rays at its interior", h),
                 "hit/miss and t as in double precision (edge decisions excepted)", s, rays,
                 double_truth_judge(s, rays), not_watertight);
    }
    // 8. Squares of side 1e-6 .. 1e6 in one scene, rays from near (a few sides away) and from
    //    unit distance.
    {
        std::vector<Mesh> quads;
        for (int k = -6; k <= 6; ++k) {
            const float side = std::pow(10.f, static_cast<float>(k));
            const Vec3 lo(2.5f * side, -0.5f * side, 0.f), hi(3.5f * side, 0.5f * side, 0.f);
            quads.push_back(
                mesh_of({lo, Vec3(hi.x, lo.y, 0.f), Vec3(hi.x, hi.y, 0.f), Vec3(lo.x, hi.y, 0.f)},
                        {0, 1, 2, 0, 2, 3}));
        }
        const Scene s = scene_of(quads);
        for (int far = 0; far < 2; ++far) {
            SplitMix64 rng = case_rng(29 + far);
            std::vector<Ray> rays;
            for (std::size_t i = 0; i < n; ++i) {
                const int k = static_cast<int>(rng.next_below(13)) - 6;
                const double side = std::pow(10.0, k);
                const Vec3 target(Vec3d(side * (2.55 + 0.9 * rng.next_double()),
                                        side * (-0.45 + 0.9 * rng.next_double()), 0.0));
                Vec3 w = square_to_uniform_sphere(rng.next_vec2());
                if (std::abs(w.z) < 0.2f) w.z = w.z < 0.f ? -0.2f : 0.2f;
                const float dist =
                    (far ? 1.f : static_cast<float>(side)) * (1.f + 2.f * rng.next_float());
                const Vec3 o = target + normalize(w) * dist;
                rays.push_back(Ray{o, normalize(target - o), 0.f, kInf});
            }
            if (far) {
                // Rays from 1..3 units away: the 1e-6 squares are 1e-6 of the distance, the 1e6
                // ones 1e6 times it. The watertight test's float bound on t grows with the vertex
                // coordinates relative to the origin; hits it cannot certify are decided in
                // double, so this is required of every backend.
                run_case(out,
                         "squares of side 1e-6 to 1e6 in one scene, rays from 1 to 3 units away",
                         "hit/miss and t as in double precision (edge decisions excepted)", s, rays,
                         double_truth_judge(s, rays), all_backends_required);
            } else {
                run_case(out,
                         "squares of side 1e-6 to 1e6 in one scene, rays from 1 to 3 sides away",
                         "hit/miss and t as in double precision (edge decisions excepted)", s, rays,
                         double_truth_judge(s, rays), all_backends_required);
            }
        }
    }
    return out;
}

} // namespace candela::numerics
