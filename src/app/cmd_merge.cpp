// `candela merge`: one EXR from renders of a frame with disjoint sample ranges.
#include "commands.h"

#include "candela/app/cli.h"
#include "candela/render/exr_layout.h"
#include "candela/render/merge.h"
#include "candela/render/output.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/strings.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace candela::app {

namespace {
struct MergeArgs {
    std::vector<std::string> inputs;
    std::string output;
    LogArgs log;
};
} // namespace

void add_merge_command(CLI::App& app, int* status) {
    auto args = std::make_shared<MergeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "merge", "Add EXR renders of one frame: parts made with disjoint sample ranges "
                 "(--sample-offset), e.g. jobs of a scheduler, or -p regions, which are "
                 "assembled into the frame");
    cmd->add_option("inputs", args->inputs, "candela EXR renders of the same frame")->required();
    cmd->add_option("-o,--output", args->output,
                    "Merged EXR to write (here -o is the output file, not CS184's -o)")
        ->required();
    add_log_options(*cmd, args->log);
    cmd->callback([args, status] {
        set_log_level(log_level_of(args->log));
        if (path_extension(args->output) != ".exr")
            throw Error(ErrorKind::Usage, SourceLoc{args->output},
                        "the merged image must be an "
                        ".exr (it keeps the sums exact)");
        namespace fs = std::filesystem;
        for (const auto& in : args->inputs) {
            std::error_code ec;
            if (in == args->output || (fs::exists(in, ec) && fs::exists(args->output, ec) &&
                                       fs::equivalent(in, args->output, ec)))
                throw Error(ErrorKind::Usage, SourceLoc{args->output},
                            "refusing to overwrite an input");
            read_image_header(in); // every input opens, with the system's reason if not
        }
        check_image_writable(args->output, OutputKind::Exr);
        ImageData out = merge_exr_files(args->inputs, args->output, command_line_text());
        if (log_level() >= LogLevel::Info)
            std::fprintf(stderr, "candela: merged %zu renders (samples %s) into %s\n",
                         args->inputs.size(), out.meta(exr::kMergedRanges).c_str(),
                         args->output.c_str());
        *status = 0;
    });
}

} // namespace candela::app
