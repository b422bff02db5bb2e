// The scene's records: kind names, area lights, spheres and ellipsoids and their areas, finalize.
#include "candela/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace candela {

const char* bsdf_kind_name(BsdfKind k) {
    switch (k) {
    case BsdfKind::Diffuse:
        return "diffuse";
    case BsdfKind::Emission:
        return "emission";
    case BsdfKind::Mirror:
        return "mirror";
    case BsdfKind::Glass:
        return "glass";
    case BsdfKind::Refraction:
        return "refraction";
    case BsdfKind::Microfacet:
        return "microfacet";
    case BsdfKind::Count:
        break;
    }
    return "?";
}

Light rect_light(const Vec3& center, const Vec3& n, const Vec3& dx, const Vec3& dy, const Rgb& L) {
    Light l;
    l.kind = LightKind::Area;
    l.L = L;
    l.p = center;
    l.n = n;
    l.dx = dx;
    l.dy = dy;
    l.area = length(cross(dx, dy));
    return l;
}

const char* light_kind_name(LightKind k) {
    switch (k) {
    case LightKind::Area:
        return "area";
    case LightKind::Mesh:
        return "mesh";
    case LightKind::Sphere:
        return "sphere";
    case LightKind::Point:
        return "point";
    case LightKind::Spot:
        return "spot";
    case LightKind::Directional:
        return "directional";
    case LightKind::Ambient:
        return "ambient";
    case LightKind::Environment:
        return "environment";
    case LightKind::Count:
        break;
    }
    return "?";
}

Bounds3 Sphere::bounds() const {
    Vec3 half(radius);
    if (ellipsoid)
        half = Vec3(length(to_world.row(0)), length(to_world.row(1)), length(to_world.row(2)));
    return Bounds3{center - half, center + half};
}

bool is_similarity(const Mat3d& L, double* scale) {
    if (!L.is_finite()) return false;
    const Vec3d c[3] = {L.column(0), L.column(1), L.column(2)};
    const double len[3] = {length(c[0]), length(c[1]), length(c[2])};
    const double mean = (len[0] + len[1] + len[2]) / 3.0;
    if (!(mean > 0.0) || !std::isfinite(mean)) return false;
    for (int i = 0; i < 3; ++i) {
        if (std::abs(len[i] - mean) > kSimilarityRelTol * mean) return false;
        const Vec3d& a = c[i];
        const Vec3d& b = c[(i + 1) % 3];
        if (std::abs(dot(a, b)) > kSimilarityRelTol * len[i] * len[(i + 1) % 3]) return false;
    }
    *scale = mean;
    return true;
}

Sphere make_ellipsoid(const Vec3& center, const Mat3d& L, std::uint32_t material) {
    Sphere s;
    s.center = center;
    s.radius = 1.f;
    s.material = material;
    s.ellipsoid = true;
    s.to_world = Mat3(L);
    // Invert the float map that is stored (not L itself), so that the two stored matrices are
    // inverses of each other up to their own rounding.
    const Mat3d A(s.to_world);
    const Mat3d inv = A.inverse();
    s.to_object = Mat3(inv);
    // max(||M||_1, ||M||_inf) >= sqrt(||M||_1 ||M||_inf) >= ||M||_2 for M = |B| |A|.
    const Mat3d M = Mat3d(s.to_object).abs() * A.abs();
    Mat3d Mt;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            Mt.m[i][j] = M.m[j][i];
    s.map_error = static_cast<float>(std::max({1.0, M.norm_inf(), Mt.norm_inf()}));
    return s;
}

namespace {
/// Gauss-Legendre nodes and weights on [-1, 1] by Newton's method on P_n (Golub & Welsch would do
/// as well; n is small and this runs once per emissive ellipsoid).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
    constexpr double kNewtonTol = 1e-15; // double precision of the nodes
    constexpr int kMaxNewton = 100;
    x.assign(static_cast<std::size_t>(n), 0.0);
    w.assign(static_cast<std::size_t>(n), 0.0);
    for (int i = 0; i < n; ++i) {
        double z = std::cos(kPiD * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < kMaxNewton; ++it) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (std::abs(dz) < kNewtonTol) break;
        }
        x[static_cast<std::size_t>(i)] = z;
        w[static_cast<std::size_t>(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}
} // namespace

double sphere_area(const Sphere& s) {
    if (!s.ellipsoid) return 4.0 * kPiD * double(s.radius) * double(s.radius);
    // Nanson: a unit-sphere patch dA with normal n maps to |det A| |A^-T n| dA. Gauss-Legendre
    // in cos(theta) (the integrand is smooth in it) times the trapezoid rule in phi (spectrally
    // accurate for a smooth periodic integrand).
    constexpr int kZNodes = 96, kPhiNodes = 192;
    const Mat3d inv(s.to_object);
    const double det = std::abs(Mat3d(s.to_world).det());
    std::vector<double> z, w;
    gauss_legendre(kZNodes, z, w);
    double sum = 0.0;
    for (int i = 0; i < kZNodes; ++i) {
        const double r = std::sqrt(
            std::max(0.0, 1.0 - z[static_cast<std::size_t>(i)] * z[static_cast<std::size_t>(i)]));
        double ring = 0.0;
        for (int j = 0; j < kPhiNodes; ++j) {
            const double phi = 2.0 * kPiD * j / kPhiNodes;
            const Vec3d n(r * std::cos(phi), r * std::sin(phi), z[static_cast<std::size_t>(i)]);
            ring += length(inv.transpose_mul(n));
        }
        sum += w[static_cast<std::size_t>(i)] * ring * (2.0 * kPiD / kPhiNodes);
    }
    return det * sum;
}

void Scene::finalize() {
    bounds = Bounds3{};
    features = SceneFeatures{};
    for (const auto& m : meshes) {
        for (const Vec3& p : m.positions)
            bounds.grow(p);
        if (m.triangle_count() > 0)
            features.bsdf_mask |= 1u << static_cast<int>(materials.at(m.material).kind);
    }
    for (const auto& s : spheres) {
        bounds.grow(s.bounds());
        features.bsdf_mask |= 1u << static_cast<int>(materials.at(s.material).kind);
    }
    for (const auto& l : lights)
        features.light_mask |= 1u << static_cast<int>(l.kind);
}

} // namespace candela
