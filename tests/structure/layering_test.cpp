// The stage graph (docs/development.md "Layout"): every #include of a candela header in
// include/candela and src follows the data flow, external libraries stay in the stage that owns
// them, and the renderer core holds none of the diagnostics' code. These tests read the source
// tree and the built libraries, so a change that breaks the layering fails here, not in a review.
#include "../support/source_text.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using candela::test::read_text;

namespace {

/// What each stage may include besides itself. A stage that is not listed (app, image_module)
/// may include anything; tests and tools are outside include/candela and src.
const std::map<std::string, std::set<std::string>>& allowed_edges() {
    static const std::map<std::string, std::set<std::string>> edges = [] {
        const std::set<std::string> core = {"math",  "util", "sampling", "scene", "io",
                                            "accel", "bsdf", "light",    "render"};
        std::map<std::string, std::set<std::string>> e = {
            {"math", {}},
            {"util", {}},
            {"sampling", {"math", "util"}},
            {"scene", {"math", "util", "sampling"}},
            {"io", {"math", "util", "scene"}},
            {"accel", {"math", "util", "sampling", "scene"}},
            {"bsdf", {"math", "util", "sampling", "scene"}},
            {"light", {"math", "util", "sampling", "scene"}},
            {"render", {"math", "util", "sampling", "scene", "io", "accel", "bsdf", "light"}},
        };
        // Diagnostics (check, bench, converge) and the numerics stress suite sit on the whole
        // core and on each other, never on the command line.
        std::set<std::string> diag = core;
        diag.insert({"diagnostics", "numerics"});
        e["diagnostics"] = diag;
        e["numerics"] = diag;
        return e;
    }();
    return edges;
}

/// External headers that only the named stages may include.
struct ExternalRule {
    const char* prefix;                   ///< beginning of the <...> include
    std::set<std::string> allowed_stages; ///< where it may appear
};
const std::vector<ExternalRule>& external_rules() {
    static const std::vector<ExternalRule> rules = {
        {"CLI/", {"app"}},                  // the command line is the app's
        {"OpenImageIO/", {"image_module"}}, // image I/O loads as a module on first use
        {"tinyxml2", {"io"}},               // the COLLADA reader
        {"OpenEXR/", {"io"}},               // EXR pixels without the image module
        {"embree3/", {"accel"}},            // traversal, and the bench's raw loops
        {"mpi.h", {"render"}},              // the distributed pass loop
    };
    return rules;
}

struct SourceFile {
    fs::path path;
    std::string stage;
};

std::vector<SourceFile> project_sources() {
    const fs::path root = CANDELA_SOURCE_DIR;
    std::vector<SourceFile> out;
    for (const char* top : {"include/candela", "src"}) {
        const fs::path dir = root / top;
        for (const auto& entry : fs::recursive_directory_iterator(dir)) {
            if (!entry.is_regular_file()) continue;
            const std::string ext = entry.path().extension().string();
            if (ext != ".h" && ext != ".cpp" && ext != ".inl") continue;
            const fs::path rel = fs::relative(entry.path(), dir);
            out.push_back({entry.path(), rel.begin()->string()});
        }
    }
    return out;
}

/// Defined, global, non-weak symbols (text, data, bss, read-only data) of a static library.
std::set<std::string> strong_symbols(const std::string& library) {
    const std::string cmd = "nm --defined-only -g -P '" + library + "' 2>/dev/null";
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    REQUIRE(pipe);
    std::set<std::string> out;
    std::array<char, 4096> line{};
    while (std::fgets(line.data(), static_cast<int>(line.size()), pipe.get())) {
        // POSIX format: "name type value size"; archive member headers end with ':'.
        std::istringstream fields(line.data());
        std::string name, type;
        if (!(fields >> name >> type) || type.size() != 1) continue;
        if (std::string("TDBR").find(type[0]) != std::string::npos) out.insert(name);
    }
    return out;
}

} // namespace

TEST_CASE("layering: candela headers are included only along the data flow", "[structure][quick]") {
    const std::regex include_re(R"(#\s*include\s+"candela/([a-z_]+)/[^"]+")");
    std::vector<std::string> bad;
    std::size_t edges_seen = 0;
    for (const SourceFile& f : project_sources()) {
        const auto rule = allowed_edges().find(f.stage);
        const std::string text = read_text(f.path);
        for (std::sregex_iterator it(text.begin(), text.end(), include_re), end; it != end; ++it) {
            const std::string target = (*it)[1];
            ++edges_seen;
            if (target == f.stage || rule == allowed_edges().end()) continue;
            if (!rule->second.count(target))
                bad.push_back(f.path.string() + " (" + f.stage + ") includes " + it->str());
        }
    }
    // The scan found the tree: a wrong CANDELA_SOURCE_DIR would pass vacuously.
    CHECK(edges_seen > 100);
    for (const std::string& b : bad)
        UNSCOPED_INFO(b);
    CHECK(bad.empty());
}

TEST_CASE("layering: external libraries stay in the stage that owns them", "[structure][quick]") {
    std::vector<std::string> bad;
    std::map<std::string, int> seen;
    for (const SourceFile& f : project_sources()) {
        const std::string text = read_text(f.path);
        for (const ExternalRule& r : external_rules()) {
            const std::string needle = std::string("#include <") + r.prefix;
            if (text.find(needle) == std::string::npos) continue;
            ++seen[r.prefix];
            if (!r.allowed_stages.count(f.stage))
                bad.push_back(f.path.string() + " (" + f.stage + ") includes <" + r.prefix + ">");
        }
    }
    CHECK(seen["CLI/"] > 0); // the rule matches real includes
    for (const std::string& b : bad)
        UNSCOPED_INFO(b);
    CHECK(bad.empty());
}

TEST_CASE("layering: Embree is included only by the accel stage's own sources in src/accel",
          "[structure][quick]") {
    // No public header names an Embree type: a stage that needs Embree's speed (the bench's
    // raw ceiling) asks accel for it (accel/raw_embree.h).
    const fs::path accel_src = fs::path(CANDELA_SOURCE_DIR) / "src" / "accel";
    std::vector<std::string> bad;
    int embree_files = 0;
    for (const SourceFile& f : project_sources()) {
        if (read_text(f.path).find("#include <embree3/") == std::string::npos) continue;
        if (f.path.parent_path() == accel_src)
            ++embree_files;
        else
            bad.push_back(f.path.string());
    }
    CHECK(embree_files > 0); // the scan reached the Embree backend
    for (const std::string& b : bad)
        UNSCOPED_INFO("includes Embree outside src/accel: " << b);
    CHECK(bad.empty());
}

TEST_CASE("layering: the renderer core holds no diagnostics code and no command line",
          "[structure][quick]") {
    const std::set<std::string> core = strong_symbols(CANDELA_CORE_LIBRARY);
    const std::set<std::string> diag = strong_symbols(CANDELA_DIAGNOSTICS_LIBRARY);
    const std::set<std::string> app = strong_symbols(CANDELA_APP_LIBRARY);
    // nm read both archives (an empty set would make the checks below vacuous).
    REQUIRE(core.size() > 100);
    REQUIRE(diag.size() > 20);
    REQUIRE(app.size() > 20);
    std::vector<std::string> both;
    for (const std::string& s : diag)
        if (core.count(s)) both.push_back(s);
    for (const std::string& s : both)
        UNSCOPED_INFO("defined in core and diagnostics: " << s);
    CHECK(both.empty());
    // No symbol of the core names check, bench, converge, numerics or CLI11 (mangled names
    // carry the identifiers verbatim).
    const std::regex forbidden("(Bench|bench|Check(Report|Options|Pair|Case|RayKind)|run_check|"
                               "classify_hits|HitClass|Converge|converge_|render_reference|"
                               "numerics|DoubleBrute|CLI)");
    std::vector<std::string> named;
    for (const std::string& s : core)
        if (std::regex_search(s, forbidden)) named.push_back(s);
    for (const std::string& s : named)
        UNSCOPED_INFO("core symbol: " << s);
    CHECK(named.empty());
}

TEST_CASE("layering: warning lines are formatted in one place", "[structure][quick]") {
    // util/log.cpp's warning_text() makes every "WHO: warning: WHAT" line (print_warning,
    // Diagnostics, warning_line); a hand-made one elsewhere would drift from it and from -q.
    const fs::path home = fs::path(CANDELA_SOURCE_DIR) / "src" / "util" / "log.cpp";
    std::vector<std::string> bad;
    bool scanned_home = false;
    for (const SourceFile& f : project_sources()) {
        const bool is_home = fs::equivalent(f.path, home);
        scanned_home |= is_home;
        // A string literal that begins a warning line: "candela: warning: ...".
        static const std::regex literal("\"[a-z]*: warning: ");
        if (!is_home && std::regex_search(read_text(f.path), literal))
            bad.push_back(f.path.string());
    }
    CHECK(scanned_home);
    for (const std::string& b : bad)
        UNSCOPED_INFO("formats a warning line by hand: " << b);
    CHECK(bad.empty());
}

TEST_CASE("layering: the render stage's files include one another in one direction",
          "[structure][quick]") {
    // A module is a header and its source (renderer.h with renderer.cpp); the render stage's
    // modules form no include cycle, so each can be read, and tested, above the ones it uses.
    // The render state (render_state.h) lies below both the pass loop (renderer) and the pass
    // policies (adaptive); the ranks' blocks are the pass loop's (renderer), below MPI's
    // (distributed).
    const std::regex include_re(R"(#\s*include\s+"candela/render/([a-z_0-9]+)\.h")");
    std::map<std::string, std::set<std::string>> uses; // module -> the modules it includes
    for (const SourceFile& f : project_sources()) {
        if (f.stage != "render") continue;
        const std::string from = f.path.stem().string();
        uses[from];
        const std::string text = read_text(f.path);
        for (std::sregex_iterator it(text.begin(), text.end(), include_re), end; it != end; ++it)
            if ((*it)[1] != from) uses[from].insert((*it)[1]);
    }
    CHECK(uses["adaptive"].count("render_state") == 1);
    CHECK(uses["renderer"].count("render_state") == 1);
    // Depth-first search for a cycle; each one found is reported by its modules.
    std::map<std::string, int> state; // 0 unseen, 1 on the path, 2 done
    std::vector<std::string> path, cycles;
    std::function<void(const std::string&)> visit = [&](const std::string& m) {
        state[m] = 1;
        path.push_back(m);
        for (const std::string& n : uses[m]) {
            if (state[n] == 1) {
                std::string c;
                for (auto it = std::find(path.begin(), path.end(), n); it != path.end(); ++it)
                    c += *it + " -> ";
                cycles.push_back(c + n);
            } else if (state[n] == 0) {
                visit(n);
            }
        }
        path.pop_back();
        state[m] = 2;
    };
    for (const auto& entry : uses)
        if (state[entry.first] == 0) visit(entry.first);
    CHECK(uses.size() > 15); // the scan found the stage
    for (const std::string& c : cycles)
        UNSCOPED_INFO("include cycle: " << c);
    CHECK(cycles.empty());
}

TEST_CASE("layering: text is formatted by fmt alone", "[structure][quick]") {
    // One formatting system: fmt::format and fmt::print. The printf family (snprintf into fixed
    // buffers, fprintf, fmt's own printf emulation) would be a second set of format strings with
    // its own rules for widths, truncation and argument types.
    static const std::regex printf_call(R"(\b(std::)?(s|sn|f|v|vs|vsn|vf)?printf\s*\()");
    const fs::path root = CANDELA_SOURCE_DIR;
    std::vector<fs::path> files;
    for (const SourceFile& f : project_sources())
        files.push_back(f.path);
    for (const auto& entry : fs::recursive_directory_iterator(root / "tools")) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".h" || ext == ".cpp")) files.push_back(entry.path());
    }
    std::vector<std::string> bad;
    for (const fs::path& p : files) {
        std::istringstream text(read_text(p));
        std::string line;
        for (int n = 1; std::getline(text, line); ++n) {
            const std::string code = line.substr(0, line.find("//"));
            if (std::regex_search(code, printf_call))
                bad.push_back(fs::relative(p, root).string() + ":" + std::to_string(n));
        }
    }
    // The scan read the tree (a wrong root would pass vacuously).
    CHECK(files.size() > 100);
    for (const std::string& b : bad)
        UNSCOPED_INFO("printf-family call: " << b);
    CHECK(bad.empty());
}
