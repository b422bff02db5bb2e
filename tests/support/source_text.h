#pragma once
// The text of a file of the source tree, for the structure tests that read it.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace candela::test {

/// The whole file at `p`, bytes as they are ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

} // namespace candela::test
