#pragma once
// The candela subcommands. Each registers its options on the main CLI11 app and returns the
// process exit status when run; main() maps candela::Error kinds to statuses.
#include <cstdio>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace candela::app {

/// Records the process arguments; `render` keeps its own in checkpoints.
void set_command_line(int argc, char** argv);
/// The arguments after the first occurrence of `subcommand`.
std::vector<std::string> command_args(const std::string& subcommand);
/// The whole command line as one shell-quoted string (`candela render ...`), for metadata.
std::string command_line_text();
/// The `Software` every written image names: "candela VERSION (COMMIT)".
std::string software_text();

/// Each `add_*` declares a subcommand; its callback runs the command and stores the exit
/// status in `*status`.
void add_render_command(CLI::App& app, int* status);
void add_info_command(CLI::App& app, int* status);
void add_check_command(CLI::App& app, int* status);
void add_bench_command(CLI::App& app, int* status);
void add_converge_command(CLI::App& app, int* status);
void add_merge_command(CLI::App& app, int* status);
void add_compare_command(CLI::App& app, int* status);
void add_probe_command(CLI::App& app, int* status);

void add_help_command(CLI::App& app);
void add_completion_command(CLI::App& app, int* status);

/// A heading of `render --help` and the flags listed under it.
struct OptionGroup {
    std::string heading;
    std::vector<std::string> flags; ///< each option's first long flag (else its short one)
};
/// The render options' groups, in the order --help shows them (help.cpp holds the table).
const std::vector<OptionGroup>& render_option_groups();
/// The heading of a render option that no group lists.
inline constexpr const char* kUngrouped = "Not yet grouped";
/// Puts each of the render command's options in its group of render_option_groups().
void group_render_options(CLI::App& render);
/// Gives `app` (and the subcommands added after) candela's help layout: groups in the table's
/// order, the top-level usage with the `candela SCENE.dae` form.
void use_help_formatter(CLI::App& app);
/// Columns of the terminal on stdout, else $COLUMNS, else 80 (never fewer than 50).
int help_columns();
/// `text` with every line longer than `width` broken at spaces, continuation lines indented
/// under an option's description.
std::string wrap_help(const std::string& text, std::size_t width);
/// Prints `help` to `to`, wrapped to help_columns(); returns 0.
int print_help(const std::string& help, std::FILE* to);

/// The bash completion script of `app`: its commands and each command's flags.
std::string bash_completion(const CLI::App& app);

/// The manual page (roff) made of the --help texts of `app` and its subcommands.
std::string man_page(const CLI::App& app);

} // namespace candela::app
