// The double-precision brute-force intersector: the numerics suite's oracle.
#include "candela/numerics/double_brute.h"

#include "candela/accel/sphere.h"
#include "candela/accel/triangle.h"
#include "candela/scene/scene.h"

namespace candela {

std::optional<HitD> DoubleBruteAccel::intersect_double(const Ray& ray) const {
    if (!is_valid_ray(ray)) return std::nullopt;
    const Vec3d o(ray.o), d(ray.d);
    const double tmin = ray.tmin;
    double tmax = ray.tmax;
    std::optional<HitD> best;
    for (std::uint32_t g = 0; g < scene_.meshes.size(); ++g) {
        const Mesh& m = scene_.meshes[g];
        const std::uint32_t n = static_cast<std::uint32_t>(m.triangle_count());
        for (std::uint32_t j = 0; j < n; ++j) {
            TriangleHitD th;
            if (!intersect_triangle_mt_double(o, d, Vec3d(m.positions[m.indices[3 * j]]),
                                              Vec3d(m.positions[m.indices[3 * j + 1]]),
                                              Vec3d(m.positions[m.indices[3 * j + 2]]), tmin, tmax,
                                              th))
                continue;
            tmax = th.t;
            best = HitD{th.t, th.u, th.v, g, j};
        }
    }
    const std::uint32_t sg = scene_.sphere_geom_id();
    for (std::uint32_t j = 0; j < scene_.spheres.size(); ++j) {
        const Sphere& s = scene_.spheres[j];
        double t = 0.0;
        if (!intersect_sphere_prim_double(s, o, d, tmin, tmax, t)) continue;
        tmax = t;
        best = HitD{t, 0.0, 0.0, sg, j};
    }
    return best;
}

std::optional<Hit> DoubleBruteAccel::intersect(const Ray& ray) const {
    const std::optional<HitD> h = intersect_double(ray);
    if (!h) return std::nullopt;
    return Hit{static_cast<float>(h->t), static_cast<float>(h->u), static_cast<float>(h->v),
               h->geom_id, h->prim_id};
}

Bounds3 DoubleBruteAccel::bounds() const {
    return scene_.bounds;
}

} // namespace candela
