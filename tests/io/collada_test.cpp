// COLLADA reader: transforms, up axis, primitive groups, materials, strict mode and the
// broken-file corpus (tests/data/broken/expected.txt).
#include "candela/io/collada.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

using namespace candela;

namespace {

/// Matrices are composed in double from exact inputs; 1e-12 covers the rounding of cos/sin
/// of 90 degrees and a few products.
constexpr double kMatTol = 1e-12;

std::string effect(const std::string& id, const std::string& body) {
    return "<effect id=\"" + id + "\">" + body + "</effect>";
}

/// A complete document with the given <asset> content, libraries and visual-scene nodes.
std::string dae(const std::string& asset, const std::string& libraries, const std::string& nodes) {
    return "<?xml version=\"1.0\"?>\n<COLLADA version=\"1.4.1\">\n<asset>" + asset + "</asset>\n" +
           libraries +
           "\n<library_lights><light id=\"lamp\" name=\"lamp\"><technique_common><point>"
           "<color>1 1 1</color></point></technique_common></light></library_lights>\n"
           "<library_visual_scenes><visual_scene id=\"vs\">\n" +
           nodes +
           "\n</visual_scene></library_visual_scenes>\n"
           "<scene><instance_visual_scene url=\"#vs\"/></scene>\n</COLLADA>\n";
}

const char* kYUp = "<up_axis>Y_UP</up_axis>";

/// World matrix of a node holding `transforms` and a point light.
Mat4 world_of(const std::string& transforms, const char* up = kYUp) {
    Diagnostics diag;
    SceneDesc d = parse_collada(
        dae(up, "",
            "<node id=\"n\" name=\"n\">" + transforms + "<instance_light url=\"#lamp\"/></node>"),
        "inline.dae", diag);
    REQUIRE(d.instances.size() == 1);
    return d.instances[0].world;
}

void check_vec(const Vec3d& a, const Vec3d& b) {
    CHECK(a.x == Approx(b.x).margin(kMatTol));
    CHECK(a.y == Approx(b.y).margin(kMatTol));
    CHECK(a.z == Approx(b.z).margin(kMatTol));
}

/// A mesh geometry `g` with the given positions and primitive groups (VERTEX at offset 0).
std::string mesh_geometry(const std::string& positions, int count, const std::string& groups,
                          const std::string& extra_sources = "") {
    return "<library_geometries><geometry id=\"g\" name=\"g\"><mesh><source id=\"pos\">"
           "<float_array id=\"pos-a\" count=\"" +
           std::to_string(count) + "\">" + positions + "</float_array></source>" + extra_sources +
           "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#pos\"/></vertices>" + groups +
           "</mesh></geometry></library_geometries>";
}

const char* kQuad = "0 0 0  1 0 0  1 1 0  0 1 0";

} // namespace

TEST_CASE("collada: translate, rotate, scale compose in document order", "[loader][quick]") {
    check_vec(world_of("<translate>1 2 3</translate>").point(Vec3d(0.0)), Vec3d(1, 2, 3));
    check_vec(world_of("<rotate>0 0 1 90</rotate>").point(Vec3d(1, 0, 0)), Vec3d(0, 1, 0));
    check_vec(world_of("<scale>2 3 4</scale>").point(Vec3d(1, 1, 1)), Vec3d(2, 3, 4));
    // L = T·S: the scale applies first, then the translation (COLLADA order).
    check_vec(world_of("<translate>1 0 0</translate><scale>2 2 2</scale>").point(Vec3d(1, 0, 0)),
              Vec3d(3, 0, 0));
    check_vec(world_of("<scale>2 2 2</scale><translate>1 0 0</translate>").point(Vec3d(1, 0, 0)),
              Vec3d(4, 0, 0));
    // <matrix> is row-major (translation in elements 3, 7, 11) and composes like the others.
    check_vec(world_of("<matrix>1 0 0 5 0 1 0 6 0 0 1 7 0 0 0 1</matrix><scale>2 2 2</scale>")
                  .point(Vec3d(1, 0, 0)),
              Vec3d(7, 6, 7));
}

TEST_CASE("collada: lookat places local -Z toward the interest point", "[loader][quick]") {
    Mat4 W = world_of("<lookat>0 0 5  0 0 0  0 1 0</lookat>");
    check_vec(W.point(Vec3d(0.0)), Vec3d(0, 0, 5));
    check_vec(W.point(Vec3d(0, 0, -1)), Vec3d(0, 0, 4));
    check_vec(W.vector(Vec3d(0, 1, 0)), Vec3d(0, 1, 0));
    Mat4 W2 = world_of("<lookat>3 0 0  0 0 0  0 1 0</lookat>");
    check_vec(W2.vector(Vec3d(0, 0, -1)), Vec3d(-1, 0, 0));
}

TEST_CASE("collada: nested nodes compose W = P·L", "[loader][quick]") {
    Diagnostics diag;
    SceneDesc d = parse_collada(
        dae(kYUp, "",
            "<node id=\"p\" name=\"p\"><translate>1 0 0</translate>"
            "<node id=\"c\" name=\"c\"><scale>2 2 2</scale><instance_light url=\"#lamp\"/></node>"
            "</node>"),
        "inline.dae", diag);
    REQUIRE(d.instances.size() == 1);
    CHECK(d.instances[0].node_name == "c");
    check_vec(d.instances[0].world.point(Vec3d(1, 0, 0)), Vec3d(3, 0, 0));
}

TEST_CASE("collada: up_axis maps the file frame to world Y-up", "[loader][quick]") {
    check_vec(world_of("<translate>1 2 3</translate>", "<up_axis>Z_UP</up_axis>").point(Vec3d(0.0)),
              Vec3d(-1, 3, 2));
    check_vec(world_of("<translate>1 2 3</translate>", "<up_axis>X_UP</up_axis>").point(Vec3d(0.0)),
              Vec3d(2, 1, -3));
    check_vec(world_of("<translate>1 2 3</translate>", "<up_axis>Y_UP</up_axis>").point(Vec3d(0.0)),
              Vec3d(1, 2, 3));
    // Missing up_axis: Y_UP with one warning; strict mode makes it an error.
    Diagnostics diag;
    std::string text = dae("", "",
                           "<node id=\"n\"><translate>1 2 3</translate>"
                           "<instance_light url=\"#lamp\"/></node>");
    SceneDesc d = parse_collada(text, "inline.dae", diag);
    CHECK(diag.warning_count() == 1);
    check_vec(d.instances[0].world.point(Vec3d(0.0)), Vec3d(1, 2, 3));
    Diagnostics strict(true);
    CHECK_THROWS_AS(parse_collada(text, "inline.dae", strict), Error);
}

TEST_CASE("collada: polylist and polygons n-gons are fan-triangulated", "[loader][quick]") {
    const std::string poly =
        "<polylist count=\"2\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>"
        "<vcount>4 3</vcount><p>0 1 2 3  0 2 3</p></polylist>";
    Diagnostics diag;
    SceneDesc d = parse_collada(dae(kYUp, mesh_geometry(kQuad, 12, poly),
                                    "<node id=\"n\"><instance_geometry url=\"#g\"/></node>"),
                                "inline.dae", diag);
    REQUIRE(d.geometries.size() == 1);
    const DescPrimGroup& g = d.geometries[0].groups.at(0);
    REQUIRE(g.triangle_count() == 3);
    std::vector<std::uint32_t> expect{0, 1, 2, 0, 2, 3, 0, 2, 3};
    CHECK(g.position_index == expect);
    CHECK(g.normal_index.empty());
    CHECK(diag.warning_count() == 0); // a planar convex quad triangulates exactly (a note only)

    // <polygons>: one <p> per polygon; a pentagon gives three triangles.
    const std::string pent = "0 0 0  2 0 0  3 1 0  1 2 0  -1 1 0";
    const std::string polys = "<polygons count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" "
                              "offset=\"0\"/><p>0 1 2 3 4</p></polygons>";
    Diagnostics diag2;
    SceneDesc d2 = parse_collada(dae(kYUp, mesh_geometry(pent, 15, polys),
                                     "<node id=\"n\"><instance_geometry url=\"#g\"/></node>"),
                                 "inline.dae", diag2);
    CHECK(d2.geometries[0].triangle_count() == 3);
    CHECK(diag2.warning_count() == 0);

    // A non-planar quad warns once per mesh (the fan may differ from the intended surface).
    Diagnostics diag3;
    SceneDesc d3 = parse_collada(dae(kYUp, mesh_geometry("0 0 0  1 0 0  1 1 1  0 1 0", 12, poly),
                                     "<node id=\"n\"><instance_geometry url=\"#g\"/></node>"),
                                 "inline.dae", diag3);
    CHECK(d3.geometries[0].triangle_count() == 3);
    CHECK(diag3.warning_count() == 1);
}

TEST_CASE("collada: stride is max(offset)+1 and degenerate triangles are dropped",
          "[loader][quick]") {
    // Inputs share offset 0 plus an unknown semantic at offset 2: stride 3.
    const std::string tri =
        "<triangles count=\"3\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>"
        "<input semantic=\"COLOR\" source=\"#pos\" offset=\"2\"/>"
        "<p>0 9 9 1 9 9 2 9 9  0 9 9 2 9 9 3 9 9  0 9 9 0 9 9 1 9 9</p></triangles>";
    Diagnostics diag;
    SceneDesc d = parse_collada(dae(kYUp, mesh_geometry(kQuad, 12, tri),
                                    "<node id=\"n\"><instance_geometry url=\"#g\"/></node>"),
                                "inline.dae", diag);
    CHECK(d.geometries[0].triangle_count() == 2); // the third (0,0,1) has zero area
    CHECK(diag.warning_count() == 1);
}

TEST_CASE("collada: every primitive group binds its own material", "[loader][quick]") {
    const std::string libs =
        "<library_effects>" +
        effect("fa", "<profile_COMMON><technique sid=\"common\"><lambert><diffuse><color>1 0 0 1"
                     "</color></diffuse></lambert></technique></profile_COMMON>") +
        effect("fb", "<profile_COMMON><technique sid=\"common\"><phong><diffuse><color>0 1 0 1"
                     "</color></diffuse></phong></technique></profile_COMMON>") +
        "</library_effects><library_materials>"
        "<material id=\"ma\" name=\"red\"><instance_effect url=\"#fa\"/></material>"
        "<material id=\"mb\" name=\"green\"><instance_effect url=\"#fb\"/></material>"
        "</library_materials>" +
        mesh_geometry(kQuad, 12,
                      "<triangles material=\"A\" count=\"1\"><input semantic=\"VERTEX\" "
                      "source=\"#v\" offset=\"0\"/><p>0 1 2</p></triangles>"
                      "<triangles material=\"B\" count=\"1\"><input semantic=\"VERTEX\" "
                      "source=\"#v\" offset=\"0\"/><p>0 2 3</p></triangles>"
                      "<triangles material=\"C\" count=\"1\"><input semantic=\"VERTEX\" "
                      "source=\"#v\" offset=\"0\"/><p>1 2 3</p></triangles>");
    const std::string node = "<node id=\"n\"><instance_geometry url=\"#g\"><bind_material>"
                             "<technique_common>"
                             "<instance_material symbol=\"B\" target=\"#mb\"/>"
                             "<instance_material symbol=\"A\" target=\"#ma\"/>"
                             "</technique_common></bind_material></instance_geometry></node>";
    Diagnostics diag;
    SceneDesc d = parse_collada(dae(kYUp, libs, node), "inline.dae", diag);
    REQUIRE(d.geometries[0].groups.size() == 3);
    REQUIRE(d.instances.size() == 1);
    const DescInstance& inst = d.instances[0];
    REQUIRE(inst.group_materials.size() == 3);
    const auto& mats = d.materials;
    CHECK(mats[static_cast<std::size_t>(inst.group_materials[0])].material.name == "red");
    CHECK(mats[static_cast<std::size_t>(inst.group_materials[1])].material.name == "green");
    // Unbound symbol C: the first bound material.
    CHECK(inst.group_materials[2] == inst.material);
    CHECK(mats[static_cast<std::size_t>(inst.material)].material.name == "green");
    CHECK(mats[static_cast<std::size_t>(inst.group_materials[0])].material.albedo == Rgb(1, 0, 0));
}

TEST_CASE("collada: CGL materials, last recognised wins, unknown BSDF warns", "[loader][quick]") {
    auto load_effect = [](const std::string& cgl, Diagnostics& diag) {
        std::string libs =
            "<library_effects>" +
            effect("fx", "<profile_COMMON><technique sid=\"common\"><phong><diffuse><color>0.2 "
                         "0.3 0.4 1</color></diffuse></phong></technique></profile_COMMON>"
                         "<extra><technique profile=\"CGL\">" +
                             cgl + "</technique></extra>") +
            "</library_effects><library_materials><material id=\"m\" name=\"m\">"
            "<instance_effect url=\"#fx\"/></material></library_materials>" +
            mesh_geometry(kQuad, 12,
                          "<triangles count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" "
                          "offset=\"0\"/><p>0 1 2</p></triangles>");
        SceneDesc d = parse_collada(
            dae(kYUp, libs,
                "<node id=\"n\"><instance_geometry url=\"#g\"><bind_material><technique_common>"
                "<instance_material symbol=\"x\" target=\"#m\"/></technique_common>"
                "</bind_material></instance_geometry></node>"),
            "inline.dae", diag);
        return d.materials.at(0).material;
    };
    Diagnostics diag;
    Material m = load_effect("<mirror><reflectance>1 1 1</reflectance></mirror>"
                             "<glass><transmittance>1 .75 .75</transmittance><reflectance>1 1 1"
                             "</reflectance><roughness>0</roughness><ior>1.45</ior></glass>",
                             diag);
    CHECK(m.kind == BsdfKind::Glass);
    CHECK(m.ior == Approx(1.45f));
    CHECK(m.transmittance == Rgb(1.f, .75f, .75f));
    Material mf = load_effect("<microfacet><alpha>0.05</alpha><eta>0.33 1.01 1.24</eta>"
                              "<k>3.16 2.57 2.46</k></microfacet>",
                              diag);
    CHECK(mf.kind == BsdfKind::Microfacet);
    CHECK(mf.alpha == Approx(0.05f));
    CHECK(mf.k.x == Approx(3.16f));
    CHECK(diag.warning_count() == 0);
    Material tf = load_effect("<thinfilm><ior>1.3</ior></thinfilm>", diag);
    CHECK(tf.kind == BsdfKind::Diffuse);
    CHECK(tf.albedo.y == Approx(0.3f));
    CHECK(diag.warning_count() == 1);
    Diagnostics strict(true);
    try {
        load_effect("<thinfilm><ior>1.3</ior></thinfilm>", strict);
        FAIL("strict mode accepted an unknown CGL BSDF");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("thinfilm") != std::string::npos);
        CHECK(std::string(e.what()).find("inline.dae:") == 0);
    }
}

TEST_CASE("collada: lights and cameras", "[loader][quick]") {
    std::string libs =
        "<library_lights>"
        "<light id=\"s\" name=\"spot\"><technique_common><spot><color>2 2 2</color>"
        "<falloff_angle>60</falloff_angle><falloff_exponent>3</falloff_exponent></spot>"
        "</technique_common></light>"
        "<light id=\"a\" name=\"area\"><technique_common><point><color>1 1 1</color></point>"
        "</technique_common><extra><technique profile=\"CGL\"><area><energy>2</energy><red>1"
        "</red><green>2</green><blue>3</blue></area></technique></extra></light>"
        "</library_lights><library_cameras><camera id=\"c\" name=\"c\"><optics>"
        "<technique_common><perspective><yfov>30</yfov><aspect_ratio>2</aspect_ratio>"
        "</perspective></technique_common></optics></camera></library_cameras>";
    Diagnostics diag;
    SceneDesc d = parse_collada(dae(kYUp, libs,
                                    "<node id=\"n1\"><instance_light url=\"#s\"/></node>"
                                    "<node id=\"n2\"><instance_light url=\"#a\"/></node>"
                                    "<node id=\"n3\"><instance_camera url=\"#c\"/></node>"),
                                "inline.dae", diag);
    REQUIRE(d.lights.size() == 2);
    CHECK(d.lights[0].kind == DescLightKind::Spot);
    CHECK(d.lights[0].falloff_angle_deg == 60.f);
    CHECK(d.lights[0].falloff_exponent == 3.f);
    CHECK(d.lights[1].kind == DescLightKind::Area); // CGL wins over technique_common
    CHECK(d.lights[1].color == Rgb(2, 4, 6));
    REQUIRE(d.cameras.size() == 1);
    // hfov = 2 atan(tan(15°)·2) = 56.37357°; defaults for clip planes (spec §1.4).
    CHECK(d.cameras[0].hfov_deg() == Approx(56.37357).epsilon(1e-5));
    CHECK(d.cameras[0].znear == Approx(0.001f));
    CHECK(d.cameras[0].zfar == Approx(1000.f));
}

TEST_CASE("collada: missing file is an Io error", "[loader][quick]") {
    Diagnostics diag;
    try {
        load_collada("no-such-file.dae", diag);
        FAIL("no exception");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Io);
        CHECK(std::string(e.what()).find("no-such-file.dae") == 0);
    }
}

TEST_CASE("collada: broken-file corpus fails with the file and line of each fault",
          "[loader][quick]") {
    const std::string dir = std::string(CANDELA_TEST_DATA) + "/broken/";
    std::ifstream index(dir + "expected.txt");
    REQUIRE(index);
    std::string line;
    int files = 0;
    while (std::getline(index, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ls(line);
        std::string file, line_no, substring;
        ls >> file >> line_no;
        std::getline(ls, substring);
        substring.erase(0, substring.find_first_not_of(' '));
        const std::string path = dir + file;
        INFO(file);
        Diagnostics diag;
        try {
            load_collada(path, diag);
            FAIL("loaded without an error: " << file);
        } catch (const Error& e) {
            const std::string msg = e.what();
            INFO(msg);
            CHECK(e.kind() == ErrorKind::Scene);
            REQUIRE(e.where());
            CHECK(e.where()->file == path);
            CHECK(std::to_string(e.where()->line) == line_no);
            CHECK(error_line(e).rfind("candela: error: " + path + ":" + line_no + ": ", 0) == 0);
            CHECK(msg.find(substring) != std::string::npos);
        }
        ++files;
    }
    CHECK(files >= 30);
}
