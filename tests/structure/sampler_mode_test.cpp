// The sampler mode (AdaptiveKind) is named only where it is declared, parsed from the command
// line and turned into a pass policy (render/adaptive.h): every question whose answer depends
// on the sampler is a PassPolicy method, so no other source asks which sampler runs.
#include "../support/source_text.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using candela::test::read_text;

namespace {

/// The files that may name AdaptiveKind (relative to the source root), and why.
const std::map<std::string, const char*>& allowed_files() {
    static const std::map<std::string, const char*> files = {
        {"include/candela/render/settings.h", "declares the modes and their names"},
        {"src/render/pass_policy.cpp", "the policy factory"},
        {"include/candela/app/cli.h", "the parsed --adaptive (options.cpp parses it by name)"},
        {"src/app/render/checks.cpp", "settles the mode from --adaptive and -a"},
        {"src/app/render/resume_options.cpp", "the --adaptive a checkpoint stores"},
    };
    return files;
}

} // namespace

TEST_CASE("sampler mode: AdaptiveKind is named only by the policy factory and option parsing",
          "[structure][quick]") {
    const fs::path root = CANDELA_SOURCE_DIR;
    const std::regex name(R"(\bAdaptiveKind\b)");
    // A test of the mode: a comparison with one of its values or a case of a switch on it.
    const std::regex test(R"((==|!=)\s*AdaptiveKind::|AdaptiveKind::\w+\s*(==|!=)|)"
                          R"(case\s+AdaptiveKind::)");
    std::vector<std::string> bad;
    std::size_t files = 0, allowed_seen = 0;
    for (const char* top : {"include/candela", "src", "tools"})
        for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
            if (!entry.is_regular_file()) continue;
            const std::string ext = entry.path().extension().string();
            if (ext != ".h" && ext != ".cpp" && ext != ".inl") continue;
            ++files;
            const std::string rel = fs::relative(entry.path(), root).generic_string();
            const std::string text = read_text(entry.path());
            const bool allowed = allowed_files().count(rel) != 0;
            const bool named = std::regex_search(text, name);
            allowed_seen += allowed && named;
            if (named && !allowed) {
                bad.push_back(rel + " names AdaptiveKind");
                continue;
            }
            if (!named) continue;
            // The factory's file switches on the mode in make_pass_policy() alone: nothing
            // before its definition names the mode.
            if (rel == "src/render/pass_policy.cpp") {
                const std::size_t factory = text.find("> make_pass_policy(");
                std::smatch m;
                if (factory == std::string::npos ||
                    (std::regex_search(text, m, name) && std::size_t(m.position(0)) < factory))
                    bad.push_back(rel + " names AdaptiveKind outside make_pass_policy()");
                continue;
            }
            if (std::regex_search(text, test)) bad.push_back(rel + " tests the sampler mode");
        }
    // The scan found the tree and the files that name the mode (a wrong root would pass
    // vacuously).
    CHECK(files > 100);
    CHECK(allowed_seen == allowed_files().size());
    for (const std::string& b : bad)
        UNSCOPED_INFO(b << " (ask the PassPolicy of render/adaptive.h instead)");
    CHECK(bad.empty());
}
