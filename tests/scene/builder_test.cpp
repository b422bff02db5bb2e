// Scene builder: candela's own scenes and the CS184 scenes (counts, lights, spheres, framed
// camera), world-space meshes (normal splitting, mirroring), lights, the luminaire rule and the
// default Cornell box. The CS184 tests skip in a clone without ../shared (support/cs184.h); the
// own-scene tests beside them check the same features on scenes/.
#include "../support/cs184.h"
#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <array>
#include <map>
#include <string>

using namespace candela;

namespace {

/// Scene values are float (positions rounded from the files' 7-digit decimals, then transformed);
/// 1e-4 absolute is far below any feature size in these unit-scale scenes.
constexpr float kPosTol = 1e-4f;

std::string shared(const std::string& name) {
    return test::cs184_scene(name);
}

std::string own(const std::string& name) {
    return test::project_scene(name);
}

Scene load(const std::string& path, Diagnostics& diag, CameraMode mode = CameraMode::Framed) {
    BuildOptions opt;
    opt.camera_mode = mode;
    return load_scene(path, opt, diag);
}

/// The spare Vec3 Embree reads after the last vertex is part of the positions' storage (its size,
/// not only its capacity), so a copy of the mesh keeps it too.
bool has_embree_padding(const Mesh& m) {
    const Mesh copy = m;
    return m.positions.padded_size() == m.positions.size() + 1 &&
           copy.positions.padded_size() == copy.positions.size() + 1 &&
           copy.positions.data()[copy.positions.size()] == Vec3(0.f);
}

void check_vec(const Vec3& a, const Vec3& b, float tol = kPosTol) {
    CHECK(a.x == Approx(b.x).margin(tol));
    CHECK(a.y == Approx(b.y).margin(tol));
    CHECK(a.z == Approx(b.z).margin(tol));
}

/// Materials in use by BSDF kind, as `info` reports them.
std::map<BsdfKind, int> materials_by_kind(const Scene& s) {
    std::map<BsdfKind, int> n;
    std::vector<bool> used(s.materials.size(), false);
    for (const auto& m : s.meshes)
        used.at(m.material) = true;
    for (const auto& sp : s.spheres)
        used.at(sp.material) = true;
    for (std::size_t i = 0; i < used.size(); ++i)
        if (used[i]) ++n[s.materials[i].kind];
    return n;
}
std::map<LightKind, int> lights_by_kind(const Scene& s) {
    std::map<LightKind, int> n;
    for (const auto& l : s.lights)
        ++n[l.kind];
    return n;
}

Vec3 geometric_normal(const Mesh& m, std::size_t tri) {
    const Vec3& p0 = m.positions[m.indices[3 * tri]];
    return normalize(
        cross(m.positions[m.indices[3 * tri + 1]] - p0, m.positions[m.indices[3 * tri + 2]] - p0));
}

struct Expect {
    const char* file;
    std::size_t triangles;
    std::size_t spheres;
    std::map<LightKind, int> lights;
    std::map<BsdfKind, int> bsdfs;
};

} // namespace

TEST_CASE("builder: every shared CS184 scene loads with the expected counts", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    using B = BsdfKind;
    using L = LightKind;
    // Triangles: spec §10 "tris" for every file. In Cornell boxes with a CGL <area> light the
    // 2-triangle emissive stand-in is dropped (§11.3) and the builder adds the 2-triangle
    // rectangle of the area light, so the count equals the §10 number. CBempty has no <area>
    // light: its panel stays and is a mesh light. Materials are those in use: the CB box is
    // 5 diffuse walls + 1 emission (the rectangle's, or CBempty's panel).
    const std::array<Expect, 11> table{{
        {"plane.dae", 2, 0, {{L::Point, 1}}, {{B::Diffuse, 1}}},
        {"cube.dae", 12, 0, {{L::Point, 1}}, {{B::Diffuse, 1}}},
        {"cow.dae", 5856, 0, {{L::Directional, 1}}, {{B::Diffuse, 1}}},
        {"teapot.dae", 2464, 0, {{L::Directional, 1}}, {{B::Diffuse, 1}}},
        {"bunny.dae", 33696, 0, {{L::Ambient, 1}}, {{B::Diffuse, 2}}},
        {"banana.dae", 2458, 0, {{L::Ambient, 1}, {L::Directional, 1}}, {{B::Diffuse, 3}}},
        {"CBempty.dae", 12, 0, {{L::Point, 1}, {L::Mesh, 1}}, {{B::Diffuse, 5}, {B::Emission, 1}}},
        {"CBgems.dae", 252, 0, {{L::Area, 1}}, {{B::Diffuse, 5}, {B::Emission, 1}, {B::Glass, 3}}},
        {"CBspheres.dae",
         12,
         2,
         {{L::Area, 1}},
         {{B::Diffuse, 5}, {B::Emission, 1}, {B::Glass, 1}, {B::Mirror, 1}}},
        {"CBspheres_lambertian.dae", 12, 2, {{L::Area, 1}}, {{B::Diffuse, 7}, {B::Emission, 1}}},
        // This CBbunny is the course's own copy: a diffuse 0.5 bunny (cs184 README).
        {"CBbunny.dae", 28588, 0, {{L::Area, 1}}, {{B::Diffuse, 6}, {B::Emission, 1}}},
    }};
    for (const Expect& e : table) {
        INFO(e.file);
        Diagnostics diag;
        Scene s = load(shared(e.file), diag);
        CHECK(s.triangle_count() == e.triangles);
        CHECK(s.spheres.size() == e.spheres);
        CHECK(lights_by_kind(s) == e.lights);
        CHECK(materials_by_kind(s) == e.bsdfs);
        for (const Mesh& m : s.meshes) {
            CHECK(m.normals.size() == m.positions.size());
            CHECK(has_embree_padding(m));
        }
    }
}

TEST_CASE("builder: Cornell box area light, stand-in and rectangle mesh", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    for (const char* f : {"CBspheres.dae", "CBspheres_lambertian.dae", "CBbunny.dae"}) {
        INFO(f);
        Diagnostics diag;
        Scene s = load(shared(f), diag);
        REQUIRE(s.lights.size() == 1);
        const Light& l = s.lights[0];
        REQUIRE(l.kind == LightKind::Area);
        // Spec §2.1 table: p = (0, 1.49, 0), n = (0, -1, 0), area 0.48, L = 10.
        check_vec(l.p, Vec3(0.f, 1.49f, 0.f));
        check_vec(l.n, Vec3(0.f, -1.f, 0.f));
        CHECK(l.area == Approx(0.48f).epsilon(1e-5));
        CHECK(l.L == Rgb(10.f));
        CHECK(std::abs(l.dx.x) == Approx(0.6f));
        CHECK(std::abs(l.dy.z) == Approx(0.8f));
        // The rectangle is a hittable emissive mesh facing n; no other emissive mesh remains.
        REQUIRE(l.geom_id < s.meshes.size());
        const Mesh& m = s.meshes[l.geom_id];
        CHECK(m.light == 0);
        CHECK(m.triangle_count() == 2);
        CHECK(s.materials[m.material].kind == BsdfKind::Emission);
        CHECK(s.materials[m.material].radiance == Rgb(10.f));
        for (std::size_t t = 0; t < 2; ++t)
            check_vec(geometric_normal(m, t), l.n);
        int emissive = 0;
        for (const Mesh& mm : s.meshes)
            emissive += s.materials[mm.material].is_emissive();
        CHECK(emissive == 1);
    }
}

TEST_CASE("builder: CBempty keeps its panel as a mesh light", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Diagnostics diag;
    Scene s = load(shared("CBempty.dae"), diag);
    const Light* mesh_light = nullptr;
    const Light* point = nullptr;
    for (const Light& l : s.lights) {
        if (l.kind == LightKind::Mesh) mesh_light = &l;
        if (l.kind == LightKind::Point) point = &l;
    }
    REQUIRE(mesh_light);
    REQUIRE(point);
    CHECK(mesh_light->area == Approx(0.48f).epsilon(1e-5));
    REQUIRE(mesh_light->tri_choice.size() == 2);
    REQUIRE(mesh_light->tri_area_per_pmf.size() == 2);
    CHECK(s.meshes.at(mesh_light->geom_id).light >= 0);
    CHECK(point->L == Rgb(5.f));
    check_vec(point->p, Vec3(0.f, 1.49f, 0.0043159f));
}

TEST_CASE("builder: CBspheres_lambertian spheres in world Y-up", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Diagnostics diag;
    Scene s = load(shared("CBspheres_lambertian.dae"), diag);
    REQUIRE(s.spheres.size() == 2);
    // File (Z-up) centres (-0.4, 0.3, 0.3) and (0.4, -0.3, 0.3) map by (x,y,z) -> (-x, z, y).
    check_vec(s.spheres[0].center, Vec3(0.4f, 0.3f, 0.3f));
    check_vec(s.spheres[1].center, Vec3(-0.4f, 0.3f, -0.3f));
    for (const Sphere& sp : s.spheres) {
        CHECK(sp.radius == Approx(0.3f));
        CHECK(s.materials[sp.material].kind == BsdfKind::Diffuse);
        CHECK(s.materials[sp.material].albedo.x == Approx(0.8f));
    }
}

TEST_CASE("builder: framed camera of the Cornell boxes and the bunny", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    const float D = 4.8023f; // 1.5·sqrt(10.25), spec §3.1
    struct Cam {
        const char* file;
        Vec3 pos;
        Vec3 z;
    };
    for (const Cam& c : {Cam{"CBspheres.dae", Vec3(0, 0.75f, D), Vec3(0, 0, 1)},
                         Cam{"CBspheres_lambertian.dae", Vec3(0, 0.75f, D), Vec3(0, 0, 1)},
                         Cam{"CBempty.dae", Vec3(0, 0.75f, D), Vec3(0, 0, 1)},
                         Cam{"CBgems.dae", Vec3(0, 0.75f, D), Vec3(0, 0, 1)},
                         Cam{"CBbunny.dae", Vec3(0, 0.75f, -D), Vec3(0, 0, -1)}}) {
        INFO(c.file);
        Diagnostics diag;
        Scene s = load(shared(c.file), diag);
        check_vec(s.camera.pos, c.pos);
        check_vec(s.camera.z, c.z); // looks along -z
        check_vec(s.camera.y, Vec3(0, 1, 0));
        check_vec(s.camera.target, Vec3(0, 0.75f, 0));
        CHECK(s.camera.hfov_deg == Approx(49.13434f));
        CHECK(s.camera.znear == Approx(0.1f));
        CHECK(s.camera.zfar == Approx(100.f));
    }
    // bunny: target (0, 0.3824, 0), D = 3.4953, c_dir = (0, 0.3162, 0.9487) (spec §3.1).
    Diagnostics diag;
    Scene b = load(shared("bunny.dae"), diag);
    check_vec(b.camera.target, Vec3(0, 0.3824f, 0), 1e-3f);
    Vec3 off = b.camera.pos - b.camera.target;
    CHECK(length(off) == Approx(3.4953f).epsilon(1e-4));
    check_vec(normalize(off), Vec3(0, 0.3162f, 0.9487f), 1e-3f);
    check_vec(b.camera.z, normalize(off));
}

TEST_CASE("builder: file camera mode uses the node pose", "[builder][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Diagnostics diag;
    Scene s = load(shared("CBspheres.dae"), diag, CameraMode::File);
    check_vec(s.camera.pos, Vec3(0, 0, 3)); // file (0,3,0) in Z-up
    check_vec(s.camera.z, Vec3(0, 0, 1));
    check_vec(s.camera.y, Vec3(0, 1, 0));
    check_vec(s.camera.x, Vec3(1, 0, 0));
}

namespace {

const char* kQuadMesh =
    "<library_geometries><geometry id=\"q\" name=\"q\"><mesh>"
    "<source id=\"p\"><float_array id=\"pa\" count=\"12\">0 0 0 1 0 0 1 1 0 0 1 0</float_array>"
    "</source><source id=\"n\"><float_array id=\"na\" count=\"6\">0 0 1 0 0.6 0.8</float_array>"
    "</source><vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>"
    "<triangles count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>"
    "<input semantic=\"NORMAL\" source=\"#n\" offset=\"1\"/><p>NORMALS</p></triangles>"
    "</mesh></geometry></library_geometries>";

std::string quad_scene(const std::string& p, const std::string& transform) {
    std::string mesh = kQuadMesh;
    mesh.replace(mesh.find("NORMALS"), 7, p);
    return "<?xml version=\"1.0\"?><COLLADA><asset><up_axis>Y_UP</up_axis></asset>" + mesh +
           "<library_visual_scenes><visual_scene id=\"vs\"><node id=\"quad-node\" name=\"quad\">" +
           transform +
           "<instance_geometry url=\"#q\"/></node></visual_scene></library_visual_scenes>"
           "<scene><instance_visual_scene url=\"#vs\"/></scene></COLLADA>";
}

Scene build_text(const std::string& text, Diagnostics& diag) {
    return build_scene(parse_collada(text, "inline.dae", diag), BuildOptions{}, diag);
}

} // namespace

TEST_CASE("builder: per-corner normals split vertices by (position, normal)", "[builder][quick]") {
    Diagnostics diag;
    // Same normal everywhere: 4 shared vertices.
    Scene a = build_text(quad_scene("0 0 1 0 2 0  0 0 2 0 3 0", ""), diag);
    REQUIRE(a.meshes.size() == 1);
    CHECK(a.meshes[0].positions.size() == 4);
    // Each triangle its own normal: the diagonal's two positions are split, 6 vertices.
    Scene b = build_text(quad_scene("0 0 1 0 2 0  0 1 2 1 3 1", ""), diag);
    REQUIRE(b.meshes[0].positions.size() == 6);
    const Mesh& m = b.meshes[0];
    check_vec(m.normals[m.indices[0]], Vec3(0, 0, 1));
    check_vec(m.normals[m.indices[3]], Vec3(0, 0.6f, 0.8f));
    // Normals go through the inverse transpose: scale y by 2 -> (0, 0.3, 0.8) normalised.
    Scene c = build_text(quad_scene("0 1 1 1 2 1  0 1 2 1 3 1", "<scale>1 2 1</scale>"), diag);
    check_vec(c.meshes[0].normals[0], normalize(Vec3(0, 0.3f, 0.8f)));
    CHECK(diag.warning_count() == 0);
}

TEST_CASE("builder: mirroring transforms keep the geometric normal consistent",
          "[builder][quick]") {
    Diagnostics diag;
    Scene plain = build_text(quad_scene("0 0 1 0 2 0  0 0 2 0 3 0", ""), diag);
    check_vec(geometric_normal(plain.meshes[0], 0), Vec3(0, 0, 1));
    // Mirror in z: the transformed local normal (0,0,1) is (0,0,-1); the winding follows.
    Scene mir = build_text(quad_scene("0 0 1 0 2 0  0 0 2 0 3 0", "<scale>1 1 -1</scale>"), diag);
    const Mesh& m = mir.meshes[0];
    check_vec(geometric_normal(m, 0), Vec3(0, 0, -1));
    check_vec(geometric_normal(m, 1), Vec3(0, 0, -1));
    check_vec(m.normals[0], Vec3(0, 0, -1));
    // Mirror in x (normal unchanged in direction): geometric normal stays +z.
    Scene mx = build_text(quad_scene("0 0 1 0 2 0  0 0 2 0 3 0", "<scale>-1 1 1</scale>"), diag);
    check_vec(geometric_normal(mx.meshes[0], 0), Vec3(0, 0, 1));
}

TEST_CASE("builder: point, spot and directional lights in world space", "[builder][quick]") {
    const std::string text =
        "<?xml version=\"1.0\"?><COLLADA><asset><up_axis>Y_UP</up_axis></asset>"
        "<library_lights>"
        "<light id=\"d\" name=\"d\"><technique_common><directional><color>1 1 1</color>"
        "</directional></technique_common></light>"
        "<light id=\"s\" name=\"s\"><technique_common><spot><color>3 3 3</color>"
        "<falloff_angle>90</falloff_angle><falloff_exponent>2</falloff_exponent>"
        "<quadratic_attenuation>0.1</quadratic_attenuation></spot></technique_common></light>"
        "</library_lights>"
        "<library_visual_scenes><visual_scene id=\"vs\">"
        "<node id=\"a\"><translate>5 5 5</translate><rotate>1 0 0 -90</rotate>"
        "<instance_light url=\"#d\"/></node>"
        "<node id=\"b\"><translate>0 4 0</translate><rotate>1 0 0 -90</rotate>"
        "<instance_light url=\"#s\"/></node>"
        "</visual_scene></library_visual_scenes>"
        "<scene><instance_visual_scene url=\"#vs\"/></scene></COLLADA>";
    Diagnostics diag;
    Scene s = build_text(text, diag);
    REQUIRE(s.lights.size() == 2);
    // Rotating -90° about x turns local -Z into world -Y: the sun shines down, so the
    // direction toward it is +Y, whatever the translation.
    CHECK(s.lights[0].kind == LightKind::Directional);
    check_vec(s.lights[0].n, Vec3(0, 1, 0));
    CHECK(s.lights[1].kind == LightKind::Spot);
    check_vec(s.lights[1].p, Vec3(0, 4, 0));
    check_vec(s.lights[1].n, Vec3(0, -1, 0));
    CHECK(s.lights[1].cos_total == Approx(std::cos(deg_to_rad(45.0))));
    CHECK(s.lights[1].falloff_exp == 2.f);
    CHECK(s.lights[1].L == Rgb(3.f));
}

TEST_CASE("builder: environment option appends an environment light", "[builder][quick]") {
    Diagnostics diag;
    const Scene plain = load_scene(own("cornell-box.dae"), BuildOptions{}, diag);
    BuildOptions opt;
    opt.env_map = std::make_shared<const EnvMap>(2, 1, std::vector<Rgb>{Rgb(1.f), Rgb(2.f)});
    const Scene lit = load_scene(own("cornell-box.dae"), opt, diag);
    REQUIRE(lit.lights.size() == plain.lights.size() + 1);
    CHECK(lit.lights.back().kind == LightKind::Environment);
    CHECK(lit.env == opt.env_map);
    CHECK(plain.env == nullptr);
    // A map that does not exist fails when it is read, never silently.
    CHECK_THROWS_AS(load_envmap("no-such-map.exr"), Error);
}

TEST_CASE("builder: default Cornell box scene", "[builder][quick]") {
    Diagnostics diag;
    Scene s = load(std::string(CANDELA_PROJECT_SCENES) + "/cornell-box.dae", diag);
    CHECK(diag.warning_count() == 0);
    // 5 walls x 2 + tall box 5 quads (10) + area light rectangle 2.
    CHECK(s.triangle_count() == 22);
    CHECK(s.meshes.size() == 7);
    CHECK(s.spheres.size() == 1);
    CHECK(lights_by_kind(s) == std::map<LightKind, int>{{LightKind::Area, 1}});
    CHECK(materials_by_kind(s) == std::map<BsdfKind, int>{{BsdfKind::Diffuse, 4},
                                                          {BsdfKind::Emission, 1},
                                                          {BsdfKind::Glass, 1}});
    const Light& l = s.lights[0];
    check_vec(l.n, Vec3(0, -1, 0));
    CHECK(l.area == Approx(0.25f));
    check_vec(s.camera.z, Vec3(0, 0, 1));
    CHECK(s.camera.hfov_deg == Approx(40.f));
}

// --- The same features on candela's own scenes (always present) -----------------------------

TEST_CASE("builder: every own scene loads with the expected counts", "[builder][quick]") {
    using B = BsdfKind;
    using L = LightKind;
    // Counts from each file's header comment: quads fan-triangulated, the <area> rectangle
    // added as 2 triangles, a coplanar emissive stand-in dropped (cornell-spheres).
    const std::array<Expect, 6> table{{
        {"cornell-box.dae",
         22,
         1,
         {{L::Area, 1}},
         {{B::Diffuse, 4}, {B::Emission, 1}, {B::Glass, 1}}},
        {"cornell-spheres.dae", 1292, 2, {{L::Area, 1}}, {{B::Diffuse, 6}, {B::Emission, 1}}},
        {"glass.dae", 18, 1, {{L::Area, 1}}, {{B::Diffuse, 2}, {B::Emission, 1}, {B::Glass, 2}}},
        {"glossy.dae",
         6,
         4,
         {{L::Area, 1}},
         {{B::Diffuse, 1}, {B::Emission, 1}, {B::Microfacet, 4}}},
        {"lights.dae",
         348,
         1,
         {{L::Mesh, 1}, {L::Point, 1}, {L::Spot, 1}, {L::Directional, 1}, {L::Ambient, 1}},
         {{B::Diffuse, 5}, {B::Emission, 1}}},
        {"materials.dae",
         346,
         4,
         {{L::Area, 1}, {L::Sphere, 1}},
         {{B::Diffuse, 4},
          {B::Emission, 2},
          {B::Mirror, 1},
          {B::Glass, 1},
          {B::Refraction, 1},
          {B::Microfacet, 1}}},
    }};
    for (const Expect& e : table) {
        INFO(e.file);
        Diagnostics diag;
        Scene s = load(own(e.file), diag);
        CHECK(diag.warning_count() == 0);
        CHECK(s.triangle_count() == e.triangles);
        CHECK(s.spheres.size() == e.spheres);
        CHECK(lights_by_kind(s) == e.lights);
        CHECK(materials_by_kind(s) == e.bsdfs);
        for (const Mesh& m : s.meshes) {
            CHECK(m.normals.size() == m.positions.size());
            CHECK(has_embree_padding(m));
        }
    }
}

TEST_CASE("builder: own Cornell box area light, stand-in and rectangle mesh", "[builder][quick]") {
    Diagnostics diag;
    Scene s = load(own("cornell-spheres.dae"), diag);
    REQUIRE(s.lights.size() == 1);
    const Light& l = s.lights[0];
    REQUIRE(l.kind == LightKind::Area);
    // File (Z-up) centre (0, 0.1, 1.59), 0.6 x 0.5, emitting down; world = (-x, z, y).
    check_vec(l.p, Vec3(0.f, 1.59f, 0.1f));
    check_vec(l.n, Vec3(0.f, -1.f, 0.f));
    CHECK(l.area == Approx(0.3f).epsilon(1e-5));
    CHECK(l.L == Rgb(15.f));
    CHECK(std::abs(l.dx.x) == Approx(0.6f));
    CHECK(std::abs(l.dy.z) == Approx(0.5f));
    // The stand-in panel is gone; the rectangle is the one hittable emissive mesh, facing n.
    REQUIRE(l.geom_id < s.meshes.size());
    const Mesh& m = s.meshes[l.geom_id];
    CHECK(m.light == 0);
    CHECK(m.triangle_count() == 2);
    CHECK(s.materials[m.material].kind == BsdfKind::Emission);
    CHECK(s.materials[m.material].radiance == Rgb(15.f));
    for (std::size_t t = 0; t < 2; ++t)
        check_vec(geometric_normal(m, t), l.n);
    int emissive = 0;
    for (const Mesh& mm : s.meshes)
        emissive += s.materials[mm.material].is_emissive();
    CHECK(emissive == 1);
}

TEST_CASE("builder: an emissive mesh without an area light is a mesh light", "[builder][quick]") {
    Diagnostics diag;
    Scene s = load(own("lights.dae"), diag);
    const Light* mesh_light = nullptr;
    const Light* point = nullptr;
    for (const Light& l : s.lights) {
        if (l.kind == LightKind::Mesh) mesh_light = &l;
        if (l.kind == LightKind::Point) point = &l;
    }
    REQUIRE(mesh_light);
    REQUIRE(point);
    CHECK(mesh_light->area > 0.f);
    REQUIRE(mesh_light->tri_choice.size() == 2); // the two-sided quad: two triangles
    // Each triangle's area per probability is the whole area when the choice follows area.
    CHECK(mesh_light->tri_area_per_pmf[0] == Approx(mesh_light->area).epsilon(1e-5));
    CHECK(s.meshes.at(mesh_light->geom_id).light >= 0);
    CHECK(point->L.x > 0.f);
}

TEST_CASE("builder: own Z-up spheres in world Y-up", "[builder][quick]") {
    Diagnostics diag;
    Scene s = load(own("cornell-spheres.dae"), diag);
    REQUIRE(s.spheres.size() == 2);
    // File centres (0.45, 0.25, 0.3) and (-0.4, -0.3, 0.3) map by (x,y,z) -> (-x, z, y).
    check_vec(s.spheres[0].center, Vec3(-0.45f, 0.3f, 0.25f));
    check_vec(s.spheres[1].center, Vec3(0.4f, 0.3f, -0.3f));
    CHECK(s.materials[s.spheres[0].material].albedo.x == Approx(0.8f));
    CHECK(s.materials[s.spheres[1].material].albedo.x == Approx(0.6f));
    for (const Sphere& sp : s.spheres) {
        CHECK(sp.radius == Approx(0.3f));
        CHECK(s.materials[sp.material].kind == BsdfKind::Diffuse);
    }
}

TEST_CASE("builder: framed camera of the own scenes", "[builder][quick]") {
    // Spec 3.1: the camera orbits the centre of the bounds at 1.5 x their diagonal, from the
    // direction of the point one unit in front of the file camera; it looks at the centre. The
    // bounds are the file's meshes and spheres; in these scenes the area light lies inside
    // them, so they equal the scene's bounds (in glass and glossy the light hangs above).
    for (const char* f :
         {"cornell-box.dae", "cornell-spheres.dae", "lights.dae", "materials.dae"}) {
        INFO(f);
        Diagnostics diag;
        Scene s = load(own(f), diag);
        check_vec(s.camera.target, s.bounds.center());
        const Vec3 off = s.camera.pos - s.camera.target;
        CHECK(length(off) == Approx(1.5f * length(s.bounds.extent())).epsilon(1e-5));
        check_vec(s.camera.z, normalize(off)); // looks along -z
    }
    // cornell-spheres' file camera looks along world +z, so the framed one sits at -z (as for
    // CBbunny); cornell-box's sits on the +z axis.
    Diagnostics diag;
    CHECK(load(own("cornell-spheres.dae"), diag).camera.pos.z < 0.f);
    Scene box = load(own("cornell-box.dae"), diag);
    check_vec(box.camera.z, Vec3(0, 0, 1));
    check_vec(box.camera.y, Vec3(0, 1, 0));
}

TEST_CASE("builder: file camera mode uses the node pose of an own scene", "[builder][quick]") {
    Diagnostics diag;
    Scene s = load(own("cornell-spheres.dae"), diag, CameraMode::File);
    check_vec(s.camera.pos, Vec3(0, 0.8f, -4.5f)); // file (0, -4.5, 0.8) in Z-up
    check_vec(s.camera.z, Vec3(0, 0, -1));         // it looks along world +z
    check_vec(s.camera.y, Vec3(0, 1, 0));
    check_vec(s.camera.x, Vec3(-1, 0, 0));
}

namespace {

/// A scene with one CGL sphere of radius `r` under the node transform `transform`, with an
/// emission or diffuse material.
std::string sphere_scene(const std::string& transform, float r, bool emissive = false) {
    const std::string effect =
        emissive ? "<effect id=\"fx\"><profile_COMMON><technique sid=\"c\"><phong/></technique>"
                   "</profile_COMMON><extra><technique profile=\"CGL\"><emission><radiance>2 2 2"
                   "</radiance></emission></technique></extra></effect>"
                 : "<effect id=\"fx\"><profile_COMMON><technique sid=\"c\"><lambert><diffuse>"
                   "<color>0.5 0.5 0.5 1</color></diffuse></lambert></technique>"
                   "</profile_COMMON></effect>";
    return "<?xml version=\"1.0\"?><COLLADA><asset><up_axis>Y_UP</up_axis></asset>"
           "<library_effects>" +
           effect +
           "</library_effects><library_materials><material id=\"mat\"><instance_effect "
           "url=\"#fx\"/></material></library_materials>"
           "<library_geometries><geometry id=\"s\" name=\"s\"><extra><technique profile=\"CGL\">"
           "<sphere><radius>" +
           std::to_string(r) +
           "</radius></sphere></technique></extra></geometry></library_geometries>"
           "<library_visual_scenes><visual_scene id=\"vs\"><node id=\"n\" name=\"n\">" +
           transform +
           "<instance_geometry url=\"#s\"><bind_material><technique_common><instance_material "
           "symbol=\"m\" target=\"#mat\"/></technique_common></bind_material>"
           "</instance_geometry></node></visual_scene></library_visual_scenes>"
           "<scene><instance_visual_scene url=\"#vs\"/></scene></COLLADA>";
}

} // namespace

TEST_CASE("builder: a non-uniform scale makes a sphere an ellipsoid", "[builder][quick]") {
    Diagnostics diag;
    Scene s =
        build_text(sphere_scene("<translate>1 2 3</translate><scale>1 2 0.5</scale>", 0.5f), diag);
    REQUIRE(s.spheres.size() == 1);
    const Sphere& e = s.spheres[0];
    CHECK(e.is_ellipsoid());
    check_vec(e.center, Vec3(1, 2, 3));
    // Semi-axes 0.5 x (1, 2, 0.5): the bounds the scene and `candela info` report.
    check_vec(e.bounds().lo, Vec3(0.5f, 1.f, 2.75f));
    check_vec(e.bounds().hi, Vec3(1.5f, 3.f, 3.25f));
    check_vec(s.bounds.lo, Vec3(0.5f, 1.f, 2.75f));
    check_vec(s.bounds.hi, Vec3(1.5f, 3.f, 3.25f));
    // The maps are inverses of each other.
    const Mat3 id = e.to_object * e.to_world;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            CHECK(id.m[i][j] == Approx(i == j ? 1.f : 0.f).margin(1e-6f));
    CHECK(e.map_error == Approx(1.f)); // axis-aligned: no amplification
}

TEST_CASE("builder: similarity transforms keep the fast sphere", "[builder][quick]") {
    struct Case {
        const char* transform;
        float radius; ///< expected world radius for a geometry radius of 0.5
    };
    for (const Case& c :
         {Case{"<scale>3 3 3</scale>", 1.5f}, Case{"<scale>-2 2 2</scale>", 1.f},
          Case{"<rotate>1 1 0 37</rotate><scale>2 2 2</scale><rotate>0 0 1 -81</rotate>", 1.f},
          Case{"<matrix>0 -2 0 1  2 0 0 0  0 0 2 0  0 0 0 1</matrix>", 1.f}}) {
        INFO(c.transform);
        Diagnostics diag;
        Scene s = build_text(sphere_scene(c.transform, 0.5f), diag);
        REQUIRE(s.spheres.size() == 1);
        CHECK_FALSE(s.spheres[0].is_ellipsoid());
        CHECK(s.spheres[0].radius == Approx(c.radius).epsilon(1e-6));
    }
    // A rotation after a non-uniform scale is still an ellipsoid, with rotated bounds: the
    // half extent on axis i is |row i of the map|.
    Diagnostics diag;
    Scene s = build_text(sphere_scene("<rotate>0 0 1 90</rotate><scale>3 1 1</scale>", 1.f), diag);
    REQUIRE(s.spheres[0].is_ellipsoid());
    check_vec(s.bounds.lo, Vec3(-1.f, -3.f, -1.f));
    check_vec(s.bounds.hi, Vec3(1.f, 3.f, 1.f));
}

TEST_CASE("builder: an emissive ellipsoid is a sphere light with its true area",
          "[builder][quick]") {
    Diagnostics diag;
    // A prolate spheroid with semi-axes (1, 1, 2): area 2 pi (1 + 2 * 2 / e asin(e)) with
    // eccentricity e = sqrt(1 - 1/4).
    Scene s = build_text(sphere_scene("<scale>1 1 2</scale>", 1.f, true), diag);
    REQUIRE(s.spheres.size() == 1);
    REQUIRE(s.lights.size() == 1);
    const Light& l = s.lights[0];
    CHECK(l.kind == LightKind::Sphere);
    CHECK(l.geom_id == 0);
    CHECK(s.spheres[0].light == 0);
    const double e = std::sqrt(1.0 - 0.25);
    const double area = 2.0 * kPi * (1.0 + 2.0 / e * std::asin(e));
    CHECK(l.area == Approx(area).epsilon(1e-6));
    // An oblate one, semi-axes (2, 2, 1) with e = sqrt(1 - 1/4): 2 pi a^2 + pi c^2 / e
    // ln((1 + e) / (1 - e)).
    Scene o = build_text(sphere_scene("<scale>2 1 2</scale>", 1.f, true), diag);
    const double oblate = 2.0 * kPi * 4.0 + kPi / e * std::log((1.0 + e) / (1.0 - e));
    CHECK(o.lights.at(0).area == Approx(oblate).epsilon(1e-6));
}

TEST_CASE("builder: a singular sphere transform is refused with its line", "[builder][quick]") {
    Diagnostics diag;
    try {
        build_text(sphere_scene("<scale>1 0 1</scale>", 1.f), diag);
        FAIL("a flat sphere was accepted");
    } catch (const Error& err) {
        CHECK(err.kind() == ErrorKind::Scene);
        CHECK_THAT(err.what(), Catch::Contains("inline.dae:"));
        CHECK_THAT(err.what(), Catch::Contains("sphere of node 'n'"));
    }
}

namespace {

/// A one-triangle scene whose material is a CGL <glass> (or <refraction>) with `roughness`.
std::string rough_glass_scene(const std::string& tag, const std::string& roughness) {
    const std::string reflectance = tag == "glass" ? "<reflectance>1 1 1</reflectance>" : "";
    return "<?xml version=\"1.0\"?><COLLADA><asset><up_axis>Y_UP</up_axis></asset>"
           "<library_effects><effect id=\"fx\"><profile_COMMON><technique sid=\"c\"><phong/>"
           "</technique></profile_COMMON><extra><technique profile=\"CGL\"><" +
           tag + "><transmittance>1 1 1</transmittance>" + reflectance + "<roughness>" + roughness +
           "</roughness><ior>1.5</ior></" + tag +
           "></technique></extra></effect></library_effects>"
           "<library_materials><material id=\"mat\"><instance_effect url=\"#fx\"/></material>"
           "</library_materials><library_geometries><geometry id=\"s\" name=\"s\"><extra>"
           "<technique profile=\"CGL\"><sphere><radius>1</radius></sphere></technique></extra>"
           "</geometry></library_geometries><library_visual_scenes><visual_scene id=\"vs\">"
           "<node id=\"n\" name=\"n\"><instance_geometry url=\"#s\"><bind_material>"
           "<technique_common><instance_material symbol=\"m\" target=\"#mat\"/>"
           "</technique_common></bind_material></instance_geometry></node></visual_scene>"
           "</library_visual_scenes><scene><instance_visual_scene url=\"#vs\"/></scene>"
           "</COLLADA>";
}

} // namespace

TEST_CASE("builder: <roughness> makes glass and refraction rough", "[builder][quick]") {
    for (const std::string tag : {"glass", "refraction"}) {
        INFO(tag);
        Diagnostics diag;
        Scene rough = build_text(rough_glass_scene(tag, "0.3"), diag);
        const Material& m = rough.materials.at(rough.spheres.at(0).material);
        CHECK(m.roughness == 0.3f);
        CHECK(m.is_rough_dielectric());
        CHECK_FALSE(m.is_delta());
        CHECK(m.has_transmission());
        Scene smooth = build_text(rough_glass_scene(tag, "0"), diag);
        CHECK(smooth.materials.at(smooth.spheres.at(0).material).is_delta());
        CHECK_THROWS_AS(build_text(rough_glass_scene(tag, "-0.1"), diag), Error);
    }
}
