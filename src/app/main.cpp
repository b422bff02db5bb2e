// candela: scene file -> loader -> Scene -> accelerator -> integrator -> film -> image writer.
// Each subcommand lives in its own cmd_*.cpp; this file only dispatches and chooses the exit
// status (README "Exit status").
#include "commands.h"

#include "candela/util/error.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    CLI::App app{"candela " CANDELA_VERSION
                 ": a physically based path tracer for CS184-style COLLADA scenes"};
    app.require_subcommand(1);
    app.set_version_flag("--version", CANDELA_VERSION);
    int status = 0;
    candela::app::set_command_line(argc, argv);
    candela::app::add_render_command(app, &status);
    candela::app::add_info_command(app, &status);
    candela::app::add_check_command(app, &status);
    candela::app::add_bench_command(app, &status);
    candela::app::add_converge_command(app, &status);
    candela::app::add_merge_command(app, &status);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr,
                     "candela: error: %s\nRun 'candela --help' or 'candela <command> "
                     "--help' for usage.\n",
                     e.what());
        return static_cast<int>(candela::ErrorKind::Usage);
    } catch (const candela::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return static_cast<int>(e.kind());
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "candela: error: out of memory\n");
        return static_cast<int>(candela::ErrorKind::Internal);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "candela: internal error: %s\n", e.what());
        return static_cast<int>(candela::ErrorKind::Internal);
    }
    return status;
}
