// SceneEditor and check_scene: emissive primitives get their light records, rect panels link
// both ways, finalize() refuses broken scenes with context; PaddedPositions keeps Embree's spare
// Vec3 through copies.
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <string>

using namespace candela;

namespace {

Material diffuse() {
    Material m;
    m.kind = BsdfKind::Diffuse;
    m.albedo = Rgb(0.5f);
    return m;
}

Material emitter(float Le) {
    Material m;
    m.kind = BsdfKind::Emission;
    m.radiance = Rgb(Le);
    return m;
}

/// The unit square [0,1]^2 at z = 0 as two triangles (areas 0.5 each).
Mesh square(std::uint32_t material) {
    Mesh m;
    m.name = "square";
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
    m.normals.assign(4, Vec3(0, 0, 1));
    m.indices = {0, 1, 2, 0, 2, 3};
    m.material = material;
    return m;
}

bool padded(const PaddedPositions& p) {
    return p.padded_size() == p.size() + 1 && p.data()[p.size()] == Vec3(0.f);
}

/// Runs check_scene and returns its message ("" when it passes).
std::string check_message(const Scene& s) {
    try {
        check_scene(s);
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Scene);
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("PaddedPositions: the spare Vec3 survives copies, assignment and growth",
          "[scene][editor][quick]") {
    PaddedPositions p;
    CHECK(p.empty());
    CHECK(padded(p));
    for (int i = 0; i < 100; ++i)
        p.push_back(Vec3(float(i), 1.f, 2.f));
    REQUIRE(p.size() == 100);
    CHECK(padded(p));
    CHECK(p.back() == Vec3(99.f, 1.f, 2.f));
    CHECK(p.end() - p.begin() == 100);

    Mesh m;
    m.positions = p;
    const Mesh copy = m; // a copy allocates exactly what the source's size asks for
    CHECK(copy.positions == m.positions);
    CHECK(padded(copy.positions));
    Mesh assigned;
    assigned = copy;
    CHECK(padded(assigned.positions));

    PaddedPositions q{Vec3(1.f), Vec3(2.f)};
    CHECK(q.size() == 2);
    CHECK(padded(q));
    q.resize(5);
    CHECK(q.size() == 5);
    CHECK(q[4] == Vec3(0.f));
    CHECK(padded(q));
    q.clear();
    CHECK(q.empty());
    CHECK(padded(q));
    const PaddedPositions from_vector(std::vector<Vec3>{Vec3(3.f)});
    CHECK(from_vector.size() == 1);
    CHECK(padded(from_vector));
}

TEST_CASE("SceneEditor: an emissive mesh gets its Mesh light, a diffuse one none",
          "[scene][editor][quick]") {
    Scene s;
    SceneEditor ed(s);
    const std::uint32_t dif = ed.add_material(diffuse());
    const std::uint32_t em = ed.add_material(emitter(2.f));
    CHECK(ed.add_mesh(square(dif)) == 0);
    CHECK(ed.add_mesh(square(em)) == 1);
    ed.finalize();
    CHECK(s.meshes[0].light == -1);
    REQUIRE(s.lights.size() == 1);
    REQUIRE(s.meshes[1].light == 0);
    const Light& l = s.lights[0];
    CHECK(l.kind == LightKind::Mesh);
    CHECK(l.geom_id == 1);
    CHECK(l.L == Rgb(2.f));
    CHECK(l.area == 1.f);
    // Two triangles of area 1/2: each chosen with probability 1/2, area per probability 1.
    REQUIRE(l.tri_choice.size() == 2);
    CHECK(l.tri_choice.pmf(0) == 0.5f);
    CHECK(l.tri_choice.pmf(1) == 0.5f);
    REQUIRE(l.tri_area_per_pmf.size() == 2);
    CHECK(l.tri_area_per_pmf[0] == 1.f);
    CHECK(l.tri_area_per_pmf[1] == 1.f);
    CHECK(s.features.has(LightKind::Mesh));
    CHECK(s.bounds.hi == Vec3(1, 1, 0));
}

TEST_CASE("SceneEditor: emissive spheres and ellipsoids get Sphere lights",
          "[scene][editor][quick]") {
    Scene s;
    SceneEditor ed(s);
    const std::uint32_t em = ed.add_material(emitter(3.f));
    const std::uint32_t dif = ed.add_material(diffuse());
    Sphere a;
    a.center = Vec3(1.f, 2.f, 3.f);
    a.radius = 0.5f;
    a.material = dif;
    Sphere b = a;
    b.material = em;
    ed.add_sphere(a);
    ed.add_sphere(b);
    ed.add_sphere(make_ellipsoid(
        Vec3(0.f), Mat3d::from_columns(Vec3d(2, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)), em));
    ed.finalize();
    CHECK(s.spheres[0].light == -1);
    REQUIRE(s.lights.size() == 2);
    CHECK(s.spheres[1].light == 0);
    CHECK(s.spheres[2].light == 1);
    CHECK(s.lights[0].kind == LightKind::Sphere);
    CHECK(s.lights[0].geom_id == 1);
    CHECK(s.lights[0].p == b.center);
    CHECK(s.lights[0].radius == 0.5f);
    CHECK(s.lights[0].area == static_cast<float>(sphere_area(b)));
    CHECK(s.lights[1].geom_id == 2);
    CHECK(s.lights[1].area == static_cast<float>(sphere_area(s.spheres[2])));
}

TEST_CASE("SceneEditor: a rect light's panel faces its normal and links both ways",
          "[scene][editor][quick]") {
    Scene s;
    SceneEditor ed(s);
    ed.add_material(diffuse());
    Light point;
    point.kind = LightKind::Point;
    point.L = Rgb(1.f);
    CHECK(ed.add_light(point) == 0);
    // Emitting down while cross(dx, dy) points up: the panel's winding is reversed.
    const Light rect = rect_light(Vec3(0.f, 2.f, 0.f), Vec3(0.f, -1.f, 0.f), Vec3(0.f, 0.f, 1.f),
                                  Vec3(1.f, 0.f, 0.f), Rgb(4.f));
    const std::uint32_t li = ed.add_rect_light(rect, "panel");
    CHECK(li == 1);
    ed.finalize();
    REQUIRE(s.meshes.size() == 1);
    const Mesh& m = s.meshes[0];
    CHECK(m.light == 1);
    CHECK(s.lights[1].geom_id == 0);
    CHECK(m.name == "panel");
    CHECK(s.materials[m.material].kind == BsdfKind::Emission);
    CHECK(s.materials[m.material].radiance == Rgb(4.f));
    const Vec3 p0 = m.positions[m.indices[0]], p1 = m.positions[m.indices[1]],
               p2 = m.positions[m.indices[2]];
    CHECK(dot(cross(p1 - p0, p2 - p0), rect.n) > 0.f);
    CHECK(padded(m.positions));
}

TEST_CASE("SceneEditor: refuses hand-made light records and primitive light kinds",
          "[scene][editor][quick]") {
    Scene s;
    SceneEditor ed(s);
    const std::uint32_t em = ed.add_material(emitter(1.f));
    Light mesh_light;
    mesh_light.kind = LightKind::Mesh;
    CHECK_THROWS_AS(ed.add_light(mesh_light), Error);
    Light sphere_light;
    sphere_light.kind = LightKind::Sphere;
    CHECK_THROWS_AS(ed.add_light(sphere_light), Error);
    Mesh m = square(em);
    m.light = 0;
    CHECK_THROWS_AS(ed.add_mesh(m), Error);
    CHECK_THROWS_AS(ed.add_mesh(square(7)), Error);
    Light point;
    point.kind = LightKind::Point;
    const std::uint32_t pi = ed.add_light(point);
    CHECK_THROWS_AS(ed.add_rect_panel(pi, "not a rect"), Error);
    CHECK(s.meshes.empty());
}

TEST_CASE("check_scene: names what is wrong with a scene assembled by hand",
          "[scene][editor][quick]") {
    auto base = [] {
        Scene s;
        s.source = "hand.dae";
        SceneEditor ed(s);
        ed.add_material(diffuse());
        ed.add_material(emitter(1.f));
        ed.add_mesh(square(0));
        ed.add_mesh(square(1));
        Sphere sp;
        sp.material = 1;
        ed.add_sphere(sp);
        return s;
    };
    CHECK(check_message(base()).empty());
    {
        Scene s = base();
        s.meshes[0].indices[4] = 9;
        const std::string msg = check_message(s);
        CHECK(msg.find("scene 'hand.dae'") != std::string::npos);
        CHECK(msg.find("mesh 0 ('square')") != std::string::npos);
        CHECK(msg.find("out of range") != std::string::npos);
    }
    {
        Scene s = base();
        s.meshes[0].indices.pop_back();
        CHECK(check_message(s).find("not a multiple of 3") != std::string::npos);
    }
    {
        Scene s = base();
        s.meshes[0].normals.pop_back();
        CHECK(check_message(s).find("normals") != std::string::npos);
    }
    {
        Scene s = base();
        s.meshes[0].material = 5;
        CHECK(check_message(s).find("material 5") != std::string::npos);
    }
    {
        Scene s = base(); // an emitter added without its record, as hand-made scenes did
        s.meshes[1].light = -1;
        CHECK(check_message(s).find("mesh 1 ('square') is emissive but has no light record") !=
              std::string::npos);
    }
    {
        Scene s = base();
        s.spheres[0].light = -1;
        CHECK(check_message(s).find("sphere 0 is emissive") != std::string::npos);
    }
    {
        Scene s = base(); // a record whose primitive does not point back
        s.lights[0].geom_id = 0;
        CHECK(!check_message(s).empty());
    }
    {
        Scene s = base();
        s.lights[0].tri_area_per_pmf.pop_back();
        CHECK(check_message(s).find("triangle densities") != std::string::npos);
    }
    {
        Scene s = base();
        s.lights[0].tri_choice = UnitCdf(std::vector<std::uint32_t>{UnitCdf::kUnits});
        CHECK(check_message(s).find("1 triangle choices") != std::string::npos);
    }
    {
        Scene s = base(); // a diffuse mesh claiming a light
        s.meshes[0].light = 0;
        CHECK(check_message(s).find("does not emit") != std::string::npos);
    }
    {
        Scene s = base();
        Light env;
        env.kind = LightKind::Environment;
        s.lights.push_back(env);
        CHECK(check_message(s).find("environment map") != std::string::npos);
    }
    {
        Scene s = base();
        SceneEditor ed(s);
        s.meshes[0].indices[0] = 100;
        CHECK_THROWS_AS(ed.finalize(), Error);
    }
}
