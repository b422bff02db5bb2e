// No function of the render core (src/render/*.cpp) is longer than kMaxFunctionLines: a long
// function there is a loop whose steps have not been named. The sources are read as text: the
// comments, string literals and preprocessor lines are blanked, then every brace that opens a
// function body is matched to its closing brace and the lines from one to the other counted.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// The longest a function of src/render may be, from the line of its body's opening brace to
/// the line of its closing brace, both counted.
constexpr int kMaxFunctionLines = 80;

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// `text` with comments, string and character literals and preprocessor lines (with their
/// continuations) replaced by spaces, every newline kept, so braces in them are not counted and
/// line numbers do not move.
std::string code_only(const std::string& text) {
    std::string out = text;
    enum class In { Code, LineComment, BlockComment, String, Char, Directive } in = In::Code;
    bool line_start = true; // only blanks so far on this line
    auto blank = [&](std::size_t k) {
        if (k < out.size() && out[k] != '\n') out[k] = ' ';
    };
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        const char next = i + 1 < text.size() ? text[i + 1] : '\0';
        const bool digit_before = i > 0 && std::isxdigit(static_cast<unsigned char>(text[i - 1]));
        switch (in) {
        case In::Code:
            if (c == '/' && next == '/') {
                in = In::LineComment;
            } else if (c == '/' && next == '*') {
                in = In::BlockComment;
                blank(i++);
            } else if (c == '"') {
                in = In::String;
            } else if (c == '\'' && !digit_before) { // not a digit separator (1'000)
                in = In::Char;
            } else if (c == '#' && line_start) {
                in = In::Directive;
            } else {
                break;
            }
            blank(i);
            break;
        case In::LineComment:
            if (c == '\n') in = In::Code;
            blank(i);
            break;
        case In::BlockComment:
            if (c == '*' && next == '/') {
                in = In::Code;
                blank(i++);
            }
            blank(i);
            break;
        case In::String:
        case In::Char:
            if (c == '\\')
                blank(i++);
            else if (c == (in == In::String ? '"' : '\''))
                in = In::Code;
            blank(i);
            break;
        case In::Directive:
            if (c == '\n' && !(i > 0 && text[i - 1] == '\\')) in = In::Code;
            blank(i);
            break;
        }
        if (text[i] == '\n')
            line_start = true;
        else if (!std::isspace(static_cast<unsigned char>(text[i])))
            line_start = false;
    }
    return out;
}

/// Whether `head`, the code between the previous ';', '{' or '}' and a '{' outside any
/// function, declares a function whose body that brace opens: it has a parameter list and is
/// not a namespace, class, struct, union or enum (a template's parameters aside).
bool opens_function(std::string head) {
    static const std::regex template_params(R"(template\s*<[^{;]*?>)");
    static const std::regex type_keyword(R"(\b(namespace|class|struct|union|enum)\b)");
    head = std::regex_replace(head, template_params, " ");
    const std::size_t paren = head.find('(');
    if (paren == std::string::npos) return false;
    return !std::regex_search(head.substr(0, paren), type_keyword);
}

/// The name a function head declares: the last word before its parameter list.
std::string function_name(const std::string& head) {
    static const std::regex name(R"(([A-Za-z_~][A-Za-z_0-9:~<>]*)\s*\()");
    std::smatch m;
    return std::regex_search(head, m, name) ? m[1].str() : "(unnamed)";
}

struct FunctionSpan {
    std::string name;
    int first_line; ///< the line of the body's opening brace (1-based)
    int lines;      ///< from that line to the closing brace's, both counted
};

/// Every function body of a C++ source, outermost only: a lambda or a local class inside a
/// function belongs to that function's lines.
std::vector<FunctionSpan> function_spans(const std::string& source) {
    const std::string code = code_only(source);
    std::vector<FunctionSpan> out;
    int line = 1;
    int depth = 0;           // braces open
    int function_depth = -1; // the depth at which the current function's body opened, or -1
    std::size_t head_begin = 0;
    FunctionSpan current;
    for (std::size_t i = 0; i < code.size(); ++i) {
        const char c = code[i];
        if (c == '\n') ++line;
        if (c == '{') {
            if (function_depth < 0) {
                const std::string head = code.substr(head_begin, i - head_begin);
                if (opens_function(head)) {
                    function_depth = depth;
                    current = {function_name(head), line, 0};
                }
            }
            ++depth;
            head_begin = i + 1;
        } else if (c == '}') {
            --depth;
            if (depth == function_depth) {
                current.lines = line - current.first_line + 1;
                out.push_back(current);
                function_depth = -1;
            }
            head_begin = i + 1;
        } else if (c == ';') {
            head_begin = i + 1;
        }
    }
    return out;
}

} // namespace

TEST_CASE("function length: the scanner measures function bodies and nothing else",
          "[structure][quick]") {
    // An 81-line function (its braces included) beside what must not be taken for one: a
    // namespace, a struct with a one-line member, a template, braces in comments and strings,
    // a lambda inside the function, a directive with a brace.
    std::string body;
    for (int k = 0; k < 79; ++k)
        body += "    x += " + std::to_string(k) + "; // }\n";
    const std::string source = "#define OPEN {\n"
                               "namespace a {\n"
                               "struct S { int f() const { return 1; } };\n"
                               "template <class T> struct U { T t; };\n"
                               "/* int g() { */\n"
                               "int long_one(int x) {\n" +
                               body +
                               "}\n"
                               "const char* s = \"{ (\";\n"
                               "template <class T> T h(T v) { auto l = [](int y) { return y; };"
                               " return v + l(1); }\n"
                               "}\n";
    const std::vector<FunctionSpan> spans = function_spans(source);
    REQUIRE(spans.size() == 3);
    CHECK(spans[0].name == "f");
    CHECK(spans[0].lines == 1);
    CHECK(spans[1].name == "long_one");
    CHECK(spans[1].first_line == 6);
    CHECK(spans[1].lines == 81);
    CHECK(spans[2].name == "h");
    CHECK(spans[2].lines == 1);
}

TEST_CASE("function length: no function in src/render is longer than 80 lines",
          "[structure][quick]") {
    const fs::path dir = fs::path(CANDELA_SOURCE_DIR) / "src" / "render";
    std::vector<std::string> long_ones;
    std::size_t functions = 0, files = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (!entry.is_regular_file() || entry.path().extension() != ".cpp") continue;
        ++files;
        for (const FunctionSpan& f : function_spans(read_text(entry.path()))) {
            ++functions;
            if (f.lines > kMaxFunctionLines)
                long_ones.push_back(entry.path().filename().string() + ":" +
                                    std::to_string(f.first_line) + " " + f.name + ": " +
                                    std::to_string(f.lines) + " lines");
        }
    }
    // The scan found the render core's functions: a wrong directory would pass vacuously.
    CHECK(files >= 5);
    CHECK(functions > 100);
    for (const std::string& f : long_ones)
        UNSCOPED_INFO(f);
    CHECK(long_ones.empty());
}
