// The "Compare your 3-1 output" recipe (README.md between its markers, else
// docs/compare-recipe.md): its candela commands run as written and end in "matches", and the
// stand-in render uses the path tracer's own flags.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

using namespace candela::test;

namespace {

constexpr const char* kBegin = "<!-- recipe:compare:begin -->";
constexpr const char* kEnd = "<!-- recipe:compare:end -->";

/// The recipe's text: README.md's between the markers when it has them, else the doc's.
std::string recipe_text() {
    for (const char* file : {"README.md", "docs/compare-recipe.md"}) {
        const std::string text = read_text(std::string(CANDELA_SOURCE_DIR) + "/" + file);
        const std::size_t begin = text.find(kBegin), end = text.find(kEnd);
        if (begin != std::string::npos && end != std::string::npos && begin < end) {
            INFO("recipe from " << file);
            return text.substr(begin, end - begin);
        }
    }
    FAIL("no recipe between " << kBegin << " and " << kEnd);
    return {};
}

/// The lines of the recipe's first ```sh block.
std::vector<std::string> shell_lines(const std::string& recipe) {
    std::vector<std::string> out;
    bool inside = false;
    for (const std::string& line : lines_of(recipe)) {
        if (!inside && line == "```sh") {
            inside = true;
        } else if (inside && line == "```") {
            return out;
        } else if (inside) {
            out.push_back(line);
        }
    }
    FAIL("the recipe has no closed ```sh block");
    return out;
}

/// Words split at spaces, with $name replaced by the variables' values.
std::vector<std::string> words_of(std::string line,
                                  const std::map<std::string, std::string>& vars) {
    for (const auto& [name, value] : vars) {
        const std::string ref = "$" + name;
        for (std::size_t at = line.find(ref); at != std::string::npos; at = line.find(ref, at))
            line.replace(at, ref.size(), value);
    }
    std::istringstream in(line);
    std::vector<std::string> words;
    for (std::string w; in >> w;)
        words.push_back(w);
    return words;
}

/// The values following `flag` in a command (up to `count` of them).
std::vector<std::string> flag_values(const std::vector<std::string>& words, const std::string& flag,
                                     int count) {
    for (std::size_t i = 0; i < words.size(); ++i)
        if (words[i] == flag && i + std::size_t(count) < words.size())
            return {words.begin() + std::ptrdiff_t(i) + 1,
                    words.begin() + std::ptrdiff_t(i) + 1 + count};
    return {};
}

} // namespace

TEST_CASE("the compare recipe runs as written and ends in a match", "[compare][app][docs]") {
    const std::vector<std::string> lines = shell_lines(recipe_text());
    TempDir dir("compare-recipe");
    const std::filesystem::path cwd = dir.path / "build";
    std::filesystem::create_directories(cwd);
    // The scene the recipe names sits where it says, relative to the path tracer's build
    // directory: the course's when present, else candela's Cornell box in its place.
    const bool course = cs184_available();
    if (!course) WARN("the CS184 scenes are absent: the recipe runs on scenes/cornell-box.dae");
    // Until `--framing` exists, the commands run without it (candela's framing on both sides).
    const bool framing =
        run_candela({"compare", "--help"}).out.find("--framing") != std::string::npos;
    if (!framing) WARN("candela has no --framing yet: the recipe runs without it");

    std::map<std::string, std::string> vars;
    std::vector<std::string> tracer, render;
    Result last;
    int ran = 0;
    for (const std::string& line : lines) {
        if (line.empty() || line[0] == '#') continue;
        const std::size_t eq = line.find('=');
        if (eq != std::string::npos && line.find(' ') == std::string::npos) {
            const std::string name = line.substr(0, eq), value = line.substr(eq + 1);
            vars[name] = value;
            const std::filesystem::path target = cwd / ".." / value;
            if (value.size() > 4 && value.substr(value.size() - 4) == ".dae") {
                std::filesystem::create_directories(target.parent_path());
                const std::string real = course ? cs184_scene(target.filename().string())
                                                : project_scene("cornell-box.dae");
                std::filesystem::create_symlink(real, target);
            }
            continue;
        }
        std::vector<std::string> words = words_of(line, vars);
        REQUIRE_FALSE(words.empty());
        if (words[0] == "./pathtracer") {
            tracer = words;
            continue;
        }
        INFO(line);
        REQUIRE(words[0] == "candela");
        words.erase(words.begin());
        if (!framing) {
            for (std::size_t i = 0; i + 1 < words.size();) {
                if (words[i] == "--framing")
                    words.erase(words.begin() + std::ptrdiff_t(i),
                                words.begin() + std::ptrdiff_t(i) + 2);
                else
                    ++i;
            }
        }
        if (words[0] != "compare") render = words;
        last = run_candela(words, cwd.string());
        ++ran;
        INFO(last.out << last.err);
        REQUIRE(last.status == 0);
    }
    REQUIRE(ran >= 2);
    // The last command is the comparison, and candela's image of a correct path tracer passes.
    INFO(last.out);
    CHECK(last.out.find("verdict: every determined layer matches") != std::string::npos);
    // The stand-in render uses the path tracer's flags.
    REQUIRE_FALSE(tracer.empty());
    REQUIRE_FALSE(render.empty());
    for (const auto& [flag, count] :
         std::vector<std::pair<std::string, int>>{{"-s", 1}, {"-l", 1}, {"-m", 1}, {"-r", 2}}) {
        INFO(flag);
        CHECK_FALSE(flag_values(tracer, flag, count).empty());
        CHECK(flag_values(tracer, flag, count) == flag_values(render, flag, count));
    }
}
