// candela: scene file -> loader -> Scene -> accelerator -> integrator -> film -> image writer.
// Each subcommand lives in its own cmd_*.cpp; this file only dispatches and chooses the exit
// status (docs/usage.md "Exit status"). Every failure is one line, `candela: error: [FILE:LINE:
// ]what`, made here from the Error (error_line()).
#include "commands.h"

#include "candela/accel/accel.h"
#include "candela/accel/bvh.h"
#include "candela/app/cli.h"
#include "candela/render/output.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

namespace {

/// `candela --version`: everything is fixed at build time or read from the CPU, so printing it
/// loads neither Embree's device nor the image module.
std::string version_text() {
    const std::string embree_isa = candela::embree_default_isa();
    return std::string("candela ") + CANDELA_VERSION + "\ncommit " + CANDELA_GIT_COMMIT +
           "\nbuild " + CANDELA_BUILD_TYPE + "\nembree " + CANDELA_EMBREE_VERSION +
           " (device isa: " + (embree_isa.empty() ? "embree's choice" : embree_isa) + ")" +
           "\nopenimageio " + CANDELA_OIIO_VERSION + " (module " + CANDELA_IMAGE_MODULE_NAME +
           ", loaded on the first image read or write)" + "\nbuiltin bvh kernel " +
           (candela::bvh_cpu_has_avx2() ? "avx2" : "sse2");
}

/// True when `args` (which does not start with a command) is a render's command line: it starts
/// with a scene file, or with a flag other than the dispatcher's own (--help, --version).
bool means_render(const std::vector<std::string>& args) {
    const std::string& first = args.front();
    if (first.empty()) return false;
    if (first[0] == '-') return first != "-h" && first != "--help" && first != "--version";
    std::error_code ec;
    return candela::path_extension(first) == ".dae" || std::filesystem::is_regular_file(first, ec);
}

int usage_error(const std::string& message) {
    fmt::print(stderr, "{}\n",
               candela::error_line(candela::Error(candela::ErrorKind::Usage, message)));
    return static_cast<int>(candela::ErrorKind::Usage);
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"candela " CANDELA_VERSION
                 ": a physically based path tracer for CS184-style COLLADA scenes"};
    app.name("candela");
    app.require_subcommand(1);
    app.set_version_flag("--version", version_text());
    candela::app::use_help_formatter(app); // before the commands, which inherit it
    int status = 0;
    candela::app::set_command_line(argc, argv);
    candela::app::add_render_command(app, &status);
    candela::app::add_info_command(app, &status);
    candela::app::add_check_command(app, &status);
    candela::app::add_bench_command(app, &status);
    candela::app::add_converge_command(app, &status);
    candela::app::add_merge_command(app, &status);
    candela::app::add_compare_command(app, &status);
    candela::app::add_probe_command(app, &status);
    candela::app::add_help_command(app);
    candela::app::add_completion_command(app, &status);
    const std::string footer = std::string("\n") + candela::exit_status_help();
    app.footer(
        "\nRun 'candela help COMMAND' (or 'candela COMMAND --help') for a command's flags.\n" +
        std::string(candela::exit_status_help()));
    std::vector<std::string> names;
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
        sub->footer(footer);
        names.push_back(sub->get_name());
    }

    // `candela help [COMMAND]` is `candela [COMMAND] --help`; a mistyped command is named with
    // its nearest spelling before CLI11 sees it.
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.size() == 2 && args[0] == "help" && args[1] == "--man") {
        // The manual page, generated at build time (CMakeLists.txt) from the --help texts.
        std::fputs(candela::app::man_page(app).c_str(), stdout);
        return 0;
    }
    if (!args.empty() && args[0] == "help") {
        if (args.size() > 2) return usage_error("help: give at most one command");
        args.erase(args.begin());
        args.push_back("--help");
    }
    if (args.empty()) {
        candela::app::print_help(app.help(), stderr);
        return usage_error("no command given");
    }
    bool known = false;
    for (const std::string& n : names)
        known |= n == args[0];
    // `candela scene.dae [flags]` and the CS184 order `candela -t 1 -s 16 scene.dae` mean
    // `render`, as in the course's binary, pbrt and Mitsuba.
    if (!known && means_render(args)) {
        args.insert(args.begin(), "render");
        known = true;
    }
    if (args[0].empty() || args[0][0] != '-') {
        if (!known) {
            const std::string near = candela::nearest_name(args[0], names);
            std::string all;
            for (const std::string& n : names)
                all += (all.empty() ? "" : ", ") + n;
            return usage_error(
                "unknown command '" + args[0] + "'" +
                (near.empty() ? " (commands: " + all + ")" : "; did you mean '" + near + "'?"));
        }
    }
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
        app.parse(reversed);
    } catch (const CLI::CallForHelp&) {
        return candela::app::print_help(app.help(), stdout);
    } catch (const CLI::CallForAllHelp&) {
        return candela::app::print_help(app.help("", CLI::AppFormatMode::All), stdout);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return usage_error(candela::describe_parse_error(app, e));
    } catch (const candela::Error& e) {
        fmt::print(stderr, "{}\n", candela::error_line(e));
        return static_cast<int>(e.kind());
    } catch (const std::bad_alloc&) {
        fmt::print(stderr, "candela: error: out of memory\n");
        return static_cast<int>(candela::ErrorKind::Internal);
    } catch (const std::exception& e) {
        fmt::print(stderr, "candela: error: internal error: {}\n", e.what());
        return static_cast<int>(candela::ErrorKind::Internal);
    }
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    return status; // the sanitizers report at the normal exit
#else
    // Every file is written and closed, and the commands' own objects are gone: what a normal
    // exit would still do (the destructors of OpenImageIO's few hundred libraries and of TBB's
    // workers) takes tens of milliseconds after the stats block's time split has ended.
    std::fflush(stdout);
    std::fflush(stderr);
    std::_Exit(status);
#endif
}
