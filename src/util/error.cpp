#include "candela/util/error.h"
#include "candela/util/check.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace candela {

std::string user_error_line(const std::string& message) {
    std::string m = message;
    while (!m.empty() && (m.back() == '\n' || m.back() == '\r'))
        m.pop_back();
    // "candela: " or "candela SUBCOMMAND: " in front of the message.
    if (m.rfind("candela", 0) == 0) {
        std::size_t colon = m.find(": ");
        std::size_t space = m.find(' ');
        bool prefix =
            colon != std::string::npos &&
            (colon == 7 || (space == 7 && m.find(' ', 8) > colon &&
                            m.find_first_not_of("abcdefghijklmnopqrstuvwxyz", 8) == colon));
        if (prefix) m = m.substr(colon + 2);
    }
    const std::string tag = "error: ";
    if (m.rfind(tag, 0) == 0) {
        m = m.substr(tag.size());
    } else if (m.rfind("internal error: ", 0) != 0) {
        std::size_t p = m.find(": " + tag);
        if (p != std::string::npos) m = m.substr(0, p) + ": " + m.substr(p + 2 + tag.size());
    }
    return "candela: error: " + m;
}

std::string file_read_failure(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return "it is a directory";
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return std::strerror(errno);
    std::fclose(f);
    return "";
}

namespace detail {

void check_failed(const char* file, int line, const char* condition, const std::string& message) {
    // Only the file name: the build directory says nothing to a user reporting the failure.
    std::string name = file;
    const std::size_t slash = name.find_last_of('/');
    if (slash != std::string::npos) name = name.substr(slash + 1);
    throw Error(ErrorKind::Internal, "internal error at " + name + ":" + std::to_string(line) +
                                         ": " + message + " (" + condition + ")");
}

} // namespace detail

} // namespace candela
