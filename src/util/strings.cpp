// The string helpers of util/strings.h.
#include "candela/util/strings.h"
#include "candela/util/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace candela {

std::string path_extension(const std::string& path) {
    std::size_t slash = path.find_last_of('/');
    std::size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

std::string shell_quote(const std::string& s) {
    if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789-_./=:,+@%") == std::string::npos)
        return s;
    std::string out = "'";
    for (char c : s)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

std::string json_quote(const std::string& s) {
    return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

double printed_number(double v, const char* format) {
    return std::strtod(fmt::format(fmt::runtime(format), v).c_str(), nullptr);
}

std::uint64_t parse_memory_size(const std::string& text, const std::string& flag) {
    const std::string what = flag + ": '" + text + "' ";
    std::size_t i = 0;
    while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.'))
        ++i;
    if (i == 0) throw Error(ErrorKind::Usage, what + "is not a size (e.g. 8G, 512M)");
    double v = std::strtod(text.substr(0, i).c_str(), nullptr);
    std::string unit = text.substr(i);
    for (char& c : unit)
        c = char(std::toupper(static_cast<unsigned char>(c)));
    double scale = 1.0;
    if (unit.empty() || unit == "B")
        scale = 1.0;
    else if (unit == "K" || unit == "KB" || unit == "KIB")
        scale = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MIB")
        scale = 1024.0 * 1024.0;
    else if (unit == "G" || unit == "GB" || unit == "GIB")
        scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "T" || unit == "TB" || unit == "TIB")
        scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    else
        throw Error(ErrorKind::Usage, what + "has an unknown unit");
    double bytes = v * scale;
    if (!std::isfinite(bytes) || bytes < 1.0 || bytes > 1.8e19)
        throw Error(ErrorKind::Usage, what + "is out of range");
    return std::uint64_t(bytes);
}

std::string format_bytes(std::uint64_t b) {
    constexpr std::uint64_t kGiB = std::uint64_t(1) << 30;
    constexpr std::uint64_t kMiB = std::uint64_t(1) << 20;
    if (b >= kGiB) return fmt::format("{:.1f} GiB", double(b) / double(kGiB));
    if (b >= kMiB) return fmt::format("{:.1f} MiB", double(b) / double(kMiB));
    return fmt::format("{} bytes", b);
}

} // namespace candela
