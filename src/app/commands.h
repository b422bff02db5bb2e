#pragma once
// The candela subcommands. Each registers its options on the main CLI11 app and returns the
// process exit status when run; main() maps candela::Error kinds to statuses.
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

/// The manual page (roff) made of the --help texts of `app` and its subcommands.
std::string man_page(const CLI::App& app);

} // namespace candela::app
