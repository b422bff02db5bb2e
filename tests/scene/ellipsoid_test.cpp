// Ellipsoids (spheres under a non-similarity transform): every backend's hits against the
// implicit equation, the projected area against pi |det A| |A^-1 v|, make_interaction's point,
// normal and error bound, and rays spawned from ellipsoid hits that must not re-hit the
// surface they leave.
#include "candela/accel/accel.h"
#include "candela/accel/brute.h"
#include "candela/accel/sphere.h"
#include "candela/numerics/double_brute.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/scene/interaction.h"
#include "candela/scene/scene.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <vector>

using namespace candela;

namespace {

/// z bound for the coverage estimates (false failure ~6e-5 per comparison).
constexpr double kZ = 4.0;

/// A rotation by `angle` radians about the unit axis `a` (Rodrigues).
Mat3d rotation(Vec3d a, double angle) {
    a = normalize(a);
    const double c = std::cos(angle), s = std::sin(angle), k = 1.0 - c;
    Mat3d r;
    r.m[0][0] = c + a.x * a.x * k;
    r.m[0][1] = a.x * a.y * k - a.z * s;
    r.m[0][2] = a.x * a.z * k + a.y * s;
    r.m[1][0] = a.y * a.x * k + a.z * s;
    r.m[1][1] = c + a.y * a.y * k;
    r.m[1][2] = a.y * a.z * k - a.x * s;
    r.m[2][0] = a.z * a.x * k - a.y * s;
    r.m[2][1] = a.z * a.y * k + a.x * s;
    r.m[2][2] = c + a.z * a.z * k;
    return r;
}

Mat3d diag(double a, double b, double c) {
    Mat3d d;
    d.m[0][0] = a;
    d.m[1][1] = b;
    d.m[2][2] = c;
    return d;
}

/// A shear x += k y, then z += k x.
Mat3d shear(double k) {
    Mat3d s1, s2;
    s1.m[0][1] = k;
    s2.m[2][0] = k;
    return s2 * s1;
}

/// The maps the tests use: axis-aligned, rotated, rotated and sheared, strongly anisotropic
/// and rotated, mirrored.
std::vector<Mat3d> test_maps() {
    return {diag(1.0, 2.0, 0.5),
            rotation(Vec3d(1, 2, 3), 0.7) * diag(0.3, 1.2, 0.6) * rotation(Vec3d(-1, 0, 2), 1.9),
            rotation(Vec3d(0, 1, 1), 0.4) * shear(1.5) * diag(0.8, 0.4, 1.1),
            rotation(Vec3d(1, 1, 0), 0.9) * diag(2.0, 0.05, 1.0) * rotation(Vec3d(0, 0, 1), 0.3),
            diag(-1.0, 0.7, 1.3) * shear(0.5)};
}

Scene one_ellipsoid_scene(const Vec3& c, const Mat3d& L) {
    Scene s;
    s.materials.push_back(Material{});
    s.spheres.push_back(make_ellipsoid(c, L, 0));
    s.finalize();
    return s;
}

/// |B (p - c)| in double with B the stored to_object: 1 on the surface every backend
/// intersects (scene.h).
double implicit(const Sphere& e, const Vec3d& p) {
    return length(Mat3d(e.to_object) * (p - Vec3d(e.center)));
}

std::vector<std::unique_ptr<Accel>> all_backends(const Scene& s) {
    std::vector<std::unique_ptr<Accel>> v;
    for (AccelKind k : {AccelKind::Brute, AccelKind::Builtin, AccelKind::Embree}) {
        AccelOptions o;
        o.kind = k;
        v.push_back(make_accel(s, o));
    }
    return v;
}

/// A ray from a random point on a sphere of radius `far` around c toward a random point of the
/// ellipsoid's bounding box, so that most rays hit.
Ray aimed_ray(const Scene& s, Pcg32& rng, float far) {
    const Bounds3 b = s.spheres[0].bounds();
    const Vec3 c = s.spheres[0].center;
    Ray r;
    r.o = c + square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float())) * far;
    const Vec3 target =
        b.lo + (b.hi - b.lo) * Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    r.d = normalize(target - r.o);
    return r;
}

} // namespace

TEST_CASE("ellipsoid: every backend's hits lie on the implicit surface", "[ellipsoid][quick]") {
    // Float hits carry the rounding of carrying the ray into object space: a few ulps of
    // |o - c| in object units (|B| |o - c|), amplified by map_error. 1e-5 is ~80 ulps.
    constexpr double kOnSurfaceRel = 1e-5;
    // Rays closer to tangent than this decide hit or miss, and t, by rounding.
    constexpr double kGrazingCos = 1e-2;
    Pcg32 rng(31, 1);
    for (const Mat3d& L : test_maps())
        for (const Vec3 c : {Vec3(0.f), Vec3(30.f, -12.f, 7.f)}) {
            const Scene s = one_ellipsoid_scene(c, L);
            const Sphere& e = s.spheres[0];
            const Mat3d inv = Mat3d(e.to_world).inverse();
            double inv_norm = 0.0;
            for (int k = 0; k < 3; ++k)
                inv_norm = std::max(inv_norm, length(inv.row(k)));
            const DoubleBruteAccel exact(s);
            const auto backends = all_backends(s);
            int hits = 0;
            for (int i = 0; i < 2000; ++i) {
                const Ray r = aimed_ray(s, rng, 5.f);
                const auto hd = exact.intersect_double(r);
                for (const auto& a : backends) {
                    const auto h = a->intersect(r);
                    INFO(a->name() << " ray " << i);
                    if (!h && !hd) continue;
                    const Vec3d q = Vec3d(r.o) + Vec3d(r.d) * (hd ? hd->t : double(h->t));
                    const Vec3d grad = inv.transpose_mul(inv * (q - Vec3d(e.center)));
                    const double cos_d = std::abs(dot(normalize(grad), Vec3d(r.d)));
                    if (cos_d < kGrazingCos) continue;
                    REQUIRE(h.has_value() == hd.has_value());
                    const Vec3d qf = Vec3d(r.o) + Vec3d(r.d) * double(h->t);
                    const double obj_scale = inv_norm * length(Vec3d(r.o) - Vec3d(e.center));
                    CHECK(std::abs(implicit(e, qf) - 1.0) <=
                          kOnSurfaceRel * e.map_error * (1.0 + obj_scale) / cos_d);
                    CHECK(h->t == Approx(hd->t).epsilon(kOnSurfaceRel * e.map_error / cos_d));
                }
                if (hd) {
                    ++hits;
                    // The double reference solves the implicit equation to double precision.
                    CHECK(implicit(e, Vec3d(r.o) + Vec3d(r.d) * hd->t) ==
                          Approx(1.0).epsilon(1e-9));
                }
            }
            CHECK(hits > 400);
        }
}

TEST_CASE("ellipsoid: projected area is pi |det A| |A^-1 v| in every backend",
          "[ellipsoid][stat]") {
    // Parallel rays along v through a stratified set of points of a square around the
    // silhouette; the covered fraction is binomial.
    constexpr int kRays = 40000;
    Pcg32 rng(32, 2);
    for (const Mat3d& L : test_maps()) {
        const Scene s = one_ellipsoid_scene(Vec3(0.5f, -0.25f, 1.f), L);
        const Sphere& e = s.spheres[0];
        const auto backends = all_backends(s);
        for (const Vec3d v :
             {Vec3d(0, 0, 1), normalize(Vec3d(1, -2, 0.5)), normalize(Vec3d(-0.3, 1, 2))}) {
            // Cauchy: the projected area is the integral of max(0, n . v) over the surface;
            // with Nanson's dA = |det A| |A^-T x| dA_x that is |det A| times the integral of
            // max(0, x . A^-1 v) over the unit sphere, pi |A^-1 v|.
            const double exact =
                kPi * std::abs(Mat3d(e.to_world).det()) * length(Mat3d(e.to_object) * v);
            // A square of half side R (the bounding sphere's radius) perpendicular to v.
            const double R = 0.5 * length(Vec3d(e.bounds().hi - e.bounds().lo));
            const Frame f{Vec3(v)};
            for (const auto& a : backends) {
                int covered = 0;
                const int side = 200; // side x side strata, one jittered ray each
                for (int i = 0; i < kRays; ++i) {
                    const int ix = i % side, iy = (i / side) % side;
                    const double sx = ((ix + rng.next_float()) / side * 2.0 - 1.0) * R;
                    const double sy = ((iy + rng.next_float()) / side * 2.0 - 1.0) * R;
                    Ray r;
                    r.o = e.center + f.s * float(sx) + f.t * float(sy) - f.n * float(4.0 * R);
                    r.d = f.n;
                    covered += a->intersect(r).has_value();
                }
                const double area = 4.0 * R * R;
                const double frac = double(covered) / kRays;
                const double est = frac * area;
                // Stratification only lowers the variance below the binomial one.
                const double se = area * std::sqrt(frac * (1.0 - frac) / kRays);
                INFO(a->name() << ": covered area " << est << " +- " << se << ", exact " << exact);
                CHECK(std::abs(est - exact) <= kZ * se);
            }
        }
    }
}

TEST_CASE("ellipsoid: interaction point, normal and error bound", "[ellipsoid][quick]") {
    Pcg32 rng(33, 3);
    for (const Mat3d& L : test_maps())
        for (const Vec3 c : {Vec3(0.f), Vec3(-200.f, 50.f, 1000.f)}) {
            const Scene s = one_ellipsoid_scene(c, L);
            const Sphere& e = s.spheres[0];
            const BruteAccel brute(s, TriangleTest::MollerTrumbore);
            int n = 0;
            for (int i = 0; i < 2000; ++i) {
                const Ray r = aimed_ray(s, rng, 5.f);
                const auto h = brute.intersect(r);
                if (!h) continue;
                ++n;
                const SurfaceInteraction si = make_interaction(s, r, *h);
                // The re-projected point is on the surface within its own error bound: a
                // displacement d changes F(p) = |B (p - c)| by about xh . B d (xh the unit
                // object point), so |F(p) - 1| <= |B^T xh| . p_error to first order. Both
                // surfaces are checked: that of the exact inverse of to_world and that of
                // the stored to_object (the one the backends intersect).
                const Vec3d p(si.p);
                const Vec3d perr(si.p_error);
                for (const Mat3d& B : {Mat3d(e.to_world).inverse(), Mat3d(e.to_object)}) {
                    const Vec3d xo = B * (p - Vec3d(e.center));
                    const double F = length(xo);
                    const double bound = dot(vabs(B.transpose_mul(xo / F)), perr);
                    CHECK(std::abs(F - 1.0) <= bound);
                    // ...and the bound is tight enough to mean something: ~100 ulps of the
                    // coordinates, in object units, times the maps' amplification.
                    double b_norm = 0.0;
                    for (int k = 0; k < 3; ++k)
                        b_norm = std::max(b_norm, length(B.row(k)));
                    CHECK(bound < 1e-5 * e.map_error * (1.0 + max_component(vabs(p)) * b_norm));
                }
                const Vec3d x = Mat3d(e.to_world).inverse() * (p - Vec3d(e.center));
                // Normal: the normalised gradient of |A^-1 (p - c)|^2.
                const Vec3d grad = Mat3d(e.to_world).inverse().transpose_mul(x);
                const Vec3d n_exact = normalize(grad);
                // The angle error follows the hit's own object-space rounding: ~ulps of
                // |p| |B| (large for a thin ellipsoid far from the origin).
                double b_norm = 0.0;
                for (int k = 0; k < 3; ++k)
                    b_norm = std::max(b_norm, length(Mat3d(e.to_object).row(k)));
                const double angle = length(cross(normalize(Vec3d(si.ns)), n_exact));
                CHECK(angle < 1e-5 * e.map_error * (1.0 + max_component(vabs(p)) * b_norm));
                CHECK(si.ng == si.ns);
                CHECK(std::abs(length(si.ns) - 1.f) < 1e-5f);
                // Outward: the ray came from outside, so it meets the normal head-on.
                CHECK(dot(si.ns, r.d) < 0.f);
                CHECK(si.p_error.x > 0.f);
                CHECK(max_component(si.p_error) <
                      1e-4f * (max_component(vabs(si.p)) + length(Vec3(L.column(0)))));
            }
            CHECK(n > 400);
        }
}

TEST_CASE("ellipsoid: rays spawned from hits never re-hit the surface they leave",
          "[ellipsoid][quick]") {
    // Inward rays closer to the tangent plane than this may leave through a chord shorter than
    // the offset; they are checked only for not hitting at the origin.
    constexpr float kInwardCos = 0.05f;
    Pcg32 rng(34, 4);
    for (const Mat3d& L : test_maps())
        for (const Vec3 c : {Vec3(0.f), Vec3(-200.f, 50.f, 1000.f)}) {
            const Scene s = one_ellipsoid_scene(c, L);
            const auto backends = all_backends(s);
            const BruteAccel brute(s, TriangleTest::MollerTrumbore);
            int leaving = 0, entering = 0;
            std::vector<SurfaceInteraction> points;
            for (int i = 0; i < 600; ++i) {
                const Ray r = aimed_ray(s, rng, 5.f);
                const auto h = brute.intersect(r);
                if (!h) continue;
                const SurfaceInteraction si = make_interaction(s, r, *h);
                points.push_back(si);
                // Directions over the whole sphere, and two within 1e-4 of the tangent plane.
                for (int k = 0; k < 8; ++k) {
                    Vec3 w = square_to_uniform_sphere(Vec2(rng.next_float(), rng.next_float()));
                    if (k == 0) w = normalize(w - si.ns * dot(w, si.ns) + si.ns * 1e-4f);
                    if (k == 1) w = normalize(w - si.ns * dot(w, si.ns) - si.ns * 1e-4f);
                    const Ray out = spawn_ray(si, w);
                    const float cos_n = dot(w, si.ng);
                    for (const auto& a : backends) {
                        const auto hit = a->intersect(out);
                        INFO(a->name() << ", centre (" << c.x << ", " << c.y << ", " << c.z
                                       << "), cos " << cos_n);
                        if (cos_n > 0.f) {
                            // A convex surface is never met again on the way out.
                            REQUIRE_FALSE(hit.has_value());
                        } else if (cos_n < -kInwardCos) {
                            // Inward: the far side, not the surface just left.
                            REQUIRE(hit.has_value());
                            const Vec3 q = out.o + out.d * hit->t;
                            REQUIRE(length(q - si.p) > 10.f * max_component(si.p_error));
                        } else if (hit) {
                            REQUIRE(hit->t > 0.f);
                        }
                    }
                    (cos_n > 0.f ? leaving : entering) += 1;
                }
            }
            CHECK(leaving > 500);
            CHECK(entering > 500);
            // Shadow rays between two points of the surface run inside it: never occluded by
            // the ellipsoid itself (the sphere-light-from-inside case).
            for (std::size_t i = 1; i < points.size(); ++i) {
                const SurfaceInteraction& a = points[i - 1];
                const SurfaceInteraction& b = points[i];
                const Ray sh = spawn_ray_to(a, b.p, b.p_error, b.ng);
                for (const auto& acc : backends) {
                    INFO(acc->name());
                    REQUIRE_FALSE(acc->occluded(sh));
                }
            }
        }
}
