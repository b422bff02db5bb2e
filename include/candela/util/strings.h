#pragma once
// Small string helpers shared by the command-line and configuration parsers, the file writers
// and the JSON reports: one home for each (tests/util/strings_test.cpp).
#include <charconv>
#include <cstdint>
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

/// The lower-case extension of the file name in `path`, with its dot: ".exr" for "out/A.EXR",
/// "" when the name has none (a dot in a directory name is not an extension).
std::string path_extension(const std::string& path);

/// `s` as one word of a POSIX shell command: as it is when it needs no quoting, else in single
/// quotes (a quote inside written '\'').
std::string shell_quote(const std::string& s);

/// JSON string literal of `s` (quotes, backslashes and control characters escaped; bytes that
/// are not UTF-8 replaced).
std::string json_quote(const std::string& s);

/// `v` as fmt prints it with `format` (e.g. "{:.6f}"), read back: a JSON writer, which prints
/// the shortest text that reads back, then shows those digits and no noise beyond them.
double printed_number(double v, const char* format);

/// Parses a size like "8G", "512M", "1.5GiB" or "1000000" (bytes; units K, M, G, T with or
/// without B or iB, all binary). Throws Error(Usage) "FLAG: 'TEXT' is not a size (e.g. 8G,
/// 512M)", "... has an unknown unit" or "... is out of range".
std::uint64_t parse_memory_size(const std::string& text, const std::string& flag);

/// "512 bytes", "3.2 MiB", "1.5 GiB".
std::string format_bytes(std::uint64_t bytes);

} // namespace candela
