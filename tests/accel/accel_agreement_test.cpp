#include "candela/accel/brute.h"
#include "candela/accel/bvh.h"
#include "candela/accel/accel.h"
#include "candela/diagnostics/accel_bench.h"
#include "candela/diagnostics/check.h"
#include "candela/scene/procedural.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <random>

using namespace candela;

namespace {

/// Random rays through the scene box: origins in the box grown by half its size, uniform
/// directions; half of them aimed at a random vertex-weighted point of a random triangle so that
/// hits are frequent even in sparse soups.
std::vector<Ray> random_rays(const Scene& scene, std::size_t n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    std::normal_distribution<float> N(0.f, 1.f);
    const Vec3 lo = scene.bounds.lo - scene.bounds.extent() * 0.5f;
    const Vec3 ext = scene.bounds.extent() * 2.f;
    std::vector<Ray> rays;
    rays.reserve(n);
    while (rays.size() < n) {
        Ray r;
        r.o = lo + ext * Vec3(U(rng), U(rng), U(rng));
        if (rays.size() % 2 == 0 && !scene.meshes.empty() && scene.meshes[0].triangle_count() > 0) {
            const Mesh& m = scene.meshes[0];
            const std::size_t j =
                static_cast<std::size_t>(U(rng) * m.triangle_count()) % m.triangle_count();
            const float b1 = U(rng), b2 = U(rng) * (1.f - b1);
            const Vec3 target = m.positions[m.indices[3 * j]] * (1.f - b1 - b2) +
                                m.positions[m.indices[3 * j + 1]] * b1 +
                                m.positions[m.indices[3 * j + 2]] * b2;
            r.d = target - r.o;
        } else {
            r.d = Vec3(N(rng), N(rng), N(rng));
        }
        if (length_squared(r.d) < 1e-8f) continue;
        r.d = normalize(r.d);
        rays.push_back(r);
    }
    return rays;
}

struct Tally {
    std::size_t rays = 0, hits = 0, ties = 0;
    std::size_t classes[kHitClassCount] = {};
};

/// Brute vs builtin: the BVH runs the same float arithmetic on the same vertices, so any
/// difference other than which of two equally distant primitives wins is a bug.
Tally compare_exact(const Scene& scene, const Accel& ref, const Accel& other,
                    const std::vector<Ray>& rays) {
    Tally t;
    for (const Ray& r : rays) {
        const auto a = ref.intersect(r);
        const auto b = other.intersect(r);
        ++t.rays;
        REQUIRE(a.has_value() == b.has_value());
        REQUIRE(ref.occluded(r) == a.has_value());
        REQUIRE(other.occluded(r) == b.has_value());
        if (!a) continue;
        ++t.hits;
        if (a->geom_id == b->geom_id && a->prim_id == b->prim_id) {
            REQUIRE(a->t == b->t);
            REQUIRE(a->u == b->u);
            REQUIRE(a->v == b->v);
        } else {
            INFO("different primitives: t " << a->t << " vs " << b->t);
            REQUIRE(std::abs(a->t - b->t) <= kTieRelTolerance * std::abs(a->t));
            ++t.ties;
        }
    }
    (void)scene;
    return t;
}

Scene soup_scene(std::size_t n, std::uint32_t seed) {
    return make_procedural_scene("soup:" + std::to_string(n) + ":" + std::to_string(seed));
}

Scene spheres_and_meshes_scene() {
    Scene s;
    add_uv_sphere_mesh(s, Vec3(0.f), 1.f, 20);
    add_grid_cube_mesh(s, Vec3(1.5f, -0.5f, -0.5f), Vec3(2.5f, 0.5f, 0.5f), 6);
    add_triangle_soup(s, 300, 5);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> U(-2.f, 2.f);
    for (int i = 0; i < 40; ++i) {
        Sphere sp;
        sp.center = Vec3(U(rng), U(rng), U(rng));
        sp.radius = 0.05f + 0.1f * std::abs(U(rng));
        s.spheres.push_back(sp);
    }
    s.finalize();
    return s;
}

/// Spheres, ellipsoids under random rotations, shears and non-uniform scales (some mirrored),
/// and a mesh: the builtin BVH then runs its ellipsoid kernels.
Scene ellipsoids_scene() {
    Scene s;
    add_uv_sphere_mesh(s, Vec3(0.f), 1.f, 20);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> U(-2.f, 2.f);
    std::normal_distribution<double> N(0.0, 1.0);
    for (int i = 0; i < 40; ++i) {
        const Vec3 c(U(rng), U(rng), U(rng));
        if (i % 4 == 0) {
            s.spheres.push_back(Sphere{c, 0.05f + 0.1f * std::abs(U(rng))});
            continue;
        }
        // A random linear map (Gaussian entries), scaled to a size of ~0.15; resampled until
        // reasonably conditioned.
        Mat3d L;
        do {
            for (int r = 0; r < 3; ++r)
                for (int k = 0; k < 3; ++k)
                    L.m[r][k] = 0.1 * N(rng);
        } while (std::abs(L.det()) < 1e-4);
        s.spheres.push_back(make_ellipsoid(c, L));
    }
    s.finalize();
    return s;
}

} // namespace

TEST_CASE("builtin BVH gives brute-force hits on random soups", "[accel][quick]") {
    for (TriangleTest test : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
        for (std::size_t n : {1u, 10u, 100u, 1000u, 10000u}) {
            const Scene scene = soup_scene(n, 17 + static_cast<std::uint32_t>(n));
            const BruteAccel brute(scene, test);
            const BvhAccel bvh(scene, test, 0);
            const std::size_t nrays = n >= 10000 ? 3000 : 6000;
            const Tally t = compare_exact(scene, brute, bvh, random_rays(scene, nrays, 3));
            INFO("soup " << n << " test " << static_cast<int>(test) << ": " << t.hits
                         << " hits, ties " << t.ties);
            CHECK(t.hits > nrays / 10);
            // Memory budget: at most 64 bytes per triangle beyond the mesh.
            CHECK(bvh.memory_bytes() <= 64 * n + 256);
        }
    }
}

TEST_CASE("builtin BVH gives brute-force hits on closed meshes and spheres", "[accel][quick]") {
    const Scene scenes[] = {make_procedural_scene("sphere:5000"),
                            make_procedural_scene("cube:3000"), spheres_and_meshes_scene(),
                            make_procedural_scene("spheres:200"), ellipsoids_scene()};
    for (const Scene& scene : scenes) {
        for (TriangleTest test : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
            const BruteAccel brute(scene, test);
            const BvhAccel bvh(scene, test, 1);
            std::vector<Ray> rays = random_rays(scene, 4000, 5);
            for (const auto& extra :
                 {make_bounce_rays(scene, 2000, 3), make_edge_rays(scene, 2000, 3),
                  make_shadow_rays(scene, 2000, 3)})
                rays.insert(rays.end(), extra.begin(), extra.end());
            const Tally t = compare_exact(scene, brute, bvh, rays);
            INFO(scene.source << ": hits " << t.hits << " ties " << t.ties);
            CHECK(t.hits > rays.size() / 10);
        }
    }
}

TEST_CASE("parallel and serial BVH builds give the same hits", "[accel][quick]") {
    const Scene scene = make_procedural_scene("sphere:40000");
    const BvhAccel serial(scene, TriangleTest::MollerTrumbore, 1);
    const BvhAccel parallel(scene, TriangleTest::MollerTrumbore, 0);
    CHECK(serial.node_count() == parallel.node_count());
    CHECK(serial.depth() < 128);
    for (const Ray& r : random_rays(scene, 5000, 8)) {
        const auto a = serial.intersect(r), b = parallel.intersect(r);
        REQUIRE(a.has_value() == b.has_value());
        if (a) {
            REQUIRE(a->prim_id == b->prim_id);
            REQUIRE(a->t == b->t);
        }
    }
}

TEST_CASE("embree agrees with the builtin BVH on at least 99.99% of rays", "[accel]") {
    const Scene scenes[] = {soup_scene(10000, 4), make_procedural_scene("sphere:28000"),
                            spheres_and_meshes_scene(), ellipsoids_scene()};
    for (const Scene& scene : scenes) {
        CheckOptions opt;
        opt.accels = {AccelKind::Builtin, AccelKind::Embree};
        opt.camera_width = 160;
        opt.camera_height = 120;
        opt.bounce_rays = 30000;
        opt.shadow_rays = 20000;
        opt.edge_rays = 20000;
        opt.seed = 5;
        const CheckReport rep = run_check(scene, opt);
        REQUIRE(rep.pairs.size() == 1);
        const CheckPair& p = rep.pairs[0];
        INFO(rep.to_text());
        // Camera, bounce and shadow rays: agree or tie on >= 99.99% of them. Edge rays are
        // aimed exactly at edges, where the two triangle tests may legitimately decide
        // differently (Graze), but they must never leak or disagree on a primitive's t.
        std::uint64_t n = 0, same = 0;
        for (CheckRayKind k : {CheckRayKind::Camera, CheckRayKind::Bounce, CheckRayKind::Shadow}) {
            const auto& row = p.counts[static_cast<int>(k)];
            for (std::uint64_t v : row)
                n += v;
            same += row[static_cast<int>(HitClass::Agree)] + row[static_cast<int>(HitClass::Tie)];
        }
        CHECK(n >= 69000);
        CHECK(static_cast<double>(same) >= 0.9999 * static_cast<double>(n));
        for (const auto& row : p.counts) {
            CHECK(row[static_cast<int>(HitClass::Leak)] == 0);
            CHECK(row[static_cast<int>(HitClass::Precision)] == 0);
        }
        for (std::uint64_t m : rep.occlusion_mismatches)
            CHECK(m == 0);
    }
}

TEST_CASE("every backend rejects invalid rays and answers occluded == intersect",
          "[accel][quick]") {
    const Scene scene = spheres_and_meshes_scene();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<Ray> bad;
    auto add = [&](Vec3 o, Vec3 d, float tmin, float tmax) {
        bad.push_back(Ray{o, d, tmin, tmax});
    };
    add(Vec3(nan, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), 0.f, inf);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, nan, -1.f), 0.f, inf);
    add(Vec3(inf, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), 0.f, inf);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, -inf), 0.f, inf);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, 0.f), 0.f, inf);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), nan, inf);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), 0.f, nan);
    add(Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), 3.f, 2.f);
    for (AccelKind k : {AccelKind::Brute, AccelKind::Builtin, AccelKind::Embree}) {
        AccelOptions ao;
        ao.kind = k;
        const auto accel = make_accel(scene, ao);
        for (const Ray& r : bad) {
            CHECK_FALSE(accel->intersect(r).has_value());
            CHECK_FALSE(accel->occluded(r));
        }
        // The valid version of the same ray hits the unit sphere mesh.
        const Ray good{Vec3(0.f, 0.f, 5.f), Vec3(0.f, 0.f, -1.f), 0.f, inf};
        const auto h = accel->intersect(good);
        REQUIRE(h.has_value());
        CHECK(h->t == Approx(4.f).epsilon(1e-3));
        CHECK(accel->occluded(good));
        for (const Ray& r : random_rays(scene, 3000, 21))
            REQUIRE(accel->occluded(r) == accel->intersect(r).has_value());
    }
}

TEST_CASE("empty scenes and names", "[accel][quick]") {
    Scene empty;
    empty.finalize();
    for (AccelKind k : {AccelKind::Brute, AccelKind::Builtin, AccelKind::Embree}) {
        AccelOptions ao;
        ao.kind = k;
        const auto accel = make_accel(empty, ao);
        const Ray r{Vec3(0.f), Vec3(0.f, 0.f, 1.f), 0.f, std::numeric_limits<float>::infinity()};
        CHECK_FALSE(accel->intersect(r).has_value());
        CHECK_FALSE(accel->occluded(r));
        CHECK(parse_accel_kind(accel_kind_name(k)) == k);
        CHECK(std::string(accel->name()) == accel_kind_name(k));
    }
    CHECK_THROWS_AS(parse_accel_kind("optix"), Error);
}

TEST_CASE("check and bench libraries run on a small scene", "[accel][quick]") {
    const Scene scene = make_procedural_scene("sphere:2000");
    CheckOptions copt;
    copt.camera_width = 64;
    copt.camera_height = 48;
    copt.bounce_rays = 5000;
    copt.shadow_rays = 5000;
    copt.edge_rays = 5000;
    const CheckReport rep = run_check(scene, copt);
    REQUIRE(rep.accels.size() == 3);
    CHECK(rep.accels[0] == "brute");
    REQUIRE(rep.pairs.size() == 2);
    for (const CheckPair& p : rep.pairs)
        CHECK(p.rays() == 64u * 48u + 15000u);
    CHECK(rep.ok());
    CHECK(rep.to_text().find("brute vs builtin") != std::string::npos);
    const nlohmann::json cj = nlohmann::json::parse(rep.to_json());
    CHECK(cj.at("ok") == true);
    CHECK(cj.at("accels") == nlohmann::json(rep.accels));
    REQUIRE(cj.at("pairs").size() == 2);
    CHECK(cj.at("pairs")[1].at("other") == rep.pairs[1].other);
    CHECK(cj.at("pairs")[0].at("counts").at("camera").at("agree") ==
          rep.pairs[0]
              .counts[static_cast<int>(CheckRayKind::Camera)][static_cast<int>(HitClass::Agree)]);
    CHECK(cj.at("occlusion_mismatches").at("brute") == 0);

    BenchOptions bopt;
    bopt.primary_width = 32;
    bopt.primary_height = 32;
    bopt.bounce_rays = 2000;
    bopt.shadow_rays = 2000;
    bopt.min_seconds = 0.01;
    const BenchReport br = run_bench(scene, bopt);
    // Every backend must find the same number of hits on the same batches.
    for (int k = 0; k < static_cast<int>(BenchRayKind::Count); ++k) {
        std::uint64_t hits = std::numeric_limits<std::uint64_t>::max();
        for (const BenchResult& r : br.results) {
            if (r.kind != static_cast<BenchRayKind>(k)) continue;
            CHECK(r.mrays_per_s > 0.0);
            if (hits == std::numeric_limits<std::uint64_t>::max()) hits = r.hits;
            CHECK(r.hits == hits);
        }
    }
    CHECK(br.ratio("embree", "embree-raw", BenchRayKind::Bounce, 1) > 0.0);
    const nlohmann::json bj = nlohmann::json::parse(br.to_json());
    CHECK(bj.at("triangles") == br.triangles);
    REQUIRE(bj.at("results").size() == br.results.size());
    REQUIRE(bj.at("builds").size() == br.builds.size());
    CHECK(bj.at("results")[0].at("hits") == br.results[0].hits);
    CHECK(bj.at("results")[0].at("kind") == bench_ray_kind_name(br.results[0].kind));
}
