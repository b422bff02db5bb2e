// Accelerator agreement on camera, bounce and shadow rays, and the classification of each
// difference.
#include "candela/diagnostics/check.h"

#include "candela/accel/triangle.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/scene/camera.h"
#include "candela/scene/interaction.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"
#include "candela/util/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>

namespace candela {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// The generator of ray `index` of batch `stream`: counter-based, so a ray depends on (seed,
/// batch, index) only and batches can be generated in parallel, identically every run.
SplitMix64 ray_rng(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
    SplitMix64 rng(seed * kGoldenGamma ^ (stream << 56) ^ (index * 0xBF58476D1CE4E5B9ull));
    rng.next_u64();
    return rng;
}

struct SurfacePoint {
    Vec3 p, p_error, ng;
};

/// Uniform choice of a primitive, then a uniform point on it.
class SurfaceSampler {
  public:
    explicit SurfaceSampler(const Scene& scene) : scene_(scene) {
        first_.push_back(0);
        for (const Mesh& m : scene.meshes)
            first_.push_back(first_.back() + m.triangle_count());
        total_ = first_.back() + scene.spheres.size();
    }
    std::size_t triangles() const { return first_.back(); }
    std::size_t total() const { return total_; }

    SurfacePoint triangle_point(std::size_t g, std::size_t j, SplitMix64& rng) const {
        const Mesh& m = scene_.meshes[g];
        const Vec3& p0 = m.positions[m.indices[3 * j]];
        const Vec3& p1 = m.positions[m.indices[3 * j + 1]];
        const Vec3& p2 = m.positions[m.indices[3 * j + 2]];
        const float su = std::sqrt(rng.next_float());
        const float b1 = 1.f - su, b2 = rng.next_float() * su, b0 = 1.f - b1 - b2;
        SurfacePoint s;
        s.p = p0 * b0 + p1 * b1 + p2 * b2;
        s.p_error = (vabs(p0 * b0) + vabs(p1 * b1) + vabs(p2 * b2)) * float_gamma(7);
        const Vec3 n = cross(p1 - p0, p2 - p0);
        const float l = length(n);
        s.ng = l > 0.f ? n / l : Vec3(0.f, 0.f, 1.f);
        return s;
    }
    SurfacePoint sphere_point(std::size_t k, SplitMix64& rng) const {
        const Sphere& sp = scene_.spheres[k];
        SurfacePoint s;
        s.ng = square_to_uniform_sphere(rng.next_vec2());
        if (sp.is_ellipsoid()) {
            // Uniform on the unit sphere of object space (not by area on the ellipsoid, which
            // the checks do not need), with make_interaction's own error bound and normal.
            const EllipsoidPoint e = ellipsoid_point(sp, s.ng, s.ng);
            s.p = e.p;
            s.p_error = e.p_error;
            s.ng = e.n;
            return s;
        }
        const Vec3 local = s.ng * sp.radius;
        s.p = sp.center + local;
        s.p_error = vabs(local) * float_gamma(5) + vabs(s.p) * float_gamma(1);
        return s;
    }
    /// Mesh g's triangle j located from a scene-wide index.
    void locate(std::size_t index, std::size_t& g, std::size_t& j) const {
        g = std::upper_bound(first_.begin(), first_.end(), index) - first_.begin() - 1;
        j = index - first_[g];
    }
    SurfacePoint sample(SplitMix64& rng) const {
        const std::size_t i = rng.next_below(total_);
        if (i >= triangles()) return sphere_point(i - triangles(), rng);
        std::size_t g, j;
        locate(i, g, j);
        return triangle_point(g, j, rng);
    }

  private:
    const Scene& scene_;
    std::vector<std::size_t> first_;
    std::size_t total_ = 0;
};

template <typename F> void parallel_rays(std::size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i < r.end(); ++i)
                              f(i);
                      });
}

/// Unnormalised outward normal of a sphere or ellipsoid at the world point q.
Vec3 sphere_outward(const Sphere& s, const Vec3& q) {
    if (s.is_ellipsoid()) return s.to_object.transpose_mul(s.to_object * (q - s.center));
    return q - s.center;
}

/// |cos| of the angle between the ray and the hit primitive's geometric normal, floored at
/// kMinGrazeCos: rounding errors of t and of the hit's position on the surface are amplified by
/// 1 / |cos|, so tolerances are divided by it.
float hit_cos(const Scene& scene, const Ray& ray, const Hit& h) {
    constexpr float kMinGrazeCos = 1e-3f; // caps the amplification at 1000
    Vec3 n(0.f, 0.f, 0.f);
    if (h.geom_id == scene.sphere_geom_id()) {
        if (h.prim_id < scene.spheres.size())
            n = sphere_outward(scene.spheres[h.prim_id], ray.o + ray.d * h.t);
    } else if (h.geom_id < scene.meshes.size()) {
        const Mesh& m = scene.meshes[h.geom_id];
        if (h.prim_id < m.triangle_count()) {
            const Vec3& p0 = m.positions[m.indices[3 * h.prim_id]];
            n = cross(m.positions[m.indices[3 * h.prim_id + 1]] - p0,
                      m.positions[m.indices[3 * h.prim_id + 2]] - p0);
        }
    }
    const float l = length(n) * length(ray.d);
    const float c = l > 0.f ? std::abs(dot(n, ray.d)) / l : 1.f;
    return std::isfinite(c) ? std::max(c, kMinGrazeCos) : 1.f;
}

bool near_edge(const Scene& scene, const Ray& ray, const Hit& h) {
    if (h.t <= ray.tmin + kTieRelTolerance * std::abs(ray.tmin) ||
        h.t >= ray.tmax - kTieRelTolerance * std::abs(ray.tmax))
        return true; // at an end of the ray's interval: in or out is decided by rounding
    if (h.geom_id == scene.sphere_geom_id()) {
        if (h.prim_id >= scene.spheres.size()) return false;
        const Vec3 n = sphere_outward(scene.spheres[h.prim_id], ray.o + ray.d * h.t);
        const float c = std::abs(dot(n, ray.d)) / (length(n) * length(ray.d));
        return c < kGrazeSphereCos;
    }
    const float b[3] = {1.f - h.u - h.v, h.u, h.v};
    if (std::min(b[0], std::min(b[1], b[2])) < kGrazeBarycentric) return true;
    // In world units: the distance to edge i is b_i times the height over that edge.
    if (h.geom_id >= scene.meshes.size()) return false;
    const Mesh& m = scene.meshes[h.geom_id];
    if (h.prim_id >= m.triangle_count()) return false;
    const Vec3 p[3] = {m.positions[m.indices[3 * h.prim_id]],
                       m.positions[m.indices[3 * h.prim_id + 1]],
                       m.positions[m.indices[3 * h.prim_id + 2]]};
    const float area2 = length(cross(p[1] - p[0], p[2] - p[0]));
    const Vec3 hit_p = ray.o + ray.d * h.t;
    const float tol = kGrazeRelDistance * (max_component(vabs(ray.o)) + max_component(vabs(hit_p)));
    for (int i = 0; i < 3; ++i) {
        const float opposite = length(p[(i + 2) % 3] - p[(i + 1) % 3]);
        if (opposite > 0.f && b[i] * area2 / opposite < tol) return true;
    }
    return false;
}

} // namespace

const char* check_ray_kind_name(CheckRayKind k) {
    switch (k) {
    case CheckRayKind::Camera:
        return "camera";
    case CheckRayKind::Bounce:
        return "bounce";
    case CheckRayKind::Shadow:
        return "shadow";
    case CheckRayKind::Edge:
        return "edge";
    case CheckRayKind::Count:
        break;
    }
    return "?";
}

const char* hit_class_name(HitClass c) {
    switch (c) {
    case HitClass::Agree:
        return "agree";
    case HitClass::Tie:
        return "tie";
    case HitClass::Graze:
        return "graze";
    case HitClass::Precision:
        return "precision";
    case HitClass::Leak:
        return "leak";
    case HitClass::Count:
        break;
    }
    return "?";
}

HitClass classify_hits(const Scene& scene, const Ray& ray, const std::optional<Hit>& a,
                       const std::optional<Hit>& b, float* abs_dt) {
    float dt = 0.f;
    HitClass cls = HitClass::Agree;
    if (a && b) {
        dt = std::abs(a->t - b->t);
        // The rounding error of a computed t is relative to the coordinates it is computed
        // from (origin and hit point), divided by |d|, not to t itself: a bounce ray that hits
        // a neighbour at tiny t still carries an error of a few ulps of |o|.
        const float t_max = std::max(std::abs(a->t), std::abs(b->t));
        const Vec3 p_far = ray.o + ray.d * t_max;
        const float scale =
            t_max + (max_component(vabs(ray.o)) + max_component(vabs(p_far))) / length(ray.d);
        const float tol =
            kTieRelTolerance * scale / std::min(hit_cos(scene, ray, *a), hit_cos(scene, ray, *b));
        const bool same = a->geom_id == b->geom_id && a->prim_id == b->prim_id;
        if (same)
            cls = dt <= tol ? HitClass::Agree : HitClass::Precision;
        else if (dt <= tol)
            cls = HitClass::Tie;
        else // the nearer hit is the one the other backend skipped
            cls = near_edge(scene, ray, a->t < b->t ? *a : *b) ? HitClass::Graze : HitClass::Leak;
    } else if (a || b) {
        dt = kInf;
        cls = near_edge(scene, ray, a ? *a : *b) ? HitClass::Graze : HitClass::Leak;
    }
    if (abs_dt) *abs_dt = dt;
    return cls;
}

std::vector<Ray> make_camera_rays(const Scene& scene, int width, int height) {
    if (width <= 0 || height <= 0) return {};
    // The renderer's rays through the pixel centres (lens centre of a thin lens), row 0 at the
    // top of the image.
    const CameraProjection camera(scene.camera, width, height);
    const Vec2 lens_centre(0.5f, 0.5f);
    std::vector<Ray> rays(static_cast<std::size_t>(width) * height);
    parallel_rays(rays.size(), [&](std::size_t i) {
        const float fx = static_cast<float>(i % width) + 0.5f;
        const float fy = static_cast<float>(i / width) + 0.5f;
        rays[i] = camera.ray(fx, fy, lens_centre);
    });
    return rays;
}

std::vector<Ray> make_bounce_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
    const SurfaceSampler sampler(scene);
    if (sampler.total() == 0) return {};
    std::vector<Ray> rays(count);
    parallel_rays(count, [&](std::size_t i) {
        SplitMix64 rng = ray_rng(seed, 1, i);
        SurfacePoint s = sampler.sample(rng);
        if (rng.next_float() < 0.5f) s.ng = -s.ng;
        Vec3 w = square_to_uniform_sphere(rng.next_vec2());
        if (dot(w, s.ng) < 0.f) w = -w;
        Ray& r = rays[i];
        r.o = offset_ray_origin(s.p, s.p_error, s.ng, w);
        r.d = w;
        r.tmin = 0.f;
        r.tmax = kInf;
    });
    return rays;
}

std::vector<Ray> make_shadow_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
    const SurfaceSampler sampler(scene);
    if (sampler.total() == 0) return {};
    std::vector<const Light*> lights;
    for (const Light& l : scene.lights) {
        const bool usable = l.kind == LightKind::Area || l.kind == LightKind::Point ||
                            l.kind == LightKind::Spot ||
                            (l.kind == LightKind::Mesh && l.geom_id < scene.meshes.size() &&
                             scene.meshes[l.geom_id].triangle_count() > 0) ||
                            (l.kind == LightKind::Sphere && l.geom_id < scene.spheres.size());
        if (usable) lights.push_back(&l);
    }
    std::vector<Ray> rays(count);
    parallel_rays(count, [&](std::size_t i) {
        SplitMix64 rng = ray_rng(seed, 2, i);
        const SurfacePoint from = sampler.sample(rng);
        SurfacePoint to;
        if (lights.empty()) {
            to = sampler.sample(rng);
        } else {
            const Light& l = *lights[rng.next_below(lights.size())];
            switch (l.kind) {
            case LightKind::Area: {
                const float su = rng.next_float() - 0.5f, sv = rng.next_float() - 0.5f;
                to.p = l.p + l.dx * su + l.dy * sv;
                to.p_error = (vabs(l.p) + vabs(l.dx * su) + vabs(l.dy * sv)) * float_gamma(3);
                to.ng = l.n;
                break;
            }
            case LightKind::Mesh: {
                const Mesh& m = scene.meshes[l.geom_id];
                to = sampler.triangle_point(l.geom_id, rng.next_below(m.triangle_count()), rng);
                break;
            }
            case LightKind::Sphere:
                to = sampler.sphere_point(l.geom_id, rng);
                break;
            default: // point and spot: a bare point
                to.p = l.p;
                to.p_error = Vec3(0.f);
                to.ng = Vec3(0.f);
                break;
            }
        }
        rays[i] = spawn_ray_between(from.p, from.p_error, from.ng, to.p, to.p_error, to.ng);
    });
    return rays;
}

std::vector<Ray> make_edge_rays(const Scene& scene, std::size_t count, std::uint64_t seed) {
    const SurfaceSampler sampler(scene);
    if (sampler.triangles() == 0) return {};
    const float diag = std::max(length(scene.bounds.extent()), 1e-3f);
    std::vector<Ray> rays(count);
    parallel_rays(count, [&](std::size_t i) {
        SplitMix64 rng = ray_rng(seed, 3, i);
        std::size_t g, j;
        sampler.locate(rng.next_below(sampler.triangles()), g, j);
        const Mesh& m = scene.meshes[g];
        const std::size_t e = rng.next_below(3);
        const Vec3& pa = m.positions[m.indices[3 * j + e]];
        const Vec3& pb = m.positions[m.indices[3 * j + (e + 1) % 3]];
        const Vec3& pc = m.positions[m.indices[3 * j + (e + 2) % 3]];
        const Vec3 target = rng.next_below(3) == 0 ? pa : pa + (pb - pa) * rng.next_float();
        Vec3 n = cross(pb - pa, pc - pa);
        const float l = length(n);
        n = l > 0.f ? n / l : Vec3(0.f, 0.f, 1.f);
        // Arrive at least ~11 degrees off the tangent plane, from either side.
        Vec3 w = square_to_uniform_sphere(rng.next_vec2());
        if (std::abs(dot(w, n)) < 0.2f) w = normalize(w + n * (dot(w, n) < 0.f ? -0.5f : 0.5f));
        const Vec3 origin = target + w * (diag * (0.05f + rng.next_float()));
        Ray& r = rays[i];
        r.o = origin;
        r.d = normalize(target - origin);
        r.tmin = 0.f;
        r.tmax = kInf;
    });
    return rays;
}

std::string CheckCase::line() const {
    return fmt::format("{:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g}", double(ray.o.x),
                       double(ray.o.y), double(ray.o.z), double(ray.d.x), double(ray.d.y),
                       double(ray.d.z), double(ray.tmin), double(ray.tmax));
}

std::uint64_t CheckPair::disagreements() const {
    std::uint64_t n = 0;
    for (const auto& row : counts)
        for (int c = 1; c < kHitClassCount; ++c)
            n += row[c];
    return n;
}

std::uint64_t CheckPair::rays() const {
    std::uint64_t n = 0;
    for (const auto& row : counts)
        for (std::uint64_t v : row)
            n += v;
    return n;
}

bool CheckReport::ok() const {
    for (const CheckPair& p : pairs)
        for (const auto& row : p.counts)
            if (row[static_cast<int>(HitClass::Leak)] > 0) return false;
    for (std::uint64_t m : occlusion_mismatches)
        if (m > 0) return false;
    return true;
}

std::string CheckReport::to_text() const {
    std::ostringstream os;
    os << "scene " << scene << ": " << count_of(triangles, "triangle") << ", "
       << count_of(spheres, "sphere") << "; " << fmt::format("{:.2f}", seconds) << " s\n";
    for (const std::string& n : notes)
        os << "note: " << n << "\n";
    for (const CheckPair& p : pairs) {
        os << "\n" << p.reference << " vs " << p.other << "\n";
        os << fmt::format("  {:<7} {:>10} {:>10} {:>8} {:>8} {:>10} {:>8} {:>12}\n", "rays",
                          "count", "agree", "tie", "graze", "precision", "leak", "agree+tie %");
        for (int k = 0; k < kCheckRayKindCount; ++k) {
            const auto& row = p.counts[k];
            std::uint64_t n = 0;
            for (std::uint64_t v : row)
                n += v;
            if (n == 0) continue;
            const double ok = 100.0 * static_cast<double>(row[0] + row[1]) / static_cast<double>(n);
            os << fmt::format("  {:<7} {:>10} {:>10} {:>8} {:>8} {:>10} {:>8} {:>12.4f}\n",
                              check_ray_kind_name(static_cast<CheckRayKind>(k)), n, row[0], row[1],
                              row[2], row[3], row[4], ok);
        }
    }
    if (!pairs.empty())
        os << "\n  count: rays traced; agree: same primitive at the same distance; tie: another\n"
              "  primitive at the same distance (coplanar or shared edge); graze: one backend\n"
              "  missed a hit on an edge or vertex; precision: same primitive, distances apart\n"
              "  by more than rounding; leak: one backend missed a hit inside a primitive (a\n"
              "  hole: the only class that fails the check)\n";
    os << "\noccluded() != intersect().has_value():";
    for (std::size_t a = 0; a < accels.size(); ++a)
        os << " " << accels[a] << "="
           << (a < occlusion_mismatches.size() ? occlusion_mismatches[a] : 0);
    os << "\n";
    if (!worst.empty()) {
        os << "\nworst cases (class kind backend |dt| : ox oy oz dx dy dz tmin tmax)\n";
        for (const CheckCase& c : worst)
            os << "  " << hit_class_name(c.cls) << " " << check_ray_kind_name(c.kind) << " "
               << c.other << " " << c.abs_dt << " : " << c.line() << "\n";
    }
    os << (ok() ? "OK: no leaks\n" : "FAIL: leaks or occlusion mismatches\n");
    return os.str();
}

std::string CheckReport::to_json() const {
    using Json = nlohmann::ordered_json;
    Json mismatches = Json::object();
    for (std::size_t a = 0; a < accels.size() && a < occlusion_mismatches.size(); ++a)
        mismatches[accels[a]] = occlusion_mismatches[a];
    Json pair_list = Json::array();
    for (const CheckPair& p : pairs) {
        Json counts = Json::object();
        for (int k = 0; k < kCheckRayKindCount; ++k) {
            Json row = Json::object();
            for (int c = 0; c < kHitClassCount; ++c)
                row[hit_class_name(static_cast<HitClass>(c))] = p.counts[k][c];
            counts[check_ray_kind_name(static_cast<CheckRayKind>(k))] = std::move(row);
        }
        pair_list.push_back({{"reference", p.reference}, {"other", p.other}, {"counts", counts}});
    }
    Json worst_list = Json::array();
    for (const CheckCase& c : worst)
        worst_list.push_back({{"class", hit_class_name(c.cls)},
                              {"kind", check_ray_kind_name(c.kind)},
                              {"other", c.other},
                              {"abs_dt", float_for_json(c.abs_dt)},
                              {"ray", c.line()}});
    const Json j = {{"scene", scene},     {"triangles", triangles},
                    {"spheres", spheres}, {"seconds", seconds},
                    {"ok", ok()},         {"accels", accels},
                    {"notes", notes},     {"occlusion_mismatches", mismatches},
                    {"pairs", pair_list}, {"worst", worst_list}};
    return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

namespace {

/// The accelerators to compare, each once, the reference first (brute force when affordable,
/// else the builtin BVH). Brute force is dropped, with a note, when its scans would exceed
/// opt.brute_max_tests.
std::vector<AccelKind> choose_accels(const CheckOptions& opt, CheckReport& rep) {
    const double total_rays =
        static_cast<double>(opt.camera_width) * opt.camera_height +
        static_cast<double>(opt.bounce_rays + opt.shadow_rays + opt.edge_rays);
    std::vector<AccelKind> kinds;
    for (AccelKind k : opt.accels) {
        if (std::find(kinds.begin(), kinds.end(), k) != kinds.end()) continue;
        // Each ray costs the brute backend one intersect and one occluded scan.
        if (k == AccelKind::Brute &&
            2.0 * total_rays * static_cast<double>(rep.triangles + rep.spheres) >
                opt.brute_max_tests) {
            rep.notes.push_back("brute skipped: " + std::to_string(rep.triangles) +
                                " triangles x " + fmt::format("{:.0f}", total_rays) +
                                " rays exceeds brute_max_tests");
            continue;
        }
        kinds.push_back(k);
    }
    if (kinds.size() < 2)
        throw Error(ErrorKind::Usage,
                    "check: fewer than two backends left to compare (" +
                        (rep.notes.empty() ? std::string("--accel names one") : rep.notes.back()) +
                        "); list another in --accel");
    auto to_front = [&](AccelKind k) {
        auto it = std::find(kinds.begin(), kinds.end(), k);
        if (it == kinds.end()) return false;
        std::rotate(kinds.begin(), it, it + 1);
        return true;
    };
    if (!to_front(AccelKind::Brute)) to_front(AccelKind::Builtin);
    return kinds;
}

/// Builds each accelerator inside `arena`, names it in the report and pairs every other one with
/// the reference.
std::vector<std::unique_ptr<Accel>> build_accels(const Scene& scene, const CheckOptions& opt,
                                                 const std::vector<AccelKind>& kinds,
                                                 tbb::task_arena& arena, CheckReport& rep) {
    std::vector<std::unique_ptr<Accel>> accels;
    arena.execute([&] {
        for (AccelKind k : kinds) {
            AccelOptions ao;
            ao.kind = k;
            ao.triangle = opt.triangle;
            ao.embree_robust = opt.embree_robust;
            ao.build_threads = opt.threads;
            accels.push_back(make_accel(scene, ao));
            rep.accels.push_back(accels.back()->name());
        }
    });
    rep.occlusion_mismatches.assign(accels.size(), 0);
    for (std::size_t a = 1; a < accels.size(); ++a) {
        CheckPair p;
        p.reference = rep.accels[0];
        p.other = rep.accels[a];
        rep.pairs.push_back(p);
    }
    return accels;
}

std::vector<Ray> make_check_rays(const Scene& scene, const CheckOptions& opt, CheckRayKind kind) {
    switch (kind) {
    case CheckRayKind::Camera:
        return make_camera_rays(scene, opt.camera_width, opt.camera_height);
    case CheckRayKind::Bounce:
        return make_bounce_rays(scene, opt.bounce_rays, opt.seed);
    case CheckRayKind::Shadow:
        return make_shadow_rays(scene, opt.shadow_rays, opt.seed);
    case CheckRayKind::Edge:
        return make_edge_rays(scene, opt.edge_rays, opt.seed);
    case CheckRayKind::Count:
        break;
    }
    return {};
}

/// Leaks first, then by |dt|: the order in which disagreements are kept and reported.
bool worse_case(const CheckCase& x, const CheckCase& y) {
    const bool lx = x.cls == HitClass::Leak, ly = y.cls == HitClass::Leak;
    if (lx != ly) return lx;
    return x.abs_dt > y.abs_dt;
}

/// Keeps the `keep` worst cases of `cases` once it holds more than four times that many.
void trim_cases(std::vector<CheckCase>& cases, std::size_t keep) {
    if (cases.size() <= 4 * keep) return;
    std::partial_sort(cases.begin(), cases.begin() + keep, cases.end(), worse_case);
    cases.resize(keep);
}

/// Traces `rays` (of one kind) through every accelerator, classifies each other accelerator's
/// answer against the reference's, counts occlusion queries that disagree with intersection,
/// and keeps the worst disagreements in rep.worst.
void compare_accels(const Scene& scene, const CheckOptions& opt, CheckRayKind kind,
                    const std::vector<Ray>& rays, const std::vector<std::unique_ptr<Accel>>& accels,
                    tbb::task_arena& arena, CheckReport& rep) {
    const int k = static_cast<int>(kind);
    const std::size_t na = accels.size(), keep = opt.worst_cases;
    std::mutex merge_mutex;
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              std::vector<std::array<std::uint64_t, kHitClassCount>> counts(
                                  rep.pairs.size(), std::array<std::uint64_t, kHitClassCount>{});
                              std::vector<std::uint64_t> occ(na, 0);
                              std::vector<CheckCase> cases;
                              std::vector<std::optional<Hit>> hits(na);
                              for (std::size_t i = range.begin(); i < range.end(); ++i) {
                                  const Ray& r = rays[i];
                                  for (std::size_t a = 0; a < na; ++a) {
                                      hits[a] = accels[a]->intersect(r);
                                      if (accels[a]->occluded(r) != hits[a].has_value()) ++occ[a];
                                  }
                                  for (std::size_t a = 1; a < na; ++a) {
                                      float dt = 0.f;
                                      const HitClass c =
                                          classify_hits(scene, r, hits[0], hits[a], &dt);
                                      ++counts[a - 1][static_cast<int>(c)];
                                      if (keep > 0 && c != HitClass::Agree && c != HitClass::Tie) {
                                          CheckCase cc;
                                          cc.kind = kind;
                                          cc.cls = c;
                                          cc.other = rep.accels[a];
                                          cc.ray = r;
                                          cc.abs_dt = dt;
                                          cases.push_back(cc);
                                          trim_cases(cases, keep);
                                      }
                                  }
                              }
                              std::lock_guard<std::mutex> lock(merge_mutex);
                              for (std::size_t p = 0; p < rep.pairs.size(); ++p)
                                  for (int c = 0; c < kHitClassCount; ++c)
                                      rep.pairs[p].counts[k][c] += counts[p][c];
                              for (std::size_t a = 0; a < na; ++a)
                                  rep.occlusion_mismatches[a] += occ[a];
                              rep.worst.insert(rep.worst.end(), cases.begin(), cases.end());
                              trim_cases(rep.worst, keep);
                          });
    });
}

/// The worst cases as text (`check --worst FILE`): a comment line, then the ray, per case.
void write_worst_cases(const std::string& path, const CheckReport& rep) {
    std::ofstream out(path);
    if (!out) throw Error(ErrorKind::Io, path + ": cannot open for writing");
    out << "# one ray per line: ox oy oz dx dy dz tmin tmax; '#' lines describe the next ray\n";
    for (const CheckCase& c : rep.worst)
        out << "# " << hit_class_name(c.cls) << " " << check_ray_kind_name(c.kind) << " "
            << rep.accels[0] << " vs " << c.other << " |dt|=" << c.abs_dt << "\n"
            << c.line() << "\n";
    if (!out) throw Error(ErrorKind::Io, path + ": write failed");
}

} // namespace

CheckReport run_check(const Scene& scene, const CheckOptions& opt) {
    if (opt.accels.empty()) throw Error(ErrorKind::Usage, "check: no accelerators to compare");
    const Stopwatch timer;
    CheckReport rep;
    rep.scene = scene.source;
    rep.triangles = scene.triangle_count();
    rep.spheres = scene.spheres.size();

    const std::vector<AccelKind> kinds = choose_accels(opt, rep);
    tbb::task_arena arena(opt.threads > 0 ? opt.threads : tbb::task_arena::automatic);
    const std::vector<std::unique_ptr<Accel>> accels = build_accels(scene, opt, kinds, arena, rep);
    for (int k = 0; k < kCheckRayKindCount; ++k) {
        const auto kind = static_cast<CheckRayKind>(k);
        std::vector<Ray> rays;
        arena.execute([&] { rays = make_check_rays(scene, opt, kind); });
        rep.rays[k] = rays.size();
        compare_accels(scene, opt, kind, rays, accels, arena, rep);
    }
    std::sort(rep.worst.begin(), rep.worst.end(), worse_case);
    if (rep.worst.size() > opt.worst_cases) rep.worst.resize(opt.worst_cases);
    if (!opt.worst_cases_path.empty()) write_worst_cases(opt.worst_cases_path, rep);
    rep.seconds = timer.seconds();
    return rep;
}

} // namespace candela
