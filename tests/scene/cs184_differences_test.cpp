// The table of docs/cs184-differences.md and its copy in code (scene/cs184_differences.h) are
// the same rows in the same order, and `candela info --vs-cs184` picks the rows a scene's
// content triggers.
#include "../support/cs184.h"

#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/scene/cs184_differences.h"

#include <catch2/catch.hpp>

#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// The three cells of every row of the document's table (after its header and rule).
std::vector<std::vector<std::string>> doc_rows() {
    std::ifstream in(std::string(CANDELA_SOURCE_DIR) + "/docs/cs184-differences.md");
    REQUIRE(in);
    std::vector<std::vector<std::string>> rows;
    std::string line;
    bool in_table = false;
    while (std::getline(in, line)) {
        if (line.rfind("| topic |", 0) == 0) {
            in_table = true;
            std::getline(in, line); // the |---| rule
            continue;
        }
        if (!in_table) continue;
        if (line.rfind("| ", 0) != 0) break;
        // "| a | b | c |": cells between " | " separators.
        const std::string body = line.substr(2, line.size() - 4);
        std::vector<std::string> cells;
        std::size_t start = 0, bar;
        while ((bar = body.find(" | ", start)) != std::string::npos) {
            cells.push_back(body.substr(start, bar - start));
            start = bar + 3;
        }
        cells.push_back(body.substr(start));
        rows.push_back(cells);
    }
    return rows;
}

std::set<std::string> topics_for(const std::string& path) {
    Diagnostics diag;
    const SceneDesc desc = load_collada(path, diag);
    const Scene scene = build_scene(desc, BuildOptions{}, diag);
    std::set<std::string> out;
    for (const AppliedDifference& d : cs184_differences_for(desc, scene))
        out.insert(d.row->topic);
    return out;
}

} // namespace

TEST_CASE("cs184 differences: the code's rows are the document's table", "[info][quick]") {
    const auto doc = doc_rows();
    const auto& code = cs184_differences();
    REQUIRE(doc.size() == code.size());
    for (std::size_t i = 0; i < doc.size(); ++i) {
        INFO("row " << i + 1 << ": " << code[i].topic);
        REQUIRE(doc[i].size() == 3);
        CHECK(doc[i][0] == code[i].topic);
        CHECK(doc[i][1] == code[i].cs184);
        CHECK(doc[i][2] == code[i].candela);
    }
}

TEST_CASE("cs184 differences: the rows that apply follow the scene's content", "[info][quick]") {
    // The Cornell box: an area light, walls as meshes, a glass sphere; no point lights.
    const std::set<std::string> box = topics_for(project_scene("cornell-box.dae"));
    CHECK(box.count("area-light pdf") == 1);
    CHECK(box.count("normals") == 1);
    CHECK(box.count("ray offsets") == 1);
    CHECK(box.count("glass Fresnel") == 1);
    CHECK(box.count("point lights") == 0);
    CHECK(box.count("non-uniform `<scale>` on a sphere") == 0);
    // Its variant with two diffuse spheres has no glass.
    CHECK(topics_for(project_scene("cornell-spheres.dae")).count("glass Fresnel") == 0);
    // The ellipsoid scene has spheres under a non-uniform scale.
    CHECK(topics_for(project_scene("ellipsoids.dae")).count("non-uniform `<scale>` on a sphere") ==
          1);
    // A scene without <up_axis> and with a 15-number matrix, from text.
    Diagnostics diag;
    const SceneDesc plain = parse_collada(
        "<COLLADA><library_visual_scenes><visual_scene id=\"s\"><node><matrix>1 0 0 0 0 1 0 0 0 "
        "0 1 0 0 0 0</matrix></node></visual_scene></library_visual_scenes><scene>"
        "<instance_visual_scene url=\"#s\"/></scene></COLLADA>",
        "inline.dae", diag);
    CHECK_FALSE(plain.up_axis_given);
    CHECK(plain.short_matrices == 1);
}
