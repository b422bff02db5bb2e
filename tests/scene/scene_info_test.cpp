// `candela info`: the text and JSON summaries of a scene, on candela's own scenes and (when
// present) the CS184 ones.
#include "../support/cs184.h"
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/scene/scene_info.h"

#include <catch2/catch.hpp>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

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

/// A small structural JSON check: strings are terminated, brackets balance and match, every
/// bare token is a number or true/false/null. Returns an empty string when valid, else why not.
std::string json_problem(const std::string& s) {
    std::vector<char> stack;
    for (std::size_t i = 0; i < s.size(); ++i) {
        char c = s[i];
        if (c == '"') {
            for (++i; i < s.size() && s[i] != '"'; ++i)
                if (s[i] == '\\') ++i;
            if (i >= s.size()) return "unterminated string";
        } else if (c == '{' || c == '[') {
            stack.push_back(c);
        } else if (c == '}' || c == ']') {
            if (stack.empty() || stack.back() != (c == '}' ? '{' : '[')) return "unbalanced";
            stack.pop_back();
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            const char* start = s.c_str() + i;
            char* end = nullptr;
            std::strtod(start, &end);
            if (end == start) return "bad number at " + std::to_string(i);
            i += static_cast<std::size_t>(end - start) - 1;
        } else if (std::isalpha(static_cast<unsigned char>(c))) {
            bool ok = false;
            for (const char* w : {"true", "false", "null"})
                if (s.compare(i, std::strlen(w), w) == 0) {
                    i += std::strlen(w) - 1;
                    ok = true;
                }
            if (!ok) return "bare word at " + std::to_string(i);
        } else if (!(c == ':' || c == ',' || c == ' ' || c == '\n')) {
            return std::string("unexpected character '") + c + "'";
        }
    }
    return stack.empty() ? "" : "unclosed bracket";
}

/// The number following `"key": ` in s (first occurrence), or NaN.
double json_number(const std::string& s, const std::string& key) {
    auto k = s.find("\"" + key + "\": ");
    if (k == std::string::npos) return std::nan("");
    return std::strtod(s.c_str() + k + key.size() + 4, nullptr);
}

} // namespace

TEST_CASE("info: JSON summary of CBspheres is valid and complete", "[info][quick]") {
    CANDELA_SKIP_WITHOUT_CS184();
    Scene s = load_shared("CBspheres.dae");
    std::string j = describe_scene(s, true);
    INFO(j);
    CHECK(json_problem(j).empty());
    for (const char* key :
         {"\"source\"", "\"triangles\"", "\"spheres\"", "\"meshes\"", "\"materials\"", "\"lights\"",
          "\"bounds\"", "\"camera\"", "\"position\"", "\"target\"", "\"hfov_deg\"",
          "\"vfov_deg_4x3\"", "\"skipped\""})
        CHECK(j.find(key) != std::string::npos);
    CHECK(json_number(j, "triangles") == 12);
    CHECK(json_number(j, "spheres") == 2);
    CHECK(json_number(j, "glass") == 1);
    CHECK(json_number(j, "mirror") == 1);
    CHECK(json_number(j, "diffuse") == 5);
    CHECK(json_number(j, "area") == 1);
    CHECK(json_number(j, "hfov_deg") == Approx(49.1343));
    // vfov at 4:3: 2 atan(tan(49.134°/2)·3/4) = 37.849° (spec §3.2 table).
    CHECK(json_number(j, "vfov_deg_4x3") == Approx(37.849).epsilon(1e-4));
    CHECK(j.find("no environment importance table") != std::string::npos);
    CHECK(j.find("no sphere intersection path") == std::string::npos); // it has spheres
    CHECK(j.find("no delta-BSDF paths") == std::string::npos);         // glass and mirror
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
    std::string j = describe_scene(s, true);
    CHECK(json_problem(j).empty());
    // A malformed document is caught by the checker itself.
    CHECK_FALSE(json_problem("{\"a\": [1, 2}").empty());
    CHECK_FALSE(json_problem("{\"a\": inf}").empty());
}

TEST_CASE("info: JSON summary of the own Cornell box is valid and complete", "[info][quick]") {
    Scene s = load_own("cornell-box.dae");
    std::string j = describe_scene(s, true);
    INFO(j);
    CHECK(json_problem(j).empty());
    for (const char* key :
         {"\"source\"", "\"triangles\"", "\"spheres\"", "\"meshes\"", "\"materials\"", "\"lights\"",
          "\"bounds\"", "\"camera\"", "\"position\"", "\"target\"", "\"hfov_deg\"",
          "\"vfov_deg_4x3\"", "\"skipped\""})
        CHECK(j.find(key) != std::string::npos);
    CHECK(json_number(j, "triangles") == 22);
    CHECK(json_number(j, "spheres") == 1);
    CHECK(json_number(j, "glass") == 1);
    CHECK(json_number(j, "mirror") == 0);
    CHECK(json_number(j, "diffuse") == 4);
    CHECK(json_number(j, "area") == 1);
    CHECK(json_number(j, "hfov_deg") == Approx(40.0));
    // vfov at 4:3: 2 atan(tan(40°/2)·3/4) = 30.537°.
    CHECK(json_number(j, "vfov_deg_4x3") == Approx(30.537).epsilon(1e-4));
    CHECK(j.find("no environment importance table") != std::string::npos);
    CHECK(j.find("no sphere intersection path") == std::string::npos); // it has a sphere
    CHECK(j.find("no delta-BSDF paths") == std::string::npos);         // glass
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
    CHECK(json_problem(describe_scene(s, true)).empty());
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
    const std::string j = describe_scene(s, true);
    INFO(j);
    CHECK(json_problem(j).empty());
    CHECK(json_number(j, "spheres") == 2);
    CHECK(json_number(j, "ellipsoids") == 1);
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
