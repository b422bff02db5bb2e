// Every render setting is declared once, by its row in render/setting_table.cpp: no other source
// spells a setting's flag or its EXR key as a string literal, and the command line, the EXR
// attributes and merge's checks are the rows'.
#include "candela/app/cli.h"
#include "candela/render/setting_table.h"

#include <CLI/CLI.hpp>
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace candela;

namespace {

/// The literals that name a setting: its CLI11 names ("-s,--spp"), its long flag ("--spp"),
/// the form messages show ("-s/--spp") and its EXR key ("candela:spp").
std::set<std::string> setting_spellings() {
    std::set<std::string> out;
    for (const SettingRow& row : setting_table()) {
        for (const std::string& s : {row.names, row.flag, row.display})
            if (!s.empty()) out.insert(s);
        if (row.exr_key) out.insert(row.exr_key);
    }
    return out;
}

/// The string literals of a C++ source, comments left out and adjacent literals joined as the
/// compiler joins them ("a " "b" is "a b"); a literal's escapes are kept as written.
std::vector<std::string> string_literals(const std::string& src) {
    std::vector<std::string> out;
    bool joining = false; // only whitespace since the last literal closed
    for (std::size_t i = 0; i < src.size(); ++i) {
        const char c = src[i];
        if (c == '/' && i + 1 < src.size() && src[i + 1] == '/') {
            i = src.find('\n', i);
            if (i == std::string::npos) break;
            continue;
        }
        if (c == '/' && i + 1 < src.size() && src[i + 1] == '*') {
            i = src.find("*/", i + 2);
            if (i == std::string::npos) break;
            ++i;
            continue;
        }
        if (c == '\'') { // a character literal ('"' among them)
            for (++i; i < src.size() && src[i] != '\''; ++i)
                if (src[i] == '\\') ++i;
            joining = false;
            continue;
        }
        if (c == '"') {
            std::string text;
            for (++i; i < src.size() && src[i] != '"'; ++i) {
                if (src[i] == '\\') text += src[i++];
                text += src[i];
            }
            if (joining)
                out.back() += text;
            else
                out.push_back(text);
            joining = true;
            continue;
        }
        if (!std::isspace(static_cast<unsigned char>(c))) joining = false;
    }
    return out;
}

/// Sources whose literals may name a flag a setting also has: the other subcommands declare
/// options of their own under the same names (bench's --accel is a list of backends, its -t a
/// list of thread counts), and accel.cpp's parser of bench's and check's --accel lies in a stage
/// below the table.
bool outside_the_render_command(const fs::path& relative) {
    const std::string p = relative.generic_string();
    const std::string name = relative.filename().string();
    return (p.rfind("src/app/cmd_", 0) == 0) || p == "src/app/scene_source.h" ||
           p == "src/accel/accel.cpp" || name == "setting_table.cpp";
}

} // namespace

TEST_CASE("setting table: the literal scanner sees joined literals and skips comments",
          "[structure][quick]") {
    const std::vector<std::string> l =
        string_literals("f(\"a \"\n  \"b\"); // \"c\"\n/* \"d\" */ g('\"', \"e\\\"f\");");
    REQUIRE(l.size() == 2);
    CHECK(l[0] == "a b");
    CHECK(l[1] == "e\\\"f");
}

TEST_CASE("setting table: no source outside the table spells a setting's flag or EXR key",
          "[structure][quick]") {
    const std::set<std::string> spellings = setting_spellings();
    const fs::path root = CANDELA_SOURCE_DIR;
    std::vector<std::string> found;
    std::size_t files = 0;
    for (const char* top : {"include/candela", "src"})
        for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
            if (!entry.is_regular_file()) continue;
            const std::string ext = entry.path().extension().string();
            if (ext != ".h" && ext != ".cpp") continue;
            const fs::path relative = fs::relative(entry.path(), root);
            if (outside_the_render_command(relative)) continue;
            ++files;
            std::ifstream in(entry.path());
            std::stringstream text;
            text << in.rdbuf();
            for (const std::string& literal : string_literals(text.str()))
                if (spellings.count(literal))
                    found.push_back(relative.generic_string() + ": \"" + literal + "\"");
        }
    CHECK(files > 100); // the tree was found
    for (const std::string& f : found)
        UNSCOPED_INFO(f);
    CHECK(found.empty());
}

TEST_CASE("setting table: one row per setting, each with its own flag and key",
          "[structure][quick]") {
    std::set<std::string> flags, keys;
    for (std::size_t i = 0; i < setting_table().size(); ++i) {
        const SettingRow& row = setting_table()[i];
        INFO("row " << i << " " << row.names);
        CHECK(row.id == Setting(i));
        CHECK(&setting_row(row.id) == &row);
        if (!row.flag.empty()) {
            CHECK(flags.insert(row.flag).second);
            CHECK(find_setting(row.flag) == &row);
            CHECK(row.flag.rfind("--", 0) == 0);
        }
        if (row.exr_key) {
            CHECK(keys.insert(row.exr_key).second);
            CHECK(std::string(row.exr_key).rfind("candela:", 0) == 0);
        }
        // A setting the EXR does not record cannot tell merge's parts apart.
        if (row.merge_equal) CHECK(row.exr_key != nullptr);
        // A runtime setting changes no pixel, so merge has nothing to compare.
        if (row.runtime) CHECK_FALSE(row.merge_equal);
    }
    CHECK(setting_table().size() == std::size_t(Setting::Count));
}

TEST_CASE("setting table: the render command declares each flag from its row",
          "[structure][quick][cli]") {
    RenderArgs args;
    CLI::App app;
    add_render_options(app, args);
    for (const SettingRow& row : setting_table()) {
        if (row.flag.empty()) continue;
        INFO(row.flag);
        const CLI::Option* o = app.get_option_no_throw(row.flag);
        REQUIRE(o != nullptr);
        CHECK(o->get_description() == row.help);
        std::string names;
        for (const std::string& s : o->get_snames())
            names += "-" + s + ",";
        for (const std::string& l : o->get_lnames())
            names += "--" + l + ",";
        CHECK(names == row.names + ",");
    }
}

TEST_CASE("setting table: the EXR attributes and merge's keys are the rows'",
          "[structure][quick]") {
    const RenderSettings s = command_line_settings();
    const std::vector<Attribute> attributes = setting_attributes(s);
    std::set<std::string> written;
    for (const Attribute& a : attributes)
        written.insert(a.name);
    std::size_t with_key = 0;
    for (const SettingRow& row : setting_table())
        if (row.exr_key) {
            ++with_key;
            CHECK(written.count(row.exr_key) == 1);
        }
    CHECK(attributes.size() == with_key);
    for (const char* key : merge_equal_keys())
        CHECK(written.count(key) == 1);
    // Parts that differ only in their sample range, budget or traversal still merge.
    const std::vector<const char*> merge = merge_equal_keys();
    for (Setting id : {Setting::Spp, Setting::SampleOffset, Setting::Accel, Setting::TimeBudget})
        CHECK(std::find(merge.begin(), merge.end(), setting_key(id)) == merge.end());
}

TEST_CASE("setting table: the command line's defaults are the rows'", "[structure][quick][cli]") {
    const RenderSettings s = command_line_settings();
    CHECK(s.spp == kDefaultSpp);
    CHECK(s.sampler == SamplerKind::Sobol);
    CHECK(s.noise_threshold == kDefaultNoiseThreshold);
    CHECK(s.adaptive_batch == kDefaultAdaptiveBatch);
    const RenderArgs args;
    CHECK(args.settings.spp == kDefaultSpp);
    CHECK(args.settings.sampler == SamplerKind::Sobol);
    // The rows without a default of their own keep RenderSettings' initializer.
    CHECK(s.max_depth == RenderSettings{}.max_depth);
    CHECK(s.light_sampler == RenderSettings{}.light_sampler);
}
