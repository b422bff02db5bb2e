#pragma once
// Small string helpers shared by the command-line and configuration parsers and the JSON reports.
#include <charconv>
#include <cstdlib>
#include <string>
#include <vector>

namespace candela {

/// The pieces of `s` between occurrences of `sep`, in order, empty pieces included:
/// split_string("a,,b", ',') is {"a", "", "b"}, split_string("", ',') is {""}.
inline std::vector<std::string> split_string(const std::string& s, char sep) {
    std::vector<std::string> parts;
    std::size_t begin = 0;
    for (;;) {
        const std::size_t end = s.find(sep, begin);
        parts.push_back(s.substr(begin, end == std::string::npos ? end : end - begin));
        if (end == std::string::npos) return parts;
        begin = end + 1;
    }
}

/// "1 sphere", "22 triangles": a count and its noun, plural when the count is not 1.
inline std::string count_of(std::size_t n, const std::string& noun) {
    return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

/// The double nearest to the shortest decimal that reads back as `v`: 1.6f gives 1.6, not
/// 1.600000023841858, so a JSON writer (which prints doubles) shows floats as written. Infinities
/// and NaN pass through.
inline double float_for_json(float v) {
    char buf[32];
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf - 1, v);
    *r.ptr = '\0';
    return std::strtod(buf, nullptr);
}

} // namespace candela
