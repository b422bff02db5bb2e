// The command line every subcommand shares (the log options, the exit statuses) and the
// render's argument record: its default paths and its parse from a plain argument list.
#include "candela/app/cli.h"
#include "cli_support.h"

#include "candela/render/adaptive.h"
#include "candela/render/checkpoint.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace candela {

namespace cli {

namespace fs = std::filesystem;

void usage(const std::string& what) {
    throw Error(ErrorKind::Usage, what);
}

std::string absolute_path(const std::string& p) {
    if (p.empty()) return p;
    std::error_code ec;
    fs::path a = fs::absolute(p, ec);
    if (ec) return p;
    return a.lexically_normal().string();
}

} // namespace cli

// ---------------------------------------------------------------------------------------------
// Shared by every subcommand
// ---------------------------------------------------------------------------------------------

void add_log_options(CLI::App& app, LogArgs& a) {
    app.add_flag("-q,--quiet", a.quiet,
                 "Only errors and warnings on stderr (no progress, summary or notes)");
    app.add_flag("-v,--verbose", a.verbose,
                 "Also notes about the scene and what a render leaves out");
    app.add_option("--log-level", a.level,
                   "error, warning, info (the default: progress, summary, files written) or "
                   "verbose; -q is warning, -v is verbose");
}

LogLevel log_level_of(const LogArgs& a) {
    const int given = (a.quiet ? 1 : 0) + (a.verbose ? 1 : 0) + (a.level.empty() ? 0 : 1);
    if (given > 1) cli::usage("give only one of -q/--quiet, -v/--verbose and --log-level");
    if (!a.level.empty()) return parse_log_level(a.level);
    if (a.quiet) return LogLevel::Warning;
    if (a.verbose) return LogLevel::Verbose;
    return LogLevel::Info;
}

const char* exit_status_help() {
    return "Exit status:\n"
           "  0   success\n"
           "  2   usage error (bad flag, value or combination), refused before any work\n"
           "  3   an input file (scene, camera, checkpoint) is malformed or unsupported\n"
           "  4   a file could not be read or written\n"
           "  5   interrupted (SIGINT/SIGTERM); the image holds the finished samples\n"
           "  70  internal error";
}

// ---------------------------------------------------------------------------------------------
// render
// ---------------------------------------------------------------------------------------------

std::string default_output_path(const std::string& scene_path) {
    std::size_t slash = scene_path.find_last_of('/');
    std::string base = slash == std::string::npos ? scene_path : scene_path.substr(slash + 1);
    std::size_t dot = base.find_last_of('.');
    if (dot != std::string::npos && dot > 0) base = base.substr(0, dot);
    return base + ".exr";
}

std::string RenderArgs::preview_path() const {
    if (!preview || output_kind != OutputKind::Exr) return "";
    return output.substr(0, output.size() - path_extension(output).size()) + ".png";
}

std::string RenderArgs::rate_path() const {
    if (!make_pass_policy(settings)->spreads_samples()) return "";
    if (output_kind == OutputKind::Ldr) return rate_image_path(output);
    const std::string p = preview_path();
    return p.empty() ? "" : rate_image_path(p);
}

std::string RenderArgs::checkpoint_path() const {
    return checkpoint.empty() ? checkpoint_path_for(output) : checkpoint;
}

RenderArgs parse_render_command_line(const std::vector<std::string>& argv) {
    RenderArgs args;
    CLI::App app{"render"};
    add_render_options(app, args);
    std::vector<std::string> reversed(argv.rbegin(), argv.rend());
    try {
        app.parse(reversed);
    } catch (const CLI::ParseError& e) {
        throw Error(ErrorKind::Usage, describe_parse_error(app, e));
    }
    record_given_options(app, args);
    finalize_render_args(args);
    return args;
}

} // namespace candela
