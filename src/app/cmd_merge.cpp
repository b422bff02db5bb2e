// `candela merge`: one EXR from renders of a frame with disjoint sample ranges.
#include "commands.h"
#include "output_paths.h"

#include "candela/app/cli.h"
#include "candela/render/exr_layout.h"
#include "candela/render/merge.h"
#include "candela/render/output.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "candela/util/strings.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>
#include <memory>

namespace candela::app {

namespace {
struct MergeArgs {
    std::vector<std::string> inputs;
    std::string output;
    LogArgs log;
};
/// The inputs are distinct candela EXR files that open, and the output is none of them.
void check_merge_inputs(const MergeArgs& a) {
    std::vector<NamedPath> inputs;
    for (std::size_t i = 0; i < a.inputs.size(); ++i) {
        const std::string& in = a.inputs[i];
        for (std::size_t j = 0; j < i; ++j)
            if (same_file_or_path(in, a.inputs[j]))
                throw Error(ErrorKind::Usage, SourceLoc{in},
                            "the same file twice (as " + a.inputs[j] +
                                "): a render merged with itself would count its samples twice");
        if (path_extension(in) != ".exr")
            throw Error(ErrorKind::Usage, SourceLoc{in},
                        "not a candela EXR render: merge adds the .exr files of candela render "
                        "(their sample counts and sums); an 8-bit image keeps neither");
        inputs.push_back({"an input", in});
    }
    check_distinct_files(inputs, {{"-o/--output", a.output}});
    for (const std::string& in : a.inputs)
        read_image_header(in); // every input opens, with the system's reason if not
}

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
        check_merge_inputs(*args);
        check_image_writable(args->output, OutputKind::Exr);
        ImageData out = merge_exr_files(args->inputs, args->output, command_line_text());
        if (log_level() >= LogLevel::Info)
            fmt::print(stderr, "candela: merged {} renders (samples {}) into {}\n",
                       args->inputs.size(), out.meta(exr::kMergedRanges), args->output);
        *status = 0;
    });
}

} // namespace candela::app
