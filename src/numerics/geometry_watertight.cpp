// Watertightness of closed meshes: rays aimed exactly at shared edges and vertices.
#include "candela/accel/accel.h"
#include "candela/accel/brute.h"
#include "candela/io/collada.h"
#include "candela/numerics/double_brute.h"
#include "candela/numerics/geometry_cases.h"
#include "candela/scene/builder.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene.h"
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"
#include "geometry_support.h"

#include <fmt/format.h>
#include <algorithm>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <unordered_map>

namespace candela::numerics {

using namespace detail;

namespace {

const char* const kGroup = "watertightness";

/// A vertex position identified by its exact bits: unwelded duplicates share a key.
struct PosKey {
    std::uint32_t b[3];
    bool operator==(const PosKey& o) const {
        return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2];
    }
    bool operator<(const PosKey& o) const {
        return std::lexicographical_compare(b, b + 3, o.b, o.b + 3);
    }
};
struct PosKeyHash {
    std::size_t operator()(const PosKey& k) const {
        return (static_cast<std::size_t>(k.b[0]) * 73856093u) ^
               (static_cast<std::size_t>(k.b[1]) * 19349663u) ^
               (static_cast<std::size_t>(k.b[2]) * 83492791u);
    }
};
PosKey key_of(const Vec3& p) {
    PosKey k;
    // +0 and -0 are the same point.
    const float c[3] = {p.x + 0.f, p.y + 0.f, p.z + 0.f};
    std::memcpy(k.b, c, sizeof k.b);
    return k;
}

using EdgeKey = std::pair<PosKey, PosKey>;
EdgeKey edge_key(const Vec3& a, const Vec3& b) {
    PosKey ka = key_of(a), kb = key_of(b);
    if (kb < ka) std::swap(ka, kb);
    return {ka, kb};
}

std::map<EdgeKey, int> edge_use(const Mesh& m) {
    std::map<EdgeKey, int> use;
    for (std::size_t j = 0; j < m.triangle_count(); ++j)
        for (int e = 0; e < 3; ++e)
            ++use[edge_key(m.positions[m.indices[3 * j + e]],
                           m.positions[m.indices[3 * j + (e + 1) % 3]])];
    return use;
}

/// Rays aimed at edges and vertices of one closed mesh, with what a correct answer is.
struct AimedRays {
    std::vector<Ray> rays;
    std::vector<float> expected; ///< distance from the origin to the aimed point
    std::vector<std::uint8_t> inside;
    std::size_t outside_count = 0, inside_count = 0;
};

/// The first hit of a ray entering the solid at the aimed point must be at the aimed
/// distance; 1e-3 relative is > 8x the float error of t at every translation used (t >= r/2
/// and ulp(|o|) <= 1.2e-4 r with r = max(1, 1e-3 |c|)), and far below any exit distance.
constexpr float kEntryRelTol = 1e-3f;
/// The ray must make at least this cosine with every face around the aimed point (about 11.5
/// degrees off each tangent plane), so that it truly crosses the surface there.
constexpr float kMinCos = 0.2f;

/// Outside rays: from target + w * dist aimed at a vertex (one in three) or a random point of
/// an edge, w in the cone of directions making kMinCos with every face around the edge's ends
/// (only at ends whose edges are all shared by two triangles). Inside rays (when `center` is
/// given, for meshes star-shaped about it): from the centre through the same points.
AimedRays make_aimed_rays(const Mesh& m, std::size_t count, float r, const Vec3* center,
                          std::uint64_t seed) {
    const std::map<EdgeKey, int> use = edge_use(m);
    std::unordered_map<PosKey, std::vector<Vec3>, PosKeyHash> normals;
    std::unordered_map<PosKey, bool, PosKeyHash> closed;
    for (std::size_t j = 0; j < m.triangle_count(); ++j) {
        const Vec3& p0 = m.positions[m.indices[3 * j]];
        const Vec3& p1 = m.positions[m.indices[3 * j + 1]];
        const Vec3& p2 = m.positions[m.indices[3 * j + 2]];
        const Vec3d n = cross(Vec3d(p1) - Vec3d(p0), Vec3d(p2) - Vec3d(p0));
        const double l = length(n);
        const Vec3* ps[3] = {&p0, &p1, &p2};
        for (int k = 0; k < 3; ++k) {
            const PosKey key = key_of(*ps[k]);
            if (l > 0.0) normals[key].push_back(Vec3(n / l));
            bool ok = use.at(edge_key(*ps[k], *ps[(k + 1) % 3])) == 2 &&
                      use.at(edge_key(*ps[k], *ps[(k + 2) % 3])) == 2 && l > 0.0;
            auto it = closed.find(key);
            if (it == closed.end())
                closed.emplace(key, ok);
            else
                it->second = it->second && ok;
        }
    }
    SplitMix64 rng = case_rng(seed);
    AimedRays out;
    const std::size_t max_attempts = 20 * count + 100;
    for (std::size_t attempt = 0; attempt < max_attempts && out.rays.size() < count; ++attempt) {
        const std::size_t j = rng.next_below(m.triangle_count());
        const int e = static_cast<int>(rng.next_below(3));
        const Vec3& pa = m.positions[m.indices[3 * j + e]];
        const Vec3& pb = m.positions[m.indices[3 * j + (e + 1) % 3]];
        const PosKey ka = key_of(pa), kb = key_of(pb);
        if (!closed[ka] || !closed[kb]) continue;
        const Vec3 target = rng.next_below(3) == 0 ? pa : pa + (pb - pa) * rng.next_float();
        std::vector<Vec3> around = normals[ka];
        around.insert(around.end(), normals[kb].begin(), normals[kb].end());
        Vec3 mean(0.f);
        for (const Vec3& n : around)
            mean += n;
        if (!(length(mean) > 0.f)) continue;
        mean = normalize(mean);
        Vec3 w;
        bool found = false;
        for (int k = 0; k < 50 && !found; ++k) {
            w = normalize(mean + square_to_uniform_sphere(rng.next_vec2()) * 0.6f);
            found = true;
            for (const Vec3& n : around)
                found = found && dot(w, n) >= kMinCos;
        }
        if (!found) continue;
        const Vec3 o = target + w * (r * (0.5f + 2.f * rng.next_float()));
        const Vec3 d = target - o;
        if (!(length(d) > 0.f)) continue;
        out.rays.push_back(Ray{o, normalize(d), 0.f, kInf});
        out.expected.push_back(length(d));
        out.inside.push_back(0);
        ++out.outside_count;
        if (center) {
            const Vec3 di = target - *center;
            if (!(length(di) > 0.f)) continue;
            out.rays.push_back(Ray{*center, normalize(di), 0.f, kInf});
            out.expected.push_back(length(di));
            out.inside.push_back(1);
            ++out.inside_count;
        }
    }
    return out;
}

struct LeakTally {
    std::size_t out_leaks = 0, in_leaks = 0, non_finite = 0;
    double max_rel_dt = 0.0; ///< max |t - t_double| / t_double over hits on the same triangle
};

/// Counts leaks of `trace` on the aimed rays. `truth`
/// holds the double-precision answers for the same rays; hits on the same triangle as the
/// double answer contribute their relative t error.
LeakTally count_leaks(const AimedRays& a, const std::vector<std::optional<HitD>>& truth,
                      const std::function<std::optional<Hit>(const Ray&)>& trace) {
    LeakTally t;
    for (std::size_t i = 0; i < a.rays.size(); ++i) {
        const std::optional<Hit> h = trace(a.rays[i]);
        if (non_finite_hit(h)) ++t.non_finite;
        if (a.inside[i]) {
            // From inside a closed surface every ray must hit it.
            if (!h) ++t.in_leaks;
        } else if (!h || h->t > a.expected[i] * (1.f + kEntryRelTol)) {
            ++t.out_leaks;
        }
        const std::optional<HitD>& hd = truth[i];
        if (h && hd && h->geom_id == hd->geom_id && h->prim_id == hd->prim_id)
            t.max_rel_dt =
                std::max(t.max_rel_dt, std::abs(static_cast<double>(h->t) - hd->t) / hd->t);
    }
    return t;
}

std::string leak_text(const LeakTally& t, const AimedRays& rays) {
    return fmt::format("{} leaks of {} (outside {} of {}, inside {} of {}); non-finite hits {}; "
        "max relative t error vs double {:.1e}",
        t.out_leaks + t.in_leaks, rays.rays.size(), t.out_leaks, rays.outside_count, t.in_leaks,
        rays.inside_count, t.non_finite, t.max_rel_dt);
}

void run_mesh(std::vector<StressResult>& out, const std::string& name, const Scene& scene,
              const AimedRays& rays) {
    // The ground truth first: double-precision Moller-Trumbore on the same float rays. It is
    // not watertight either, only far less likely to fall between two triangles; its own count
    // is reported.
    const DoubleBruteAccel ref(scene);
    std::vector<std::optional<HitD>> truth;
    truth.reserve(rays.rays.size());
    for (const Ray& r : rays.rays)
        truth.push_back(ref.intersect_double(r));
    {
        std::size_t i = 0;
        const LeakTally t = count_leaks(rays, truth, [&](const Ray&) {
            const std::optional<HitD>& hd = truth[i++];
            if (!hd) return std::optional<Hit>();
            return std::optional<Hit>(Hit{static_cast<float>(hd->t), static_cast<float>(hd->u),
                                          static_cast<float>(hd->v), hd->geom_id, hd->prim_id});
        });
        out.push_back(make_row(kGroup, name, "brute double-precision Moller-Trumbore", "0 leaks",
                               leak_text(t, rays), false, true));
    }
    for (const Backend& b : all_backends()) {
        const std::unique_ptr<Accel> accel = make_accel(scene, b.opt);
        const LeakTally t =
            count_leaks(rays, truth, [&](const Ray& r) { return accel->intersect(r); });
        out.push_back(make_row(kGroup, name, b.name, "0 leaks, 0 non-finite", leak_text(t, rays),
                               b.watertight, t.out_leaks + t.in_leaks == 0 && t.non_finite == 0));
    }
}

const char* translation_label(float t) {
    if (t == 0.f) return "at the origin";
    if (t == 1e3f) return "translated 1e3";
    if (t == 1e5f) return "translated 1e5";
    return "translated 1e6";
}

} // namespace

std::size_t count_open_edges(const Mesh& m) {
    std::size_t open = 0;
    for (const auto& kv : edge_use(m))
        if (kv.second != 2) ++open;
    return open;
}

Mesh unweld_mesh(const Mesh& m) {
    Mesh u;
    u.name = m.name + "_unwelded";
    u.material = m.material;
    u.light = m.light;
    u.positions.reserve(m.indices.size());
    const bool has_normals = m.normals.size() == m.positions.size();
    for (std::size_t i = 0; i < m.indices.size(); ++i) {
        u.positions.push_back(m.positions[m.indices[i]]);
        if (has_normals) u.normals.push_back(m.normals[m.indices[i]]);
        u.indices.push_back(static_cast<std::uint32_t>(i));
    }
    return u;
}

std::vector<StressResult> run_watertight_procedural(StressSize size) {
    std::vector<StressResult> out;
    const std::size_t n_rays = size == StressSize::Quick ? 3000 : 30000;
    /// UV sphere of 22 rings (1,848 triangles) and a cube with a 10 x 10 grid per face (1,200).
    constexpr int kRings = 22;
    constexpr int kCubeGrid = 10;
    for (float T : {0.f, 1e3f, 1e5f, 1e6f}) {
        // The mesh grows with the translation so that its vertices stay resolved: at 1e6 the
        // float spacing is 0.0625, so the radius there is 1000 (spacing 6e-5 of the radius).
        const float r = std::max(1.f, 1e-3f * T);
        const Vec3 c(T, T, T);
        const std::string where =
            std::string(translation_label(T)) + fmt::format(", radius {:g}", r);
        {
            Scene s;
            add_uv_sphere_mesh(s, c, r, kRings);
            SceneEditor(s).finalize();
            const AimedRays rays = make_aimed_rays(s.meshes[0], n_rays, r, &c, 11);
            run_mesh(out,
                     fmt::format("UV sphere ({} triangles) ", s.meshes[0].triangle_count()) +
                         where,
                     s, rays);
            Scene u;
            SceneEditor ue(u);
            for (const Material& m : s.materials)
                ue.add_material(m);
            ue.add_mesh(unweld_mesh(s.meshes[0]));
            ue.finalize();
            const AimedRays urays = make_aimed_rays(u.meshes[0], n_rays, r, &c, 12);
            run_mesh(out, "same sphere, unwelded (3 vertices per triangle) " + where, u, urays);
        }
        {
            Scene s;
            add_grid_cube_mesh(s, c - Vec3(r), c + Vec3(r), kCubeGrid);
            SceneEditor(s).finalize();
            const AimedRays rays = make_aimed_rays(s.meshes[0], n_rays, r, &c, 13);
            run_mesh(out,
                     fmt::format("grid cube ({} triangles) ", s.meshes[0].triangle_count()) +
                         where,
                     s, rays);
        }
    }

    return out;
}

std::vector<StressResult> run_watertight_bunny(StressSize size, const std::string& shared_scenes) {
    // The CS184 bunny: only its closed part is a fair target.
    const std::string path = shared_scenes + "/CBbunny.dae";
    if (!std::ifstream(path)) {
        std::vector<StressResult> out;
        out.push_back(make_row(kGroup, "CBbunny", "-", "scene present",
                               "skipped: " + path + " not found", false, true));
        return out;
    }
    return run_watertight_scene_mesh(size, path, "CBbunny");
}

std::vector<StressResult> run_watertight_scene_mesh(StressSize size, const std::string& path,
                                                    const std::string& label) {
    std::vector<StressResult> out;
    Diagnostics diag;
    const Scene full = load_scene(path, BuildOptions{}, diag);
    std::size_t biggest = 0;
    for (std::size_t g = 0; g < full.meshes.size(); ++g)
        if (full.meshes[g].triangle_count() > full.meshes[biggest].triangle_count()) biggest = g;
    Scene scene;
    SceneEditor editor(scene);
    Mesh m = full.meshes.at(biggest); // a copy keeps the positions' spare Vec3 (PaddedPositions)
    m.material = editor.add_material(Material{});
    m.light = -1;
    editor.add_mesh(std::move(m));
    editor.finalize();
    const Mesh& bm = scene.meshes[0];
    const std::size_t open = count_open_edges(bm);
    out.push_back(make_row(kGroup, label + " mesh '" + bm.name + "'", "edge count", "closed",
                           fmt::format("{} open edges (not shared by exactly 2 triangles) of {} "
                                        "triangles",
                                        open, bm.triangle_count()),
                           false, true));
    const float diag_len = length(scene.bounds.extent());
    // Fewer rays than for the small meshes: brute force tests every triangle per ray.
    const std::size_t n_rays = size == StressSize::Quick ? 1000 : 20000;
    const AimedRays rays = make_aimed_rays(bm, n_rays, 0.2f * diag_len, nullptr, 14);
    run_mesh(
        out,
        fmt::format("{}, rays at edges/vertices whose neighbourhood is closed ({} triangles)",
                     label, bm.triangle_count()),
        scene, rays);
    return out;
}

std::vector<StressResult> run_watertight_cases(StressSize size, const std::string& shared_scenes) {
    std::vector<StressResult> out = run_watertight_procedural(size);
    std::vector<StressResult> bunny = run_watertight_bunny(size, shared_scenes);
    out.insert(out.end(), bunny.begin(), bunny.end());
    return out;
}

} // namespace candela::numerics
