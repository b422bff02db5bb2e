// What the transport cases share: their scenes, renders and comparisons with analytic values.
#include "transport_support.h"

#include "candela/scene/procedural.h"
#include "candela/scene/scene_editor.h"

#include "candela/accel/accel.h"

#include <fmt/format.h>
#include <cmath>
#include <cstdio>
#include <memory>

namespace candela::numerics::transport {

RenderSettings case_settings(int size, int spp, std::uint64_t seed) {
    RenderSettings s;
    s.width = s.height = size;
    s.spp = spp;
    s.threads = 0;
    s.quiet = true;
    s.accel.kind = AccelKind::Embree;
    s.aovs = AovSet::parse("variance");
    s.seed = seed;
    return s;
}

Measured render_measure(const Scene& scene, const RenderSettings& s, double ref) {
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    Renderer renderer(scene, *accel, s);
    RenderStats stats;
    Film film = renderer.render(stats);

    Measured m;
    m.samples = stats.samples;
    m.dropped = film.total_dropped();
    m.rays = stats.rays;
    m.seconds = stats.seconds;
    double sum = 0.0, var = 0.0;
    m.min_pixel = INFINITY;
    m.max_pixel = -INFINITY;
    const double P = double(film.width()) * film.height();
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            const Rgb px = film.mean(x, y);
            if (!is_finite(px)) {
                ++m.nonfinite_pixels;
                continue;
            }
            const double lum = luminance(px);
            sum += lum;
            m.min_pixel = std::min(m.min_pixel, lum);
            m.max_pixel = std::max(m.max_pixel, lum);
            // Standard deviation of the luminance of the mean, treating the channels as fully
            // correlated (an upper bound).
            const Rgb v = film.variance_of_mean(x, y);
            const double sd =
                0.2126 * std::sqrt(v.x) + 0.7152 * std::sqrt(v.y) + 0.0722 * std::sqrt(v.z);
            var += sd * sd;
            if (ref > 0.0)
                for (int c = 0; c < 3; ++c)
                    m.max_rel_dev = std::max(m.max_rel_dev, std::abs(double(px[c]) - ref) / ref);
        }
    m.mean = sum / P;
    m.std_err = std::sqrt(var) / P;
    return m;
}

std::uint32_t add_material(Scene& scene, const Material& m) {
    return SceneEditor(scene).add_material(m);
}

Material diffuse_material(float albedo, float Le) {
    Material m;
    m.kind = BsdfKind::Diffuse;
    m.albedo = Rgb(albedo);
    m.radiance = Rgb(Le);
    m.name = "diffuse";
    return m;
}

Material emission_material(float Le) {
    Material m;
    m.kind = BsdfKind::Emission;
    m.radiance = Rgb(Le);
    m.name = "emitter";
    return m;
}

Material glass_material(float ior) {
    Material m;
    m.kind = BsdfKind::Glass;
    m.ior = ior;
    m.reflectance = Rgb(1.f);
    m.transmittance = Rgb(1.f);
    m.name = "glass";
    return m;
}

Material conductor_material(float alpha, const Rgb& eta, const Rgb& k) {
    Material m;
    m.kind = BsdfKind::Microfacet;
    m.alpha = alpha;
    m.eta = eta;
    m.k = k;
    m.name = "conductor";
    return m;
}

void add_sphere(Scene& scene, const Vec3& c, float r, std::uint32_t mat) {
    Sphere s;
    s.center = c;
    s.radius = r;
    s.material = mat;
    SceneEditor(scene).add_sphere(s);
}

namespace {

/// Appends the quad centre +- a +- b (normal cross(a, b)) to `mesh` as two triangles.
void add_quad(Mesh& mesh, const Vec3& centre, const Vec3& a, const Vec3& b) {
    const auto base = std::uint32_t(mesh.positions.size());
    const Vec3 n = normalize(cross(a, b));
    for (const Vec3& p : {centre - a - b, centre + a - b, centre + a + b, centre - a + b}) {
        mesh.positions.push_back(p);
        mesh.normals.push_back(n);
    }
    for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u})
        mesh.indices.push_back(base + i);
}

} // namespace

void add_box(Scene& scene, const Vec3& lo, const Vec3& hi, std::uint32_t mat) {
    Mesh mesh;
    mesh.name = "box";
    mesh.material = mat;
    const Vec3 c = (lo + hi) * 0.5f, h = (hi - lo) * 0.5f;
    const Vec3 ex(h.x, 0, 0), ey(0, h.y, 0), ez(0, 0, h.z);
    // cross(a, b) points outward for each face.
    add_quad(mesh, c + ex, ey, ez);
    add_quad(mesh, c - ex, ez, ey);
    add_quad(mesh, c + ey, ez, ex);
    add_quad(mesh, c - ey, ex, ez);
    add_quad(mesh, c + ez, ex, ey);
    add_quad(mesh, c - ez, ey, ex);
    SceneEditor(scene).add_mesh(std::move(mesh));
}

void add_sky(Scene& scene, float Le) {
    Light sky;
    sky.kind = LightKind::Ambient;
    sky.L = Rgb(Le);
    SceneEditor(scene).add_light(sky);
}

Camera look_at(const Vec3& pos, const Vec3& target, const Vec3& up, float hfov_deg) {
    Camera c;
    c.pos = pos;
    c.z = normalize(pos - target); // the camera looks along -z
    c.x = normalize(cross(up, c.z));
    c.y = cross(c.z, c.x);
    c.hfov_deg = hfov_deg;
    c.znear = 0.f;
    c.zfar = 1e30f;
    c.target = target;
    return c;
}

std::string method_of(const RenderSettings& s, const char* what) {
    return fmt::format("{}, {}x{} x {} spp, {}", what, s.width, s.height, s.spp,
                        accel_kind_name(s.accel.kind));
}

StressResult band_row(const std::string& group, const std::string& name, const std::string& method,
                      const std::string& expected_desc, double lo, double hi, const Measured& m,
                      double informative_rel) {
    StressResult r;
    r.group = group;
    r.name = name;
    r.method = method;
    const double centre = 0.5 * (lo + hi);
    const double dist = m.mean < lo ? m.mean - lo : (m.mean > hi ? m.mean - hi : 0.0);
    const double z = m.std_err > 0.0 ? dist / m.std_err : (dist == 0.0 ? 0.0 : INFINITY);
    r.expected = expected_desc + fmt::format(", |z| < {:.0f}, se < {:.1f}%, 0 non-finite", kZBound,
                                              100.0 * informative_rel);
    r.measured = fmt::format("{:.6g} +- {:.2g} (z = {:.2f}, rel. err {:+.2g}%), {} non-finite of {}",
                              m.mean, m.std_err, z, 100.0 * (m.mean - centre) / centre,
                              m.dropped, m.samples);
    r.pass = std::abs(z) < kZBound && m.std_err < informative_rel * std::abs(centre) &&
             m.dropped == 0 && m.nonfinite_pixels == 0;
    return r;
}

StressResult z_row(const std::string& group, const std::string& name, const std::string& method,
                   const std::string& expected_desc, double expected, const Measured& m,
                   double informative_rel) {
    return band_row(group, name, method, expected_desc, expected, expected, m, informative_rel);
}

} // namespace candela::numerics::transport
