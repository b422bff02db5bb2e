// tools/bootstrap.sh's first render, as the script runs it (at a smaller size): it writes an
// image a newcomer can open without an HDR viewer, a PNG, and the script's last lines name
// every file they speak of, each of them written.
#include "app_support.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <sstream>

using namespace candela::test;
namespace fs = std::filesystem;

namespace {

/// `text` with every `from` replaced by `to`.
std::string replace_all(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t p = text.find(from); p != std::string::npos;
         p = text.find(from, p + to.size()))
        text.replace(p, from.size(), to);
    return text;
}

} // namespace

TEST_CASE("bootstrap: the first render writes a PNG preview and names both files",
          "[app][bootstrap]") {
    const std::string script = read_text(std::string(CANDELA_SOURCE_DIR) + "/tools/bootstrap.sh");
    const std::vector<std::string> lines = lines_of(script);
    // The render command: from its `"$build/candela" render` line to the first line without a
    // continuation backslash; after it, to the end of the render branch, what the script says.
    std::size_t first = 0;
    while (first < lines.size() &&
           lines[first].find("\"$build/candela\" render") == std::string::npos)
        ++first;
    REQUIRE(first < lines.size());
    std::string command;
    std::size_t last = first;
    for (; last < lines.size(); ++last) {
        const std::string& l = lines[last];
        const bool more = !l.empty() && l.back() == '\\';
        command += " " + (more ? l.substr(0, l.size() - 1) : l);
        if (!more) break;
    }
    std::string said;
    for (std::size_t i = last + 1; i < lines.size() && lines[i].find("else") != 0; ++i)
        said += lines[i] + "\n";

    // The script's root: a directory of its own whose scenes are the project's.
    TempDir root("bootstrap");
    fs::create_directory_symlink(CANDELA_PROJECT_SCENES, root.path / "scenes");
    fs::create_directories(root.path / "out");
    std::istringstream words(replace_all(command, "\"", ""));
    std::vector<std::string> args;
    std::string w;
    words >> w; // the binary
    while (words >> w)
        args.push_back(replace_all(w, "$root", root.path.string()));
    // A tenth of the frame keeps the test short; everything else as the script has it.
    const auto r = std::find(args.begin(), args.end(), "-r");
    REQUIRE(std::distance(r, args.end()) > 2);
    *(r + 1) = "40";
    *(r + 2) = "30";
    const Result run = run_candela(args);
    INFO(run.err);
    REQUIRE(run.status == 0);

    // Every file the closing lines name exists; the EXR and a PNG are among them.
    std::vector<std::string> named;
    const std::string prefix = "$root/out/";
    for (std::size_t p = said.find(prefix); p != std::string::npos; p = said.find(prefix, p + 1)) {
        const std::size_t end = said.find_first_of(" \n\"", p);
        named.push_back(said.substr(p + prefix.size(), end - p - prefix.size()));
    }
    INFO(said);
    CHECK(std::count(named.begin(), named.end(), "cornell-box.exr") == 1);
    CHECK(std::count(named.begin(), named.end(), "cornell-box.png") == 1);
    for (const std::string& f : named) {
        INFO(f);
        CHECK(fs::exists(root.path / "out" / f));
    }
}
