// The Error type, the lines it is shown in, and the failed-check reporter of util/check.h.
#include "candela/util/error.h"
#include "candela/util/check.h"
#include "candela/util/log.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

namespace candela {

Error::Error(ErrorKind kind, std::string message)
    : std::runtime_error(message), kind_(kind), message_(std::move(message)) {}

Error::Error(ErrorKind kind, SourceLoc where, std::string message)
    : std::runtime_error(located_text(where, message)), kind_(kind), where_(std::move(where)),
      message_(std::move(message)) {}

std::string located_text(const std::optional<SourceLoc>& where, const std::string& message) {
    return where ? where->str() + ": " + message : message;
}

std::string error_line(const Error& e) {
    return "candela: error: " + located_text(e.where(), e.message());
}

std::string warning_line(const Error& e) {
    return warning_text(located_text(e.where(), e.message()));
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
