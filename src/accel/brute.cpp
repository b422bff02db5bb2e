// The brute-force backend: every ray against every triangle and sphere, the oracle of the others.
#include "candela/accel/brute.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/scene.h"

#include <cmath>
#include <utility>

namespace candela {

BruteAccel::BruteAccel(const Scene& scene, TriangleTest test) : scene_(scene), test_(test) {}

template <TriangleTest kTest, bool kAnyHit> bool BruteAccel::trace(const Ray& ray, Hit& hit) const {
    float tmax = ray.tmax;
    bool found = false;
    WatertightRay wr;
    if (kTest == TriangleTest::Watertight) wr = make_watertight_ray(ray.d);
    for (std::uint32_t g = 0; g < scene_.meshes.size(); ++g) {
        const Mesh& m = scene_.meshes[g];
        const std::uint32_t n = static_cast<std::uint32_t>(m.triangle_count());
        for (std::uint32_t j = 0; j < n; ++j) {
            const Vec3& p0 = m.positions[m.indices[3 * j]];
            const Vec3& p1 = m.positions[m.indices[3 * j + 1]];
            const Vec3& p2 = m.positions[m.indices[3 * j + 2]];
            TriangleHit th;
            const bool h =
                kTest == TriangleTest::Watertight
                    ? intersect_triangle_watertight(ray.o, wr, p0, p1, p2, ray.tmin, tmax, th)
                    : intersect_triangle_mt(ray.o, ray.d, p0, p1, p2, ray.tmin, tmax, th);
            if (!h) continue;
            if (kAnyHit) return true;
            found = true;
            tmax = th.t;
            hit = Hit{th.t, th.u, th.v, g, j};
        }
    }
    const std::uint32_t sg = scene_.sphere_geom_id();
    for (std::uint32_t j = 0; j < scene_.spheres.size(); ++j) {
        const Sphere& s = scene_.spheres[j];
        float t;
        if (!intersect_sphere_prim(s, ray.o, ray.d, ray.tmin, tmax, t)) continue;
        if (kAnyHit) return true;
        found = true;
        tmax = t;
        hit = Hit{t, 0.f, 0.f, sg, j};
    }
    return found;
}

std::optional<Hit> BruteAccel::intersect(const Ray& ray) const {
    if (!is_valid_ray(ray)) return std::nullopt;
    Hit hit;
    const bool found = test_ == TriangleTest::Watertight
                           ? trace<TriangleTest::Watertight, false>(ray, hit)
                           : trace<TriangleTest::MollerTrumbore, false>(ray, hit);
    if (!found) return std::nullopt;
    return hit;
}

bool BruteAccel::occluded(const Ray& ray) const {
    if (!is_valid_ray(ray)) return false;
    Hit hit;
    return test_ == TriangleTest::Watertight ? trace<TriangleTest::Watertight, true>(ray, hit)
                                             : trace<TriangleTest::MollerTrumbore, true>(ray, hit);
}

Bounds3 BruteAccel::bounds() const {
    return scene_.bounds;
}

} // namespace candela
