#include "commands.h"

#include "candela/render/merge.h"
#include "candela/render/output.h"
#include "candela/util/error.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>

namespace candela::app {

namespace {
struct MergeArgs {
    std::vector<std::string> inputs;
    std::string output;
    bool quiet = false;
};
} // namespace

void add_merge_command(CLI::App& app, int* status) {
    auto args = std::make_shared<MergeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "merge", "Add EXR renders of one frame made with disjoint sample ranges "
                 "(--sample-offset), e.g. parts rendered as separate jobs of a scheduler");
    cmd->add_option("inputs", args->inputs, "candela EXR renders of the same frame")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", args->output, "Merged EXR to write")->required();
    cmd->add_flag("-q,--quiet", args->quiet, "No summary on stderr");
    cmd->callback([args, status] {
        if (path_extension(args->output) != ".exr")
            throw Error(ErrorKind::Usage, args->output + ": error: the merged image must be an "
                                                         ".exr (it keeps the sums exact)");
        for (const auto& in : args->inputs)
            if (in == args->output)
                throw Error(ErrorKind::Usage,
                            args->output + ": error: refusing to overwrite an input");
        ImageData out = merge_exr_files(args->inputs, args->output);
        if (!args->quiet)
            std::fprintf(stderr, "candela: merged %zu renders (samples %s) into %s\n",
                         args->inputs.size(), out.meta("candela:merged_ranges").c_str(),
                         args->output.c_str());
        *status = 0;
    });
}

} // namespace candela::app
