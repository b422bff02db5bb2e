// `--help` that fits a terminal: render's options in topic groups, every line within the width,
// the top-level help naming `help` and the `candela SCENE.dae` form; and the bash completion
// written from the same option table.
#include "app_support.h"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

using namespace candela::test;

namespace {

/// The headings `render --help` groups its options under, in the order it shows them.
const std::vector<std::string> kRenderGroups = {"Input and output",
                                                "Sampling",
                                                "Light transport",
                                                "Camera",
                                                "EXR",
                                                "8-bit images",
                                                "Checkpoints and resuming",
                                                "Ray traversal",
                                                "Running and diagnostics"};

/// `candela ARGS` with $COLUMNS set to `columns` (stdout is a pipe, so $COLUMNS decides).
Result help_at(const std::vector<std::string>& args, int columns) {
    ::setenv("COLUMNS", std::to_string(columns).c_str(), 1);
    Result r = run_candela(args);
    ::unsetenv("COLUMNS");
    return r;
}

/// Each option line's names ("-s" and "--spp" of "  -s,--spp UINT ...") with the heading it is
/// under.
std::map<std::string, std::string> heading_of_flags(const std::string& help) {
    std::map<std::string, std::string> out;
    std::string heading;
    for (const std::string& line : lines_of(help)) {
        if (!line.empty() && line[0] != ' ' && line.back() == ':') heading = line;
        if (line.rfind("  -", 0) != 0) continue;
        std::istringstream names(line.substr(2, line.find(' ', 2) - 2));
        for (std::string name; std::getline(names, name, ',');)
            out[name] = heading;
    }
    return out;
}

/// Runs `script` with bash; returns its stdout.
std::string bash_output(const TempDir& dir, const std::string& script) {
    {
        std::ofstream f(dir / "run.sh");
        f << script;
    }
    const std::string out = dir / "out.txt";
    REQUIRE(std::system(("bash '" + (dir / "run.sh") + "' > '" + out + "' 2>&1").c_str()) == 0);
    return read_text(out);
}

/// What the completion offers for the words of a command line (the last one being completed).
std::string completions(const TempDir& dir, const std::string& words) {
    return bash_output(dir, "source '" + (dir / "candela.bash") + "'\nCOMP_WORDS=(" + words +
                                ")\nCOMP_CWORD=$((${#COMP_WORDS[@]} - 1))\n_candela\n"
                                "printf '%s\\n' \"${COMPREPLY[@]}\"\n");
}

} // namespace

TEST_CASE("help: render --help fits 80 columns, every option under its topic's heading",
          "[app][help]") {
    const Result h = help_at({"render", "--help"}, 80);
    REQUIRE(h.status == 0);
    for (const std::string& line : lines_of(h.out)) {
        INFO(line);
        CHECK(line.size() <= 80u);
    }
    std::size_t last = 0;
    for (const std::string& g : kRenderGroups) {
        INFO(g);
        const std::size_t at = h.out.find("\n" + g + ":\n");
        CHECK(at != std::string::npos);
        CHECK(at > last); // in the table's order
        last = at;
    }
    const std::set<std::string> headings(kRenderGroups.begin(), kRenderGroups.end());
    const std::map<std::string, std::string> under = heading_of_flags(h.out);
    CHECK(under.size() >= 50u);
    for (const auto& [flag, heading] : under) {
        INFO(flag << " is under '" << heading << "'");
        CHECK(headings.count(heading.substr(0, heading.size() - 1)) == 1);
    }
}

TEST_CASE("help: every command's --help follows the terminal's width", "[app][help]") {
    for (const char* cmd : {"render", "info", "check", "bench", "converge", "merge", "compare",
                            "probe", "completion"}) {
        for (int columns : {60, 100}) {
            const Result h = help_at({cmd, "--help"}, columns);
            REQUIRE(h.status == 0);
            std::size_t widest = 0;
            for (const std::string& line : lines_of(h.out))
                widest = std::max(widest, line.size());
            INFO(cmd << " at " << columns << " columns:\n" << h.out);
            CHECK(widest <= std::size_t(columns));
        }
    }
    // Wider terminals get longer lines: the text is wrapped to the width, not to a fixed one.
    std::size_t widest = 0;
    for (const std::string& line : lines_of(help_at({"render", "--help"}, 140).out))
        widest = std::max(widest, line.size());
    CHECK(widest > 100u);
}

TEST_CASE("help: the top-level help lists help and shows the SCENE.dae form", "[app][help]") {
    const Result h = help_at({"--help"}, 80);
    REQUIRE(h.status == 0);
    CHECK_THAT(h.out, Catch::Contains("candela SCENE.dae [FLAGS]"));
    const std::regex command("^  (help|completion|render) ");
    std::set<std::string> listed;
    for (const std::string& line : lines_of(h.out)) {
        std::smatch m;
        if (std::regex_search(line, m, command)) listed.insert(m[1].str());
    }
    CHECK(listed == std::set<std::string>{"completion", "help", "render"});
    // `candela help` is the same page.
    CHECK(run_candela({"help"}).out == run_candela({"--help"}).out);
}

TEST_CASE("completion: the bash script completes every command and every render flag",
          "[app][help]") {
    const Result c = run_candela({"completion", "bash"});
    REQUIRE(c.status == 0);
    TempDir dir("completion");
    {
        std::ofstream f(dir / "candela.bash");
        f << c.out;
    }
    // bash accepts it.
    REQUIRE(std::system(("bash -n '" + (dir / "candela.bash") + "'").c_str()) == 0);
    // The script the build wrote, and that cmake --install installs, is this one.
    CHECK(read_text(CANDELA_COMPLETION) == c.out);

    // Every command --help lists is completed from its first letters.
    const Result top = run_candela({"--help"});
    const std::regex command("^  ([a-z]+) ");
    std::set<std::string> commands;
    bool in_list = false;
    for (const std::string& line : lines_of(top.out)) {
        if (!line.empty() && line[0] != ' ') in_list = line == "Subcommands:";
        std::smatch m;
        if (in_list && std::regex_search(line, m, command)) commands.insert(m[1].str());
    }
    CHECK(commands.size() >= 10u);
    for (const std::string& cmd : commands) {
        INFO(cmd);
        CHECK_THAT(completions(dir, "candela " + cmd.substr(0, cmd.size() - 1)),
                   Catch::Contains(cmd + "\n"));
    }
    // Every render flag is offered after `candela render`, and after the CS184 order.
    const std::string all = completions(dir, "candela render -");
    const std::string cs184 = completions(dir, "candela -t 1 -");
    for (const auto& [flag, heading] : heading_of_flags(run_candela({"render", "--help"}).out)) {
        INFO(flag);
        CHECK_THAT(all, Catch::Contains("\n" + flag + "\n") || Catch::StartsWith(flag + "\n"));
        CHECK_THAT(cs184, Catch::Contains("\n" + flag + "\n") || Catch::StartsWith(flag + "\n"));
    }
    CHECK(completions(dir, "candela render --sp") == "--spp\n");
    // After a flag that takes a number nothing is offered; after -f, file names.
    CHECK(completions(dir, "candela render -s ''") == "\n");
    CHECK_THAT(completions(dir, "candela render -f " + (dir / "cand")),
               Catch::Contains("candela.bash"));
    // An unknown shell is a usage error.
    check_one_line(run_candela({"completion", "zsh"}), 2, "bash");
}
