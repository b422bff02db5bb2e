// The string helpers of util/strings.h: one home, each checked on the cases its callers meet.
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

using namespace candela;

TEST_CASE("strings: split_string keeps empty pieces", "[strings][quick]") {
    CHECK(split_string("a,,b", ',') == std::vector<std::string>{"a", "", "b"});
    CHECK(split_string("", ',') == std::vector<std::string>{""});
    CHECK(split_string("a,", ',') == std::vector<std::string>{"a", ""});
}

TEST_CASE("strings: count_of is plural unless one", "[strings][quick]") {
    CHECK(count_of(0, "light") == "0 lights");
    CHECK(count_of(1, "sphere") == "1 sphere");
    CHECK(count_of(22, "triangle") == "22 triangles");
}

TEST_CASE("strings: path_extension is the file name's, lower case, with its dot",
          "[strings][quick]") {
    CHECK(path_extension("out/A.EXR") == ".exr");
    CHECK(path_extension("scene.dae") == ".dae");
    CHECK(path_extension("a.tar.gz") == ".gz");
    CHECK(path_extension("noext") == "");
    CHECK(path_extension("dir.d/noext") == ""); // a dot in a directory is no extension
    CHECK(path_extension("") == "");
}

TEST_CASE("strings: shell_quote quotes only what a shell would split or expand",
          "[strings][quick]") {
    CHECK(shell_quote("plain/path-1.exr") == "plain/path-1.exr");
    CHECK(shell_quote("") == "''");
    CHECK(shell_quote("two words") == "'two words'");
    CHECK(shell_quote("it's") == "'it'\\''s'");
    CHECK(shell_quote("$HOME") == "'$HOME'");
}

TEST_CASE("strings: json_quote is a JSON string that reads back", "[strings][quick]") {
    const std::string s = "a \"quoted\"\\path\n\ttab";
    const std::string q = json_quote(s);
    CHECK(q.front() == '"');
    CHECK(q.back() == '"');
    CHECK(nlohmann::json::parse(q).get<std::string>() == s);
    // Bytes that are not UTF-8 are replaced, not a failure.
    CHECK_NOTHROW(nlohmann::json::parse(json_quote(std::string("bad \xff byte"))));
}

TEST_CASE("strings: parse_memory_size reads binary units", "[strings][limits][quick]") {
    CHECK(parse_memory_size("512M", "--max-memory") == 512ull << 20);
    CHECK(parse_memory_size("8G", "--max-memory") == 8ull << 30);
    CHECK(parse_memory_size("8gb", "--max-memory") == 8ull << 30);
    CHECK(parse_memory_size("1.5GiB", "--max-memory") == 3ull << 29);
    CHECK(parse_memory_size("2K", "--max-memory") == 2048u);
    CHECK(parse_memory_size("1000", "--max-memory") == 1000u);
    CHECK(parse_memory_size("1T", "--max-memory") == 1ull << 40);
}

TEST_CASE("strings: parse_memory_size names the flag and the fault", "[strings][limits][quick]") {
    const auto message = [](const std::string& text) {
        try {
            parse_memory_size(text, "--max-memory");
        } catch (const Error& e) {
            CHECK(e.kind() == ErrorKind::Usage);
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    CHECK_THAT(message("lots"), Catch::Contains("--max-memory: 'lots' is not a size"));
    CHECK_THAT(message("8X"), Catch::Contains("--max-memory: '8X' has an unknown unit"));
    CHECK_THAT(message("0"), Catch::Contains("--max-memory: '0' is out of range"));
    CHECK_THAT(message("99999999T"), Catch::Contains("is out of range"));
}

TEST_CASE("strings: format_bytes picks bytes, MiB or GiB", "[strings][quick]") {
    CHECK(format_bytes(0) == "0 bytes");
    CHECK(format_bytes(1023) == "1023 bytes");
    CHECK(format_bytes(1ull << 20) == "1.0 MiB");
    CHECK(format_bytes(3ull << 29) == "1.5 GiB");
}
