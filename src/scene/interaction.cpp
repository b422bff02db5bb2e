// Hit to shading data (make_interaction) and the robust offset of spawned rays.
#include "candela/scene/interaction.h"

#include "candela/math/float_error.h"
#include "candela/scene/scene.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <cmath>
#include <limits>
#include <string>

namespace candela {

using interaction_detail::kMinNormalLengthSq;
using interaction_detail::unit_or;

EllipsoidPoint ellipsoid_point(const Sphere& s, const Vec3& x, const Vec3& fallback_n) {
    EllipsoidPoint e;
    const float l2 = length_squared(x);
    // x = 0 only for a hit computed at the centre (impossible for a finite hit on a non-degenerate
    // ellipsoid); the pole then stands in for it.
    const Vec3 xu =
        (l2 > kMinNormalLengthSq && std::isfinite(l2)) ? x / std::sqrt(l2) : Vec3(0.f, 0.f, 1.f);
    const Vec3 local = s.to_world * xu;
    e.p = s.center + local;
    // Error bound of p (per axis). Let A = to_world, B = to_object (the stored floats), |.| the
    // element-wise absolute value, g(n) = float_gamma(n), m = map_error >= ||(|B| |A|)||_2.
    //  1. xu is unit up to the rounding of the normalisation: |xu| = 1 + d with |d| <= g(4)
    //     (three squares and two sums, a square root, a division). The surface point
    //     A xu / |xu| differs from A xu by A xu d / (1 + d): at most g(5) (|A| |xu|) per axis.
    //  2. Each row of A xu is a three-term dot product: at most g(3) (|A| |xu|) per axis, and
    //     adding the centre rounds once more: g(1) |p|.
    //  3. The surfaces of A and B differ: B A = I + E with |E| <= eps (|B| |A|) element-wise
    //     (roundings of an exact inverse pair), so |B A xu| - 1 is at most eps m.
    //  4. A ray spawned from p' (p offset along n) is carried into object space as B (p' - c),
    //     rounded by g(4) |B| |p' - c| <= g(4) (|B| |A| |xu|) per component: a radial error
    //     |xu . err| <= g(4) m (to first order), and intersect_sphere's |f|^2 - 1 adds g(3).
    //     The offset must cover it, or the ray could re-hit the surface it leaves.
    // An offset delta along the unit normal n = B^T xu / |B^T xu| moves |B (p - c)| by
    // delta |B^T xu|, and offset_ray_origin moves by delta = n . p_error. With p_error >=
    // k (|A| |xu|): delta |B^T xu| >= k |n . A xu| |B^T xu| = k |xu . B A xu| ~ k. Items 3 and 4
    // need k >= (g(1) + g(4) + g(3)) m, items 1 and 2 g(8). Rounded up generously:
    // p_error = (g(8) + g(10) m) (|A| |xu|) + g(1) |p|, about 3.5 times a sphere's own bound
    // g(5) |r n| + g(1) |p| for a round ellipsoid, and still ~1e-6 of its size.
    const Vec3 ax = s.to_world.abs() * vabs(xu);
    e.p_error = ax * (float_gamma(8) + float_gamma(10) * s.map_error) + vabs(e.p) * float_gamma(1);
    // Outward normal: the gradient of |B (p - c)|^2 is 2 B^T B (p - c) = 2 B^T xu.
    e.n = unit_or(s.to_object.transpose_mul(xu), fallback_n);
    return e;
}

SurfaceInteraction make_interaction(const Scene& scene, const Ray& ray, const Hit& hit) {
    SurfaceInteraction si;
    si.t = hit.t;
    si.geom_id = hit.geom_id;
    si.prim_id = hit.prim_id;
    si.wo = outgoing_direction(ray.d);

    if (hit.geom_id == scene.sphere_geom_id()) {
        CANDELA_CHECK(hit.prim_id < scene.spheres.size(),
                      "make_interaction: sphere " + std::to_string(hit.prim_id) + " out of range");
        const Sphere& s = scene.spheres[hit.prim_id];
        const Vec3 q = ray.o + ray.d * hit.t;
        if (s.is_ellipsoid()) {
            const EllipsoidPoint e = ellipsoid_point(s, s.to_object * (q - s.center), -si.wo);
            si.p = e.p;
            si.p_error = e.p_error;
            si.ng = si.ns = e.n;
        } else {
            const Vec3 n = unit_or(q - s.center, -si.wo);
            const Vec3 local = n * s.radius;
            si.p = s.center + local;
            // Re-projection leaves gamma(5)|local| (pbrt-v4 eq. 6.29) when it divides by the
            // length; unit_or multiplies by its reciprocal, one rounding more: gamma(6). Adding
            // the centre rounds once.
            si.p_error = vabs(local) * float_gamma(6) + vabs(si.p) * float_gamma(1);
            si.ng = si.ns = n;
        }
        si.material = s.material;
        si.light = s.light;
    } else {
        CANDELA_CHECK(hit.geom_id < scene.meshes.size(), "make_interaction: geometry " +
                                                             std::to_string(hit.geom_id) +
                                                             " out of range");
        const Mesh& m = scene.meshes[hit.geom_id];
        CANDELA_CHECK(hit.prim_id < m.triangle_count(),
                      "make_interaction: triangle " + std::to_string(hit.prim_id) +
                          " out of range in mesh '" + m.name + "'");
        const std::uint32_t i0 = m.indices[3 * hit.prim_id];
        const std::uint32_t i1 = m.indices[3 * hit.prim_id + 1];
        const std::uint32_t i2 = m.indices[3 * hit.prim_id + 2];
        const bool normals = m.normals.size() == m.positions.size();
        const Vec3 zero(0.f);
        const TriangleSurface t = triangle_surface(
            m.positions[i0], m.positions[i1], m.positions[i2], normals ? m.normals[i0] : zero,
            normals ? m.normals[i1] : zero, normals ? m.normals[i2] : zero, hit.u, hit.v, si.wo);
        si.p = t.p;
        si.p_error = t.p_error;
        si.ng = t.ng;
        si.ns = t.ns;
        si.material = m.material;
        si.light = m.light;
    }
    si.frame = Frame(si.ns);
    return si;
}

void adapt_shading_normal(SurfaceInteraction& si) {
    const Vec3 ns = adapted_shading_normal(si.ns, si.ng, si.wo);
    if (ns.x == si.ns.x && ns.y == si.ns.y && ns.z == si.ns.z) return;
    si.ns = ns;
    si.frame = Frame(si.ns);
}

} // namespace candela
