// The installed candela: it loads its own image module and no build tree's, its bash completion
// is installed, and its manual page has the usual sections and fits an 80-column terminal.
#include "../support/cs184.h"
#include "app_support.h"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace candela::test;
namespace fs = std::filesystem;

namespace {

std::string read_all(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// A line of a roff page as man shows it: escapes of hyphens, backslashes and line-start dots
/// removed.
std::string shown(std::string line) {
    for (const std::string& esc : {std::string("\\-"), std::string("\\e"), std::string("\\&")})
        for (std::size_t p = line.find(esc); p != std::string::npos; p = line.find(esc, p))
            line.replace(p, esc.size(), esc == "\\-" ? "-" : esc == "\\e" ? "\\" : "");
    return line;
}

} // namespace

TEST_CASE("install: an installed candela never loads a build tree's image module",
          "[app][install]") {
    TempDir dir("install-module");
    const std::string build = fs::path(CANDELA_MAN_PAGE).parent_path().string();
    REQUIRE(std::system(("cmake --install '" + build + "' --prefix '" + dir.path.string() +
                         "' > '" + (dir / "install.log") + "' 2>&1")
                            .c_str()) == 0);
    const fs::path bin = dir.path / "bin" / "candela";
    const fs::path module = dir.path / "lib" / "candela" / "libcandela_image.so";
    REQUIRE(fs::exists(bin));
    // The bash completion is installed where bash-completion looks for it on demand.
    const fs::path completion = dir.path / "share" / "bash-completion" / "completions" / "candela";
    CHECK(fs::exists(completion));
    CHECK(read_all(completion.string()) == read_all(CANDELA_COMPLETION));
    REQUIRE(fs::remove(module));
    // Without its own module the installed binary stops with one error: it does not fall back
    // to the build tree's module (which exists: this test binary uses it).
    const std::string out = dir / "a.exr";
    const std::string cmd = "env -u CANDELA_IMAGE_MODULE '" + bin.string() + "' render '" +
                            project_scene("cornell-box.dae") + "' -r 8 6 -s 1 -q -f '" + out +
                            "' 2> '" + (dir / "err.txt") + "'";
    const int st = std::system(cmd.c_str());
    const std::string err = read_all(dir / "err.txt");
    INFO(err);
    CHECK(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 4);
    CHECK_THAT(err, Catch::Contains("cannot load the image module"));
    CHECK_THAT(err, !Catch::Contains(build + "/libcandela_image.so"));
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("man page: EXAMPLES, ENVIRONMENT and FILES, 80 columns", "[app][install]") {
    const Result man = run_candela({"help", "--man"});
    REQUIRE(man.status == 0);
    for (const char* section : {".SH EXAMPLES", ".SH ENVIRONMENT", ".SH FILES", ".SH EXIT STATUS"})
        CHECK_THAT(man.out, Catch::Contains(section));
    CHECK_THAT(man.out, Catch::Contains("CANDELA_IMAGE_MODULE"));
    // No-fill text is shown as written, indented by 7 columns: it must fit in 73.
    bool nofill = false;
    int lines = 0;
    for (const std::string& line : lines_of(man.out)) {
        if (line == ".nf") nofill = true;
        if (line == ".fi") nofill = false;
        if (!nofill || line.empty() || line[0] == '.') continue;
        ++lines;
        INFO(line);
        CHECK(shown(line).size() <= 73u);
    }
    CHECK(lines > 100);
}
