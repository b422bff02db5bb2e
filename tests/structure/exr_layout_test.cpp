// The channel names and metadata keys of a candela EXR are spelled in one header,
// render/exr_layout.h, except the keys of the render settings, which their rows in
// render/setting_table.cpp declare: no other source holds a "candela:..." key as a string literal.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

TEST_CASE("exr layout: metadata keys are spelled only in render/exr_layout.h and the settings' "
          "table",
          "[structure][quick]") {
    const fs::path root = CANDELA_SOURCE_DIR;
    const std::regex key("\"candela:[a-z_]+\"");
    std::vector<std::string> found;
    for (const char* top : {"include/candela", "src"})
        for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
            if (!entry.is_regular_file()) continue;
            const std::string ext = entry.path().extension().string();
            if (ext != ".h" && ext != ".cpp") continue;
            const fs::path name = entry.path().filename();
            if (name == "exr_layout.h" || name == "setting_table.cpp") continue;
            std::ifstream in(entry.path());
            std::stringstream text;
            text << in.rdbuf();
            const std::string s = text.str();
            for (std::sregex_iterator it(s.begin(), s.end(), key), e; it != e; ++it)
                found.push_back(entry.path().string() + ": " + (*it)[0].str());
        }
    for (const std::string& f : found)
        UNSCOPED_INFO(f);
    CHECK(found.empty());
}
