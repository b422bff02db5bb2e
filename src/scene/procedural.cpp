// Procedural scenes for tests and benchmarks, built without any file.
#include "candela/scene/procedural.h"

#include "candela/math/constants.h"
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

namespace candela {

namespace {

/// box:<kind>:<N>: half the edge of the open box around the content (which spans [-1, 1]^3).
constexpr float kBoxHalfSize = 2.f;
/// Radiance of the box's ceiling light: lights the walls to roughly unit brightness.
constexpr float kBoxLightRadiance = 12.f;

/// Swaps triangle windings so that every triangle's geometric normal points away from `c`
/// (valid for meshes star-shaped about c, which all procedural closed meshes are).
void orient_outward(Mesh& m, const Vec3& c) {
    for (std::size_t j = 0; j < m.triangle_count(); ++j) {
        std::uint32_t* t = &m.indices[3 * j];
        const Vec3 &p0 = m.positions[t[0]], &p1 = m.positions[t[1]], &p2 = m.positions[t[2]];
        const Vec3 centroid = (p0 + p1 + p2) / 3.f;
        if (dot(cross(p1 - p0, p2 - p0), centroid - c) < 0.f) std::swap(t[1], t[2]);
    }
}

/// A camera at `pos` looking along -z (axes x, y, z of the world), at the point of the axis at
/// height `target_y` and z = 0.
void look_down_z(Camera& camera, const Vec3& pos, float target_y, float hfov_deg, float zfar) {
    camera.pos = pos;
    camera.x = Vec3(1.f, 0.f, 0.f);
    camera.y = Vec3(0.f, 1.f, 0.f);
    camera.z = Vec3(0.f, 0.f, 1.f);
    camera.hfov_deg = hfov_deg;
    camera.znear = 0.01f;
    camera.zfar = zfar;
    camera.target = Vec3(0.f, target_y, 0.f);
}

void ensure_material(Scene& scene) {
    if (!scene.materials.empty()) return;
    Material mat;
    mat.kind = BsdfKind::Diffuse;
    mat.name = "procedural_diffuse";
    mat.albedo = Rgb(0.7f);
    SceneEditor(scene).add_material(mat);
}

/// Appends the five inner walls of the cube [-h, h]^3 without its +z face (the camera looks in
/// through that opening) as one mesh of material 0, each face with its own vertices and an
/// inward normal.
void add_open_box(Scene& scene, float h) {
    ensure_material(scene);
    Mesh m;
    m.name = "open_box";
    const Vec3 faces[5][2] = {// {inward normal, first edge}; the second edge is n x e1
                              {Vec3(0.f, 1.f, 0.f), Vec3(1.f, 0.f, 0.f)},
                              {Vec3(0.f, -1.f, 0.f), Vec3(1.f, 0.f, 0.f)},
                              {Vec3(0.f, 0.f, 1.f), Vec3(1.f, 0.f, 0.f)},
                              {Vec3(1.f, 0.f, 0.f), Vec3(0.f, 1.f, 0.f)},
                              {Vec3(-1.f, 0.f, 0.f), Vec3(0.f, 1.f, 0.f)}};
    m.positions.reserve(4 * 5);
    for (const auto& f : faces) {
        const Vec3 n = f[0], e1 = f[1] * h, e2 = cross(n, f[1]) * h, c = -n * h;
        const auto base = static_cast<std::uint32_t>(m.positions.size());
        for (const Vec3& p : {c - e1 - e2, c + e1 - e2, c + e1 + e2, c - e1 + e2}) {
            m.positions.push_back(p);
            m.normals.push_back(n);
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    SceneEditor(scene).add_mesh(std::move(m));
}

/// A light of kind `k % 4` (point, spot, rectangle, emissive sphere) at `p` emitting about the
/// power of a point light of intensity `intensity`, with its orientation and size drawn from
/// `rng`: a spot cone of half-angle cosine in [0.3, 0.9], a rectangle of sides in [0.1, 1] m (an
/// Area record, invisible to rays) facing `facing` when that is non-zero, else a random way, a
/// sphere of radius in [0.05, 0.3] m. Appends it (and a sphere's emission material) to `scene`.
void add_scattered_light(Scene& scene, std::size_t k, const Vec3& p, float intensity,
                         const Vec3& facing, std::mt19937_64& rng) {
    std::uniform_real_distribution<float> U(0.f, 1.f);
    const auto direction = [&] {
        for (;;) { // uniform on the sphere, by rejection from the cube
            const Vec3 v(2.f * U(rng) - 1.f, 2.f * U(rng) - 1.f, 2.f * U(rng) - 1.f);
            const float l2 = length_squared(v);
            if (l2 > 1e-4f && l2 <= 1.f) return v / std::sqrt(l2);
        }
    };
    SceneEditor editor(scene);
    Light l;
    l.p = p;
    l.L = Rgb(intensity);
    switch (k % 4) {
    case 0:
        l.kind = LightKind::Point;
        editor.add_light(l);
        break;
    case 1:
        l.kind = LightKind::Spot;
        l.n = direction();
        l.cos_total = 0.3f + 0.6f * U(rng);
        editor.add_light(l);
        break;
    case 2: {
        // pi L a b = 4 pi I: the power of the point light
        const float a = 0.1f + 0.9f * U(rng), b = 0.1f + 0.9f * U(rng);
        const Vec3 n = length_squared(facing) > 0.f ? facing : direction();
        const Vec3 t =
            normalize(cross(n, std::abs(n.x) < 0.9f ? Vec3(1.f, 0.f, 0.f) : Vec3(0.f, 1.f, 0.f)));
        editor.add_light(rect_light(p, n, t * a, cross(n, t) * b, Rgb(4.f * intensity / (a * b))));
        break;
    }
    default: {
        // 4 pi r^2 * pi L = 4 pi I
        const float r = 0.05f + 0.25f * U(rng);
        Material m;
        m.kind = BsdfKind::Emission;
        m.name = "sphere-light-" + std::to_string(k);
        m.radiance = Rgb(intensity / (kPi * r * r));
        Sphere sphere;
        sphere.center = p;
        sphere.radius = r;
        sphere.material = editor.add_material(m);
        editor.add_sphere(sphere);
        break;
    }
    }
}

/// A diffuse square of side 2 * half centred at `c` in the plane spanned by unit `u` and `v`,
/// facing cross(u, v), of material 0.
void add_square(Scene& scene, const Vec3& c, const Vec3& u, const Vec3& v, float half) {
    ensure_material(scene);
    Mesh m;
    m.name = "square";
    const Vec3 n = normalize(cross(u, v));
    for (const Vec3& q : {c - u * half - v * half, c + u * half - v * half, c + u * half + v * half,
                          c - u * half + v * half}) {
        m.positions.push_back(q);
        m.normals.push_back(n);
    }
    m.indices = {0, 1, 2, 0, 2, 3};
    SceneEditor(scene).add_mesh(std::move(m));
}

} // namespace

Scene make_near_wall_scene(std::size_t count, std::uint64_t seed) {
    Scene scene;
    scene.source = "nearwall:" + std::to_string(count) + ":" + std::to_string(seed);
    add_square(scene, Vec3(0.f), Vec3(1.f, 0.f, 0.f), Vec3(0.f, 1.f, 0.f), 4.f);
    SceneEditor editor(scene);
    Light near;
    near.kind = LightKind::Point;
    near.p = Vec3(0.6f, 0.4f, 0.95f);
    near.L = Rgb(4.4f);
    editor.add_light(near);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    for (std::size_t k = 0; k < count;) {
        const Vec3 p(24.f * U(rng) - 12.f, 24.f * U(rng) - 12.f, 24.f * U(rng) - 12.f);
        const float intensity = std::pow(10.f, 3.f * U(rng) - 2.f);
        if (length(p - near.p) < 3.f) continue;
        add_scattered_light(scene, k++, p, intensity, Vec3(0.f), rng);
    }
    look_down_z(scene.camera, Vec3(0.f, 0.f, 6.f), 0.f, 60.f, 100.f);
    editor.finalize();
    return scene;
}

Scene make_panel_lights_scene(std::size_t count, std::uint64_t seed) {
    Scene scene;
    scene.source = "inpanel:" + std::to_string(count) + ":" + std::to_string(seed);
    ensure_material(scene);
    add_floor(scene, 6.f, 0.f, 0);
    add_rect_light(scene, Vec3(0.f, 2.5f, 0.f), Vec3(6.f, 0.f, 0.f), Vec3(0.f, 0.f, 6.f),
                   Rgb(0.05f));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> U(0.f, 1.f);
    for (std::size_t k = 0; k < count; ++k) {
        const Vec3 p(6.f * U(rng) - 3.f, 0.2f + 2.2f * U(rng), 6.f * U(rng) - 3.f);
        const float intensity = 0.01f * std::pow(300.f, U(rng));
        add_scattered_light(scene, k, p, intensity, Vec3(0.f, -1.f, 0.f), rng);
    }
    look_down_z(scene.camera, Vec3(0.f, 1.5f, 9.f), 0.5f, 60.f, 100.f);
    SceneEditor(scene).finalize();
    return scene;
}

void add_uv_sphere_mesh(Scene& scene, const Vec3& c, float r, int rings) {
    ensure_material(scene);
    rings = std::max(rings, 2);
    const int segments = 2 * rings;
    Mesh m;
    m.name = "uv_sphere";
    const std::size_t nv = 2 + static_cast<std::size_t>(rings - 1) * segments;
    m.positions.reserve(nv);
    m.normals.reserve(nv);
    auto add = [&](const Vec3& n) {
        m.positions.push_back(c + n * r);
        m.normals.push_back(n);
    };
    add(Vec3(0.f, 1.f, 0.f));
    for (int i = 1; i < rings; ++i) {
        const double theta = kPiD * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double phi = 2.0 * kPiD * j / segments;
            add(Vec3(Vec3d(std::sin(theta) * std::cos(phi), std::cos(theta),
                           std::sin(theta) * std::sin(phi))));
        }
    }
    add(Vec3(0.f, -1.f, 0.f));
    const std::uint32_t south = static_cast<std::uint32_t>(nv - 1);
    auto ring_vertex = [&](int i, int j) {
        return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments));
    };
    m.indices.reserve(static_cast<std::size_t>(6) * segments * (rings - 1));
    for (int j = 0; j < segments; ++j) {
        m.indices.insert(m.indices.end(), {0u, ring_vertex(1, j + 1), ring_vertex(1, j)});
        m.indices.insert(m.indices.end(),
                         {south, ring_vertex(rings - 1, j), ring_vertex(rings - 1, j + 1)});
    }
    for (int i = 1; i < rings - 1; ++i)
        for (int j = 0; j < segments; ++j) {
            const std::uint32_t a = ring_vertex(i, j), b = ring_vertex(i, j + 1),
                                cc = ring_vertex(i + 1, j), d = ring_vertex(i + 1, j + 1);
            m.indices.insert(m.indices.end(), {a, b, d, a, d, cc});
        }
    orient_outward(m, c);
    SceneEditor(scene).add_mesh(std::move(m));
}

void add_icosphere_mesh(Scene& scene, const Vec3& c, float r, int subdivisions) {
    ensure_material(scene);
    // The icosahedron's vertices are the cyclic permutations of (0, +-1, +-g), g the golden
    // ratio, on the unit sphere after normalising; vertices are kept in double until the end.
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                            {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                            {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (Vec3d& p : v)
        p = normalize(p);
    std::vector<std::uint32_t> tri = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                      1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                      3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                      4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};
    for (int level = 0; level < subdivisions; ++level) {
        std::unordered_map<std::uint64_t, std::uint32_t> midpoint;
        auto middle = [&](std::uint32_t a, std::uint32_t b) {
            const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            const auto it = midpoint.find(key);
            if (it != midpoint.end()) return it->second;
            v.push_back(normalize(v[a] + v[b]));
            const auto index = static_cast<std::uint32_t>(v.size() - 1);
            midpoint.emplace(key, index);
            return index;
        };
        std::vector<std::uint32_t> next;
        next.reserve(tri.size() * 4);
        for (std::size_t j = 0; j < tri.size(); j += 3) {
            const std::uint32_t a = tri[j], b = tri[j + 1], d = tri[j + 2];
            const std::uint32_t ab = middle(a, b), bd = middle(b, d), da = middle(d, a);
            next.insert(next.end(), {a, ab, da, b, bd, ab, d, da, bd, ab, bd, da});
        }
        tri = std::move(next);
    }
    Mesh m;
    m.name = "icosphere";
    m.positions.reserve(v.size());
    m.normals.reserve(v.size());
    for (const Vec3d& p : v) {
        m.positions.push_back(c + Vec3(p) * r);
        m.normals.push_back(Vec3(p));
    }
    m.indices = std::move(tri);
    orient_outward(m, c);
    SceneEditor(scene).add_mesh(std::move(m));
}

void add_grid_cube_mesh(Scene& scene, const Vec3& lo, const Vec3& hi, int n) {
    ensure_material(scene);
    n = std::max(n, 1);
    Mesh m;
    m.name = "grid_cube";
    const std::size_t nv = 6 * static_cast<std::size_t>(n + 1) * (n + 1);
    m.positions.reserve(nv);
    std::unordered_map<std::uint64_t, std::uint32_t> weld;
    const std::uint64_t side = static_cast<std::uint64_t>(n) + 1;
    auto vertex = [&](int i, int j, int k) {
        const std::uint64_t key = (static_cast<std::uint64_t>(i) * side + j) * side + k;
        auto it = weld.find(key);
        if (it != weld.end()) return it->second;
        const Vec3 f(float(i) / n, float(j) / n, float(k) / n);
        const Vec3 p = lo + (hi - lo) * f;
        const auto idx = static_cast<std::uint32_t>(m.positions.size());
        m.positions.push_back(p);
        m.normals.push_back(normalize(p - (lo + hi) * 0.5f));
        weld.emplace(key, idx);
        return idx;
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int face = 0; face < 2; ++face)
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    auto at = [&](int s, int t) {
                        int c[3];
                        c[axis] = face * n;
                        c[(axis + 1) % 3] = s;
                        c[(axis + 2) % 3] = t;
                        return vertex(c[0], c[1], c[2]);
                    };
                    const std::uint32_t v00 = at(a, b), v10 = at(a + 1, b), v01 = at(a, b + 1),
                                        v11 = at(a + 1, b + 1);
                    m.indices.insert(m.indices.end(), {v00, v10, v11, v00, v11, v01});
                }
    orient_outward(m, (lo + hi) * 0.5f);
    SceneEditor(scene).add_mesh(std::move(m));
}

void add_triangle_soup(Scene& scene, std::size_t count, std::uint64_t seed) {
    ensure_material(scene);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> U(-1.f, 1.f);
    // Triangles about as large as the mean spacing of their centres, so a ray meets a few.
    const float size = 1.5f / std::cbrt(static_cast<float>(std::max<std::size_t>(count, 1)));
    Mesh m;
    m.name = "soup";
    m.positions.reserve(3 * count);
    for (std::size_t i = 0; i < count; ++i) {
        const Vec3 c(U(rng), U(rng), U(rng));
        Vec3 p[3];
        for (Vec3& q : p)
            q = c + Vec3(U(rng), U(rng), U(rng)) * size;
        Vec3 n = cross(p[1] - p[0], p[2] - p[0]);
        const float l = length(n);
        n = l > 0.f ? n / l : Vec3(0.f, 0.f, 1.f);
        for (const Vec3& q : p) {
            m.indices.push_back(static_cast<std::uint32_t>(m.positions.size()));
            m.positions.push_back(q);
            m.normals.push_back(n);
        }
    }
    SceneEditor(scene).add_mesh(std::move(m));
}

std::uint32_t add_rect_light(Scene& scene, const Vec3& center, const Vec3& dx, const Vec3& dy,
                             const Rgb& L) {
    return SceneEditor(scene).add_rect_light(
        rect_light(center, normalize(cross(dx, dy)), dx, dy, L), "rect-light");
}

void add_floor(Scene& scene, float half, float height, std::uint32_t mat) {
    Mesh m;
    m.name = "floor";
    m.positions = {Vec3(-half, height, -half), Vec3(-half, height, half), Vec3(half, height, half),
                   Vec3(half, height, -half)};
    m.normals.assign(4, Vec3(0.f, 1.f, 0.f));
    m.indices = {0, 1, 2, 0, 2, 3};
    m.material = mat;
    SceneEditor(scene).add_mesh(std::move(m));
}

Scene make_furnace_scene(float albedo, float Le) {
    Scene scene;
    scene.source = "furnace";
    SceneEditor editor(scene);
    Material m;
    m.kind = BsdfKind::Diffuse;
    m.name = "furnace";
    m.albedo = Rgb(albedo);
    m.radiance = Rgb(Le);
    Sphere sphere;
    sphere.center = Vec3(0.f);
    sphere.radius = 1.f;
    sphere.material = editor.add_material(m);
    editor.add_sphere(sphere);
    scene.camera.pos = Vec3(0.1f, -0.2f, 0.3f);
    scene.camera.hfov_deg = 90.f;
    scene.camera.znear = 0.f;
    editor.finalize();
    return scene;
}

Scene make_sunlit_room_scene(float ground_width, bool sun) {
    Scene scene;
    scene.source = "sunlit-room";
    SceneEditor editor(scene);
    // Six flat walls without vertex normals, so that the light a wall point receives has the
    // closed form the light-selection test integrates (I cos / d^2).
    ensure_material(scene);
    Mesh room;
    room.name = "room";
    for (int k = 0; k < 8; ++k)
        room.positions.push_back(Vec3(k & 1 ? 2.f : -2.f, k & 2 ? 3.f : 0.f, k & 4 ? 2.f : -2.f));
    // Two triangles per face; corners by bit (x = 1, y = 2, z = 4).
    room.indices = {0, 1, 3, 0, 3, 2, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                    2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 3, 7, 1, 7, 5};
    orient_outward(room, Vec3(0.f, 1.5f, 0.f));
    editor.add_mesh(std::move(room));
    Light lamp;
    lamp.kind = LightKind::Point;
    lamp.p = Vec3(0.3f, 2.6f, -0.4f);
    lamp.L = Rgb(10.f);
    editor.add_light(lamp);
    if (sun) {
        // Just under the room's floor, so that it closes no gap a ray could pass through.
        add_floor(scene, 0.5f * ground_width, -1e-3f, 0);
        Light s;
        s.kind = LightKind::Directional;
        s.n = normalize(Vec3(0.3f, 1.f, 0.2f)); // toward the sun
        s.L = Rgb(1.f);
        editor.add_light(s);
    }
    look_down_z(scene.camera, Vec3(0.f, 1.5f, 1.9f), 1.5f, 70.f, 1e6f);
    editor.finalize();
    return scene;
}

Scene make_procedural_scene(const std::string& full_spec) {
    // "box:" puts the content in a lit open box (a path tracer's ray mix: bounces off walls).
    const bool boxed = full_spec.rfind("box:", 0) == 0;
    const std::string spec = boxed ? full_spec.substr(4) : full_spec;
    const auto colon = spec.find(':');
    if (colon == std::string::npos)
        throw Error(ErrorKind::Usage, "procedural scene '" + spec + "': expected <kind>:<count>");
    const std::string kind = spec.substr(0, colon);
    std::string rest = spec.substr(colon + 1);
    std::uint64_t seed = 1;
    const auto colon2 = rest.find(':');
    double count = 0.0;
    try {
        if (colon2 != std::string::npos) {
            seed = std::stoull(rest.substr(colon2 + 1));
            rest = rest.substr(0, colon2);
        }
        std::size_t used = 0;
        count = std::stod(rest, &used);
        if (used != rest.size()) throw std::invalid_argument("trailing characters");
    } catch (const std::exception&) {
        throw Error(ErrorKind::Usage, "procedural scene '" + spec + "': bad count or seed");
    }
    if (!(count >= 1.0 && count <= 1e9))
        throw Error(ErrorKind::Usage, "procedural scene '" + spec + "': count out of range");
    if (kind == "nearwall" || kind == "inpanel") {
        if (boxed) throw Error(ErrorKind::Usage, "procedural scene '" + full_spec + "': no box");
        Scene many = kind == "nearwall" ? make_near_wall_scene(std::size_t(count), seed)
                                        : make_panel_lights_scene(std::size_t(count), seed);
        many.source = "procedural:" + full_spec;
        return many;
    }
    Scene scene;
    scene.source = "procedural:" + full_spec;
    SceneEditor editor(scene);
    float cam_dist = 3.5f;
    if (kind == "sphere") {
        add_uv_sphere_mesh(scene, Vec3(0.f), 1.f,
                           static_cast<int>(std::lround(std::sqrt(count / 4.0))));
    } else if (kind == "cube") {
        add_grid_cube_mesh(scene, Vec3(-1.f), Vec3(1.f),
                           static_cast<int>(std::lround(std::sqrt(count / 12.0))));
        cam_dist = 4.5f;
    } else if (kind == "soup") {
        add_triangle_soup(scene, static_cast<std::size_t>(count), seed);
        cam_dist = 4.5f;
    } else if (kind == "spheres") {
        ensure_material(scene);
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<float> U(-1.f, 1.f);
        const float r = 0.5f / static_cast<float>(std::cbrt(count));
        for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
            Sphere s;
            s.center = Vec3(U(rng), U(rng), U(rng));
            s.radius = r * (0.5f + 0.5f * std::abs(U(rng)));
            editor.add_sphere(s);
        }
        cam_dist = 4.5f;
    } else {
        throw Error(ErrorKind::Usage,
                    "procedural scene '" + spec +
                        "': unknown kind (sphere, cube, soup, spheres, nearwall, inpanel)");
    }
    if (boxed) {
        add_open_box(scene, kBoxHalfSize);
        // A square ceiling light facing down (cross(x, z) = -y), a quarter of the box's width.
        add_rect_light(scene, Vec3(0.f, kBoxHalfSize * 0.999f, 0.f),
                       Vec3(kBoxHalfSize * 0.5f, 0.f, 0.f), Vec3(0.f, 0.f, kBoxHalfSize * 0.5f),
                       Rgb(kBoxLightRadiance));
        // Far enough out that the 50-degree view spans the box's opening.
        cam_dist = kBoxHalfSize * 3.2f;
    }
    look_down_z(scene.camera, Vec3(0.f, 0.f, cam_dist), 0.f, 50.f, 100.f);
    if (!boxed) {
        Light light;
        light.kind = LightKind::Point;
        light.p = Vec3(2.f, 3.f, 4.f);
        light.L = Rgb(10.f);
        editor.add_light(light);
    }
    editor.finalize();
    return scene;
}

} // namespace candela
