#pragma once
// Small string helpers shared by the command-line and configuration parsers and the JSON reports.
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

/// `s` as the inside of a JSON string: quotes and backslashes escaped, control characters (which
/// no name or message of candela's needs) replaced by spaces.
inline std::string json_escape(const std::string& s) {
    std::string o;
    o.reserve(s.size());
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\';
        o += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    }
    return o;
}

} // namespace candela
