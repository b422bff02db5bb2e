// The image module names the libraries of cmake/image_module_link_order.txt first among its
// needed libraries (cmake/ImageModuleLinkOrder.cmake), so that the dynamic loader's search list
// starts with the libraries most symbols bind to. These tests load the built module and
// OpenImageIO alone with the dynamic loader itself (every relocation done, as `ldd -r` does,
// with LD_DEBUG reporting each binding) and check that the order shortens the search, loads no
// library OpenImageIO does not, and moves no strong symbol to another library.
#include "../support/temp_dir.h"

#include <catch2/catch.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// The list's purpose is a shorter search: with the 45 libraries listed for Debian bookworm, the
/// mean position (in the search list) of the library a binding ends at is 0.32 of its value in
/// OpenImageIO's own order (a module without the list: 0.99). A list that no longer halves it
/// is stale (other libraries receive the bindings now): run tools/image_module_link_order.py.
constexpr double kMaxSearchRatio = 0.5;

std::string read_pipe(const std::string& cmd) {
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    REQUIRE(pipe);
    std::string out;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe.get()))
        out += buf.data();
    return out;
}

/// The canonical path of a file (remembered: the loader names a few hundred files 170 000 times).
const std::string& real(const std::string& p) {
    static std::map<std::string, std::string> known;
    auto it = known.find(p);
    if (it == known.end()) {
        std::error_code ec;
        const fs::path r = fs::canonical(p, ec);
        it = known.emplace(p, ec ? p : r.string()).first;
    }
    return it->second;
}

/// One load of a library by the dynamic loader.
struct Load {
    std::vector<std::string> sonames; ///< the loaded libraries, in search order, root left out
    std::vector<std::string> paths;   ///< their files (canonical), same order
    std::map<std::pair<std::string, std::string>, std::string> bindings; ///< (file, symbol) -> file
};

/// The dynamic loader the library is loaded by (its ld-linux line in `ldd`).
std::string dynamic_loader(const std::string& library) {
    std::istringstream lines(read_pipe("ldd '" + library + "' 2>/dev/null"));
    const std::regex loader(R"(^\s*(/\S*ld-linux\S*)\s)");
    std::string line;
    std::smatch m;
    while (std::getline(lines, line))
        if (std::regex_search(line, m, loader)) return m[1];
    return {};
}

Load trace(const std::string& library, const candela::test::TempDir& dir) {
    const std::string loader = dynamic_loader(library);
    REQUIRE_FALSE(loader.empty());
    const std::string prefix = dir / "debug";
    const std::string out = read_pipe("LD_TRACE_LOADED_OBJECTS=1 LD_WARN=yes LD_BIND_NOW=yes "
                                      "LD_DEBUG=bindings LD_DEBUG_OUTPUT='" +
                                      prefix + "' '" + loader + "' '" + library + "'");
    Load load;
    std::istringstream lines(out);
    const std::regex listed(R"(^\s*(\S+) => (\S+) \()");
    std::string line;
    std::smatch m;
    while (std::getline(lines, line))
        if (std::regex_search(line, m, listed)) {
            load.sonames.push_back(m[1]);
            load.paths.push_back(real(m[2]));
        }
    // "binding file F [n] to T [n]: normal symbol `S'" (std::regex is too slow for 170 000).
    const std::string file_tag = "binding file ", to_tag = " to ", sym_tag = ": normal symbol `";
    for (const auto& entry : fs::directory_iterator(dir.path)) {
        std::ifstream in(entry.path());
        while (std::getline(in, line)) {
            const std::size_t f = line.find(file_tag);
            if (f == std::string::npos) continue;
            const std::size_t f0 = f + file_tag.size(), f1 = line.find(' ', f0);
            const std::size_t to = line.find(to_tag, f1);
            if (f1 == std::string::npos || to == std::string::npos) continue;
            const std::size_t t0 = to + to_tag.size(), t1 = line.find(' ', t0);
            const std::size_t s0 = line.find(sym_tag, t1);
            if (t1 == std::string::npos || s0 == std::string::npos) continue;
            const std::size_t s1 = line.find('\'', s0 + sym_tag.size());
            load.bindings[{real(line.substr(f0, f1 - f0)),
                           line.substr(s0 + sym_tag.size(), s1 - s0 - sym_tag.size())}] =
                real(line.substr(t0, t1 - t0));
        }
        fs::remove(entry.path());
    }
    return load;
}

/// The dynamic symbols `library` defines weakly or as unique (vague linkage: C++ templates,
/// inline functions' statics, type information); any definition of one serves every user.
std::set<std::string> weak_symbols(const std::string& library) {
    std::istringstream lines(read_pipe("nm -D --defined-only -P '" + library + "' 2>/dev/null"));
    std::set<std::string> out;
    std::string line;
    while (std::getline(lines, line)) {
        std::istringstream fields(line);
        std::string name, type;
        if (!(fields >> name >> type) || type.size() != 1) continue;
        if (std::string("WVwvu").find(type[0]) != std::string::npos)
            out.insert(name.substr(0, name.find('@')));
    }
    return out;
}

/// Mean position in `load`'s search list of the library each binding ends at.
double mean_search_position(const Load& load) {
    std::map<std::string, std::size_t> position;
    for (std::size_t i = 0; i < load.paths.size(); ++i)
        position.emplace(load.paths[i], i + 1);
    double sum = 0;
    std::size_t n = 0;
    for (const auto& b : load.bindings) {
        const auto it = position.find(b.second);
        sum += it == position.end() ? 0.0 : double(it->second); // 0: the root itself
        ++n;
    }
    return n ? sum / double(n) : 0.0;
}

} // namespace

TEST_CASE("image module: its link order shortens the loader's search and moves no strong symbol",
          "[structure]") {
    const std::string oiio = CANDELA_OIIO_LIBRARY;
    if (oiio.empty()) {
        WARN("SKIPPED: the build found no libOpenImageIO.so to compare the image module with");
        return;
    }
    candela::test::TempDir dir("image-module-link");
    const Load module = trace(CANDELA_IMAGE_MODULE, dir);
    const Load alone = trace(oiio, dir);
    REQUIRE(alone.bindings.size() > 1000);
    REQUIRE(module.bindings.size() > 1000);

    // The module loads OpenImageIO's libraries and no other.
    std::set<std::string> expected(alone.paths.begin(), alone.paths.end());
    expected.insert(real(oiio));
    CHECK(std::set<std::string>(module.paths.begin(), module.paths.end()) == expected);

    // Its search list starts with the listed libraries OpenImageIO loads, in the list's order.
    std::set<std::string> loaded(alone.sonames.begin(), alone.sonames.end());
    const std::string oiio_soname = fs::path(real(oiio)).filename().string();
    std::vector<std::string> first;
    std::ifstream list(std::string(CANDELA_SOURCE_DIR) + "/cmake/image_module_link_order.txt");
    REQUIRE(list);
    std::string name;
    while (std::getline(list, name))
        if (!name.empty() && name[0] != '#' &&
            (loaded.count(name) || oiio_soname.rfind(name, 0) == 0))
            first.push_back(name);
    REQUIRE(first.size() >= 10);
    REQUIRE(module.sonames.size() >= first.size());
    CHECK(std::vector<std::string>(module.sonames.begin(), module.sonames.begin() + first.size()) ==
          first);

    // Shorter walks: the libraries most bindings end at come early.
    const double ratio = mean_search_position(module) / mean_search_position(alone);
    INFO("mean search position, module / OpenImageIO alone: " << ratio);
    CHECK(ratio < kMaxSearchRatio);

    // Every binding that ends elsewhere than in OpenImageIO's own order is of a symbol both
    // libraries define weakly or as unique.
    std::map<std::string, std::set<std::string>> weak;
    auto is_weak = [&](const std::string& library, const std::string& symbol) {
        auto it = weak.find(library);
        if (it == weak.end()) it = weak.emplace(library, weak_symbols(library)).first;
        return it->second.count(symbol) > 0;
    };
    std::size_t moved = 0;
    std::vector<std::string> strong_moved;
    for (const auto& b : alone.bindings) {
        const auto it = module.bindings.find(b.first);
        if (it == module.bindings.end() || it->second == b.second) continue;
        ++moved;
        const std::string& symbol = b.first.second;
        if (!is_weak(b.second, symbol) || !is_weak(it->second, symbol))
            strong_moved.push_back(b.first.first + ": " + symbol + " from " + b.second + " to " +
                                   it->second);
    }
    INFO("bindings of weak or unique symbols that end in another library: " << moved);
    for (std::size_t i = 0; i < strong_moved.size() && i < 10; ++i)
        UNSCOPED_INFO(strong_moved[i]);
    CHECK(strong_moved.empty());
}
