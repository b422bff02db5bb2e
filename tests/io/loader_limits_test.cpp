// Loader resource limits (candela/io/collada.h, loader_limits): hostile size claims, strides,
// offsets, indices, nesting, file size and instancing must fail fast with a clear message and
// without allocating what they claim. Large inputs are generated in memory.
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

using namespace candela;

namespace {

/// Every rejection below is a linear scan of at most a few MB of text; 1 s is more than ten
/// times what a debug build needs, while honouring any of the hostile claims (gigabytes of
/// polygon sizes, vertices or triangles) would take far longer or exhaust memory.
constexpr double kMaxRejectSeconds = 1.0;

/// A document with one mesh geometry `g` (positions `positions`, `count` floats, the given
/// accessor and primitive groups) instanced by `instances` (node content).
std::string document(const std::string& positions, const std::string& count,
                     const std::string& accessor, const std::string& groups,
                     const std::string& instances) {
    return "<?xml version=\"1.0\"?>\n<COLLADA version=\"1.4.1\">\n"
           "<asset><up_axis>Y_UP</up_axis></asset>\n"
           "<library_geometries><geometry id=\"g\" name=\"g\"><mesh>\n"
           "<source id=\"pos\"><float_array id=\"pos-a\" count=\"" +
           count + "\">" + positions + "</float_array>" + accessor +
           "</source>\n"
           "<source id=\"nrm\"><float_array id=\"nrm-a\" count=\"3\">0 0 1</float_array></source>\n"
           "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#pos\"/></vertices>\n" +
           groups +
           "\n</mesh></geometry></library_geometries>\n"
           "<library_lights><light id=\"lamp\"><technique_common><point><color>1 1 1</color>"
           "</point></technique_common></light></library_lights>\n"
           "<library_visual_scenes><visual_scene id=\"vs\">\n<node id=\"n\" name=\"n\">" +
           instances +
           "</node>\n<node id=\"l\"><translate>0 2 0</translate>"
           "<instance_light url=\"#lamp\"/></node>\n"
           "</visual_scene></library_visual_scenes>\n"
           "<scene><instance_visual_scene url=\"#vs\"/></scene>\n</COLLADA>\n";
}

const char* kTriangle = "0 0 0  1 0 0  0 1 0";
const char* kOneInstance = "<instance_geometry url=\"#g\"/>";

std::string triangles(const std::string& count, const std::string& p,
                      const std::string& normal_offset = "") {
    std::string s = "<triangles count=\"" + count +
                    "\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/>";
    if (!normal_offset.empty())
        s += "<input semantic=\"NORMAL\" source=\"#nrm\" offset=\"" + normal_offset + "\"/>";
    return s + "<p>" + p + "</p></triangles>";
}

/// Runs `load` (which must throw), checks the message and that it failed within the bound.
void expect_fast_error(const std::function<void()>& load, const std::string& substring,
                       ErrorKind kind = ErrorKind::Scene) {
    INFO("expected: " << substring);
    const Stopwatch timer;
    bool threw = false;
    try {
        load();
    } catch (const Error& e) {
        threw = true;
        const std::string msg = e.what();
        INFO("message: " << msg);
        CHECK(e.kind() == kind);
        CHECK(e.where()); // the file (and line) it concerns
        CHECK(msg.find(substring) != std::string::npos);
    }
    const double seconds = timer.seconds();
    CHECK(threw);
    CHECK(seconds < kMaxRejectSeconds);
}

void expect_parse_error(const std::string& text, const std::string& substring) {
    expect_fast_error(
        [&] {
            Diagnostics diag;
            parse_collada(text, "limits.dae", diag);
        },
        substring);
}

} // namespace

TEST_CASE("limits: the baseline document loads and builds", "[limits][quick]") {
    // Guards the tests below: each one changes a single claim of this valid document.
    Diagnostics diag;
    SceneDesc d = parse_collada(
        document(kTriangle, "9", "", triangles("1", "0 0 1 0 2 0", "1"), kOneInstance),
        "limits.dae", diag);
    REQUIRE(d.geometries.size() == 1);
    CHECK(d.geometries[0].triangle_count() == 1);
    Scene s = build_scene(d, BuildOptions{}, diag);
    CHECK(s.meshes.size() == 1);
}

TEST_CASE("limits: huge count attributes fail before allocation", "[limits][quick]") {
    expect_parse_error(document(kTriangle, "4000000000", "", triangles("1", "0 1 2"), kOneInstance),
                       "count=\"4000000000\" but 9 numbers");
    expect_parse_error(document(kTriangle, "9", "", triangles("4000000000", "0 1 2"), kOneInstance),
                       "has 3 indices but 12000000000 corners x stride 1 = 12000000000 expected");
    // count*3 would wrap a 32-bit product: 1431655766 * 3 = 2^32 + 2.
    expect_parse_error(document(kTriangle, "9", "", triangles("1431655766", "0 1 2"), kOneInstance),
                       "has 3 indices but 4294967298 corners x stride 1 = 4294967298 expected");
    // Beyond 32 bits the attribute itself is refused.
    expect_parse_error(
        document(kTriangle, "9", "", triangles("18446744073709551617", "0 1 2"), kOneInstance),
        "count=\"18446744073709551617\" is not a non-negative integer");
}

TEST_CASE("limits: vcount sums that <p> cannot hold fail before allocation", "[limits][quick]") {
    const std::string polylist = "<polylist count=\"3\"><input semantic=\"VERTEX\" source=\"#v\" "
                                 "offset=\"0\"/><vcount>4294967295 4294967295 4294967295</vcount>"
                                 "<p>0 1 2</p></polylist>";
    expect_parse_error(document(kTriangle, "9", "", polylist, kOneInstance),
                       "<p> of <polylist> of mesh 'g' has 3 indices but 12884901885 corners");
    // Many large vcounts in memory: the sum is stopped before it could overflow.
    std::string many;
    for (int i = 0; i < 100000; ++i)
        many += "4294967295 ";
    const std::string big = "<polylist count=\"100000\"><input semantic=\"VERTEX\" source=\"#v\" "
                            "offset=\"0\"/><vcount>" +
                            many + "</vcount><p>0 1 2</p></polylist>";
    expect_parse_error(document(kTriangle, "9", "", big, kOneInstance),
                       "has 3 indices but 429496729500000 corners");
}

TEST_CASE("limits: absurd accessor strides and input offsets", "[limits][quick]") {
    expect_parse_error(document(kTriangle, "9",
                                "<technique_common><accessor count=\"1\" stride=\"4294967295\"/>"
                                "</technique_common>",
                                triangles("1", "0 0 0"), kOneInstance),
                       "has stride 4294967295, more than the limit of 1024");
    // The largest stride is honoured: vectors start 1024 floats apart.
    {
        constexpr std::uint32_t kS = loader_limits::kMaxAccessorStride;
        std::string floats;
        for (std::uint32_t i = 0; i < 2 * kS + 3; ++i)
            floats += (i == kS || i == 2 * kS + 1) ? "1 " : "0 ";
        Diagnostics diag;
        SceneDesc d = parse_collada(document(floats, std::to_string(2 * kS + 3),
                                             "<technique_common><accessor count=\"3\" stride=\"" +
                                                 std::to_string(kS) + "\"/></technique_common>",
                                             triangles("1", "0 1 2"), kOneInstance),
                                    "limits.dae", diag);
        REQUIRE(d.geometries.size() == 1);
        const std::vector<Vec3>& P = d.geometries[0].positions;
        REQUIRE(P.size() == 3);
        CHECK(P[0] == Vec3(0.f, 0.f, 0.f));
        CHECK(P[1] == Vec3(1.f, 0.f, 0.f));
        CHECK(P[2] == Vec3(0.f, 1.f, 0.f));
    }
    // offset = 2^32-1 would make the index stride (max offset + 1) wrap to zero.
    expect_parse_error(
        document(kTriangle, "9", "", triangles("1", "0 0 1 0 2 0", "4294967295"), kOneInstance),
        "has offset 4294967295, more than the limit of 1023");
}

TEST_CASE("limits: huge indices are range-checked", "[limits][quick]") {
    expect_parse_error(document(kTriangle, "9", "", triangles("1", "0 1 4294967295"), kOneInstance),
                       "VERTEX index 4294967295 out of range (3 positions)");
    expect_parse_error(document(kTriangle, "9", "", triangles("1", "0 1 4294967296"), kOneInstance),
                       "'4294967296' is out of range");
    expect_parse_error(
        document(kTriangle, "9", "", triangles("1", "0 0 1 4294967295 2 0", "1"), kOneInstance),
        "NORMAL index 4294967295 out of range (1 normals)");
}

TEST_CASE("limits: deep XML nesting is refused with a clear message", "[limits][quick]") {
    std::string nodes;
    constexpr int kDepth = 100000; // far past the limit; must not recurse that deep
    for (int i = 0; i < kDepth; ++i)
        nodes += "<node>";
    for (int i = 0; i < kDepth; ++i)
        nodes += "</node>";
    expect_parse_error(document(kTriangle, "9", "", triangles("1", "0 1 2"), nodes),
                       "nested deeper than 98 levels");
    // At the limit: COLLADA, library_visual_scenes, visual_scene and node "n" are levels 1-4;
    // `extra` more nodes put the innermost node at level 4 + extra, with a self-closing
    // instance_geometry one level below it.
    const auto nested = [](int extra) {
        std::string s;
        for (int i = 0; i < extra; ++i)
            s += "<node>";
        s += kOneInstance;
        for (int i = 0; i < extra; ++i)
            s += "</node>";
        return document(kTriangle, "9", "", triangles("1", "0 1 2"), s);
    };
    expect_parse_error(nested(loader_limits::kMaxXmlDepth - 3), "nested deeper than 98 levels");
    Diagnostics diag;
    SceneDesc d = parse_collada(nested(loader_limits::kMaxXmlDepth - 4), "ok.dae", diag);
    CHECK(d.instances.size() == 2); // the geometry and the light
}

TEST_CASE("limits: instancing beyond the triangle budget fails before building",
          "[limits][quick]") {
    // 2^14 triangles instanced 2^14 + 1 times: 2^28 + 2^14 triangles, a little over the limit.
    constexpr std::uint64_t kTris = std::uint64_t(1) << 14;
    static_assert(kTris * kTris == loader_limits::kMaxTriangles, "test sized for the limit");
    std::string p;
    for (std::uint64_t i = 0; i < kTris; ++i)
        p += "0 1 2 ";
    std::string inst;
    for (std::uint64_t i = 0; i < kTris + 1; ++i)
        inst += kOneInstance;
    const std::string text =
        document(kTriangle, "9", "", triangles(std::to_string(kTris), p), inst);
    Diagnostics diag;
    SceneDesc d = parse_collada(text, "bomb.dae", diag);
    REQUIRE(d.instances.size() == kTris + 2);
    expect_fast_error([&] { build_scene(d, BuildOptions{}, diag); },
                      "instancing makes more than 268435456 triangles");
}

TEST_CASE("limits: a file over the size limit fails before it is read", "[limits][quick]") {
    // A sparse file: the size is set without writing (or reading) half a gigabyte.
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() / "candela-limits-too-large.dae";
    {
        std::ofstream f(path, std::ios::binary);
        REQUIRE(f);
    }
    std::filesystem::resize_file(path, loader_limits::kMaxFileBytes + 1);
    expect_fast_error(
        [&] {
            Diagnostics diag;
            load_collada(path.string(), diag);
        },
        "file too large (536870913 bytes, limit 536870912)", ErrorKind::Io);
    std::filesystem::remove(path);
    // A directory has no meaningful size (tellg reports 2^63 - 1 on Linux): say what it is.
    expect_fast_error(
        [&] {
            Diagnostics diag;
            load_collada(std::filesystem::temp_directory_path().string(), diag);
        },
        "is a directory", ErrorKind::Io);
}

TEST_CASE("limits: a small group of a large mesh builds only its own vertices",
          "[limits][builder][quick]") {
    // 3000 positions, two one-triangle groups: each mesh gets exactly its three vertices, in
    // first-use order (the sparse renumbering path of the builder).
    std::string floats;
    for (int i = 0; i < 3000; ++i)
        floats += std::to_string(i % 7) + " " + std::to_string(i % 11) + " " +
                  std::to_string(i % 13) + " ";
    const std::string groups = triangles("1", "2999 0 1") + triangles("1", "5 17 4");
    Diagnostics diag;
    SceneDesc d =
        parse_collada(document(floats, "9000", "", groups, kOneInstance), "sparse.dae", diag);
    Scene s = build_scene(d, BuildOptions{}, diag);
    REQUIRE(s.meshes.size() == 2);
    for (const Mesh& m : s.meshes) {
        CHECK(m.positions.size() == 3);
        CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2});
    }
    const auto pos = [&](int i) { return Vec3(float(i % 7), float(i % 11), float(i % 13)); };
    CHECK(s.meshes[0].positions[0] == pos(2999));
    CHECK(s.meshes[0].positions[1] == pos(0));
    CHECK(s.meshes[1].positions[0] == pos(5));
    CHECK(s.meshes[1].positions[1] == pos(17));
    CHECK(s.meshes[1].positions[2] == pos(4));
}
