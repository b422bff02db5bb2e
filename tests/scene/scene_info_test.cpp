// `candela info`: the text and JSON summaries of a scene, on candela's own scenes and (when
// present) the CS184 ones.
#include "../support/cs184.h"
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <string>

using namespace candela;

namespace {

Scene load_shared(const std::string& name) {
    Diagnostics diag;
    return load_scene(test::cs184_scene(name), BuildOptions{}, diag);
}

Scene load_own(const std::string& name) {
    Diagnostics diag;
    return load_scene(test::project_scene(name), BuildOptions{}, diag);
}

/// The JSON summary parsed; a malformed document fails the test.
nlohmann::json parse_info(const std::string& s) {
    nlohmann::json j = nlohmann::json::parse(s, nullptr, false);
    REQUIRE_FALSE(j.is_discarded());
    return j;
}

/// Whether one of the summary's skipped features mentions `text`.
bool skips(const nlohmann::json& j, const std::string& text) {
    for (const auto& line : j.at("skipped"))
        if (line.get<std::string>().find(text) != std::string::npos) return true;
    return false;
}

/// Every key of `info --json`, at the top level and in its objects.
void check_complete(const nlohmann::json& j) {
    for (const char* key : {"source", "triangles", "spheres", "ellipsoids", "meshes", "materials",
                            "lights", "bounds", "camera", "skipped"})
        CHECK(j.contains(key));
    for (const char* key : {"position", "target", "hfov_deg", "vfov_deg_4x3"})
        CHECK(j.at("camera").contains(key));
    CHECK(j.at("camera").at("position").size() == 3);
}

} // namespace

TEST_CASE("info: JSON summary of CBspheres is valid and complete", "[info][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Scene s = load_shared("CBspheres.dae");
    const std::string text = describe_scene(s, true);
    INFO(text);
    const nlohmann::json j = parse_info(text);
    check_complete(j);
    CHECK(j.at("triangles") == 12);
    CHECK(j.at("spheres") == 2);
    CHECK(j.at("materials").at("glass") == 1);
    CHECK(j.at("materials").at("mirror") == 1);
    CHECK(j.at("materials").at("diffuse") == 5);
    CHECK(j.at("lights").at("area") == 1);
    CHECK(j.at("camera").at("hfov_deg").get<double>() == Approx(49.1343));
    // vfov at 4:3: 2 atan(tan(49.134°/2)·3/4) = 37.849° (spec §3.2 table).
    CHECK(j.at("camera").at("vfov_deg_4x3").get<double>() == Approx(37.849).epsilon(1e-4));
    CHECK(skips(j, "no environment importance table"));
    CHECK_FALSE(skips(j, "no sphere intersection path")); // it has spheres
    CHECK_FALSE(skips(j, "no delta-BSDF paths"));         // glass and mirror
}

TEST_CASE("info: text summary names skipped features", "[info][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Scene s = load_shared("bunny.dae");
    std::string t = describe_scene(s, false);
    INFO(t);
    CHECK(t.find("triangles  33696") != std::string::npos);
    CHECK(t.find("ambient 1") != std::string::npos);
    CHECK(t.find("no sphere intersection path (no spheres)") != std::string::npos);
    CHECK(t.find("no delta-BSDF paths") != std::string::npos);
    CHECK(t.find("no area-light sampling") != std::string::npos);
    CHECK(t.find("no delta-light sampling") != std::string::npos);
    CHECK(t.find("no ambient lookups") == std::string::npos);
    const nlohmann::json j = parse_info(describe_scene(s, true));
    check_complete(j);
    CHECK(skips(j, "no sphere intersection path (no spheres)"));
}

TEST_CASE("info: JSON summary of the own Cornell box is valid and complete", "[info][quick]") {
    Scene s = load_own("cornell-box.dae");
    const std::string text = describe_scene(s, true);
    INFO(text);
    const nlohmann::json j = parse_info(text);
    check_complete(j);
    CHECK(j.at("triangles") == 22);
    CHECK(j.at("spheres") == 1);
    CHECK(j.at("materials").at("glass") == 1);
    CHECK(j.at("materials").at("mirror") == 0);
    CHECK(j.at("materials").at("diffuse") == 4);
    CHECK(j.at("lights").at("area") == 1);
    CHECK(j.at("camera").at("hfov_deg").get<double>() == Approx(40.0));
    // vfov at 4:3: 2 atan(tan(40°/2)·3/4) = 30.537°.
    CHECK(j.at("camera").at("vfov_deg_4x3").get<double>() == Approx(30.537).epsilon(1e-4));
    CHECK(skips(j, "no environment importance table"));
    CHECK_FALSE(skips(j, "no sphere intersection path")); // it has a sphere
    CHECK_FALSE(skips(j, "no delta-BSDF paths"));         // glass
}

TEST_CASE("info: text summary of an own scene names skipped features", "[info][quick]") {
    Scene s = load_own("glossy.dae");
    std::string t = describe_scene(s, false);
    INFO(t);
    CHECK(t.find("triangles  6") != std::string::npos);
    CHECK(t.find("microfacet 4") != std::string::npos);
    CHECK(t.find("no delta-BSDF paths") != std::string::npos);
    CHECK(t.find("no delta-light sampling") != std::string::npos);
    CHECK(t.find("no ambient lookups") != std::string::npos);
    CHECK(t.find("no sphere intersection path") == std::string::npos); // four spheres
    CHECK(t.find("no area-light sampling") == std::string::npos);      // the strip light
    check_complete(parse_info(describe_scene(s, true)));
    // lights.dae has an ambient light, so its escaped rays look up the sky.
    CHECK(describe_scene(load_own("lights.dae"), false).find("no ambient lookups") ==
          std::string::npos);
}

TEST_CASE("info: ellipsoids are counted and bounded by their true extent", "[info][quick]") {
    Scene s;
    s.source = "ellipsoid";
    Material rough_glass;
    rough_glass.kind = BsdfKind::Glass;
    rough_glass.roughness = 0.2f;
    s.materials.push_back(rough_glass);
    Mat3d L;
    L.m[0][0] = 1.0;
    L.m[1][1] = 2.0;
    L.m[2][2] = 0.5;
    s.spheres.push_back(make_ellipsoid(Vec3(1.f, 0.f, 0.f), L, 0));
    s.spheres.push_back(Sphere{Vec3(0.f, 0.f, 5.f), 0.25f, 0});
    s.finalize();
    const std::string text = describe_scene(s, true);
    INFO(text);
    const nlohmann::json j = parse_info(text);
    check_complete(j);
    CHECK(j.at("spheres") == 2);
    CHECK(j.at("ellipsoids") == 1);
    CHECK(s.bounds.lo.x == Approx(-0.25f));
    CHECK(s.bounds.lo.y == Approx(-2.f));
    CHECK(s.bounds.hi.y == Approx(2.f));
    CHECK(s.bounds.lo.z == Approx(-0.5f));
    CHECK(s.bounds.hi.z == Approx(5.25f));
    const std::string t = describe_scene(s, false);
    CHECK(t.find("spheres    2 (1 of them ellipsoids)") != std::string::npos);
    // A rough dielectric is neither a delta path nor free of microfacet evaluation.
    CHECK(t.find("no delta-BSDF paths") != std::string::npos);
    CHECK(t.find("no microfacet evaluation") == std::string::npos);
}

TEST_CASE("info: coordinates that are float rounding of a zero print as 0", "[info][quick]") {
    Scene s = load_own("cornell-box.dae");
    // Residues of the size float arithmetic leaves on coordinates of size ~1 where the scene
    // has a zero (the values `info` printed for two course scenes).
    s.camera.pos = Vec3(5.88118e-16f, 1.f, 3.4f);
    s.bounds.lo.y = -5.96046e-08f;
    const std::string text = describe_scene(s, false);
    INFO(text);
    CHECK_THAT(text, Catch::Contains("camera     at (0, 1, 3.4)"));
    CHECK_THAT(text, !Catch::Contains("e-16") && !Catch::Contains("e-08"));
    const nlohmann::json j = parse_info(describe_scene(s, true));
    CHECK(j.at("camera").at("position").at(0) == 0.0);
    CHECK(j.at("bounds").at("min").at(1) == 0.0);
    // A small coordinate that is not rounding of the scene's size is kept.
    s.camera.pos.x = 1e-3f;
    CHECK_THAT(describe_scene(s, false), Catch::Contains("camera     at (0.001, 1, 3.4)"));
}
