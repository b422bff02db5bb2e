// docs/usage.md's "What candela prints" and docs/exr-metadata.md's `oiiotool --info -v` listing
// come from real runs of today's defaults (tools/exr_docs.sh remakes both). These tests fail
// when the defaults drift away from them: the printed lines must have the same shape, and the
// EXR the same attributes with the same default values. The listings' counts are those of an
// 800x600 render too long for a test; the fingerprint exr_docs.sh writes under them (a 40x30
// default render's sample statistics) stands for them: when the renderer's images change, it
// changes, and the listings are out of date.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

using namespace candela;
using namespace candela::test;
namespace fs = std::filesystem;

namespace {

std::string read_doc(const std::string& relative) {
    std::ifstream in(std::string(CANDELA_SOURCE_DIR) + "/" + relative);
    REQUIRE(in);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The first ``` block after the line containing `heading`.
std::string block_after(const std::string& doc, const std::string& heading) {
    const std::size_t h = doc.find(heading);
    REQUIRE(h != std::string::npos);
    const std::size_t open = doc.find("```\n", h);
    REQUIRE(open != std::string::npos);
    const std::size_t close = doc.find("```", open + 4);
    REQUIRE(close != std::string::npos);
    return doc.substr(open + 4, close - open - 4);
}

/// A printed line's shape: every number is '#', paths are dropped to their file name.
std::string shape(const std::string& line) {
    static const std::regex path("[^ :]*/([^/ :]+)");
    static const std::regex number("[0-9]+(\\.[0-9]+)?(e[+-]?[0-9]+)?");
    return std::regex_replace(std::regex_replace(line, path, "$1"), number, "#");
}

/// The shapes of the lines of `text`, without progress lines, with a run of lines that hold
/// only numbers (the samples-by-region grid, whose size follows the image's) kept once.
std::vector<std::string> shapes(const std::string& text) {
    std::vector<std::string> out;
    for (const std::string& line : lines_of(text)) {
        if (line.rfind("progress", 0) == 0) continue;
        std::string s = shape(line);
        if (s.find_first_not_of(" #") == std::string::npos) s = "<grid>";
        if (!out.empty() && out.back() == s && s == "<grid>") continue;
        out.push_back(s);
    }
    return out;
}

/// `name: value` lines of an `oiiotool --info -v` listing (indented by four spaces).
std::map<std::string, std::string> listed_attributes(const std::string& listing) {
    std::map<std::string, std::string> out;
    static const std::regex entry("^    ([A-Za-z][A-Za-z0-9_:]*): (.*)$");
    for (const std::string& line : lines_of(listing)) {
        std::smatch m;
        if (std::regex_match(line, m, entry)) out[m[1].str()] = m[2].str();
    }
    return out;
}

/// An attribute's value as oiiotool lists it: strings quoted, numbers with 6 digits.
std::string listed_value(const Attribute& a) {
    std::ostringstream s;
    switch (a.type) {
    case Attribute::Type::String:
        return "\"" + a.text + "\"";
    case Attribute::Type::Int:
        return std::to_string(a.i);
    case Attribute::Type::Float:
        s << a.f;
        return s.str();
    case Attribute::Type::Double:
        s << a.d;
        return s.str();
    default:
        return "";
    }
}

/// A render with every default but a small image, in a directory whose scenes/ is the
/// repository's (the command line the documents show).
struct DefaultRender {
    TempDir dir{"docs-listing"};
    Result result;
    DefaultRender() {
        fs::create_directory_symlink(CANDELA_PROJECT_SCENES, dir.path / "scenes");
        result =
            run_candela({"render", "scenes/cornell-box.dae", "-r", "40", "30"}, dir.path.string());
        REQUIRE(result.status == 0);
    }
};

} // namespace

TEST_CASE("docs: usage.md's printed example is what the default render prints", "[app][docs]") {
    const std::string usage = read_doc("docs/usage.md");
    const std::string example = block_after(usage, "## What candela prints");
    DefaultRender run;
    INFO("docs/usage.md:\n" << example << "\nprinted:\n" << run.result.err);
    CHECK(shapes(example) == shapes(run.result.err));
}

TEST_CASE("docs: the listings are remade when the default render's images change", "[app][docs]") {
    const std::string usage = read_doc("docs/usage.md");
    const std::string marker = "<!-- exr_docs fingerprint (40x30): ";
    const std::size_t at = usage.find(marker);
    REQUIRE(at != std::string::npos);
    const std::size_t begin = at + marker.size();
    const std::string recorded = usage.substr(begin, usage.find(" -->", begin) - begin);
    DefaultRender run;
    // The same lines tools/exr_docs.sh takes: samples/pixel, stopped, samples; spaces squeezed.
    std::string now;
    static const std::regex stat("^  (samples/pixel|stopped|samples) .*");
    static const std::regex spaces(" +");
    for (const std::string& line : lines_of(run.result.err)) {
        if (!std::regex_match(line, stat)) continue;
        const std::string squeezed = std::regex_replace(line.substr(2), spaces, " ");
        now += (now.empty() ? "" : " | ") + squeezed;
    }
    INFO("the 40x30 default render's statistics differ from the fingerprint under the listing "
         "of docs/usage.md \"What candela prints\": run bash tools/exr_docs.sh");
    CHECK(recorded == now);
}

TEST_CASE("docs: exr-metadata.md's listing has the default render's attributes and values",
          "[app][docs]") {
    const std::string doc = read_doc("docs/exr-metadata.md");
    const std::map<std::string, std::string> listed =
        listed_attributes(block_after(doc, "## A default render"));
    DefaultRender run;
    const ImageData img = read_image(run.dir / "cornell-box.exr");
    // Every candela attribute of the file is listed, and every listed one is in the file.
    std::set<std::string> in_file, in_doc;
    for (const Attribute& a : img.attributes)
        if (a.name.rfind("candela:", 0) == 0) in_file.insert(a.name);
    for (const auto& [name, value] : listed)
        if (name.rfind("candela:", 0) == 0) in_doc.insert(name);
    CHECK(in_file == in_doc);
    for (const char* standard : {"chromaticities", "Software", "worldToCamera", "worldToNDC"}) {
        INFO(standard);
        CHECK(listed.count(standard) == 1);
        CHECK(img.attribute(standard) != nullptr);
    }
    // The settings' values are the defaults'; what depends on the run (time, samples taken, the
    // largest sample index a pixel used, the command and paths, the frame's size) is not compared.
    const std::set<std::string> of_the_run = {"candela:command_line", "candela:render_seconds",
                                              "candela:samples", "candela:sample_end",
                                              "candela:scene"};
    for (const Attribute& a : img.attributes) {
        if (!in_doc.count(a.name) || of_the_run.count(a.name)) continue;
        INFO(a.name);
        CHECK(listed.at(a.name) == listed_value(a));
    }
    // The channels listed are the file's.
    const std::regex channels("channel list: ([^\n]*)");
    std::smatch m;
    const std::string listing = block_after(doc, "## A default render");
    REQUIRE(std::regex_search(listing, m, channels));
    std::set<std::string> doc_channels,
        file_channels(img.channel_names.begin(), img.channel_names.end());
    std::stringstream list(m[1].str());
    for (std::string c; std::getline(list, c, ',');)
        doc_channels.insert(c.substr(c.find_first_not_of(' ')));
    CHECK(doc_channels == file_channels);
}
