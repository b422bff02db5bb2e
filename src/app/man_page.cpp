// `candela help --man`: the manual page, made of the --help texts themselves, so the installed
// page (CMakeLists.txt) can never disagree with what the binary says.
#include "commands.h"

#include "candela/app/cli.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>

#include <sstream>

namespace candela::app {

namespace {

/// Widest line of a no-fill block: man indents a section's text by 7 columns, and the page
/// must fit an 80-column terminal.
constexpr std::size_t kManTextWidth = 80 - 7;

/// Text for a roff no-fill block: lines wrapped to kManTextWidth, backslashes and hyphens
/// escaped, control characters at the start of a line neutralised.
std::string roff_block(const std::string& text) {
    std::ostringstream out;
    std::istringstream in(wrap_help(text, kManTextWidth));
    std::string line;
    while (std::getline(in, line)) {
        std::string esc;
        for (char c : line) {
            if (c == '\\')
                esc += "\\e";
            else if (c == '-')
                esc += "\\-";
            else
                esc += c;
        }
        if (!esc.empty() && (esc[0] == '.' || esc[0] == '\'')) esc = "\\&" + esc;
        out << esc << "\n";
    }
    return out.str();
}

} // namespace

std::string man_page(const CLI::App& app) {
    std::ostringstream m;
    m << ".TH CANDELA 1 \"\" \"candela " CANDELA_VERSION "\" \"User Commands\"\n"
      << ".SH NAME\n"
      << "candela \\- a physically based path tracer for CS184-style COLLADA scenes\n"
      << ".SH SYNOPSIS\n"
      << ".B candela\n"
      << ".I COMMAND\n"
      << "[\\fIOPTIONS\\fR] [\\fISCENE\\fR]\n"
      << ".br\n"
      << ".B candela help\n"
      << "[\\fICOMMAND\\fR]\n"
      << ".br\n"
      << ".B candela\n"
      << ".I SCENE.dae\n"
      << "[\\fIOPTIONS\\fR]\n"
      << ".SH DESCRIPTION\n"
      << "candela renders CS184-style COLLADA scenes (.dae) with an Embree-accelerated path "
         "tracer and writes HDR OpenEXR images with alpha, auxiliary channels and metadata. "
         "Each command below is followed by its own \\fB\\-\\-help\\fR text.\n"
      << ".PP\n.nf\n"
      << roff_block(app.help()) << ".fi\n"
      << ".SH COMMANDS\n";
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
        m << ".SS " << sub->get_name() << "\n"
          << ".nf\n"
          << roff_block(sub->help()) << ".fi\n";
    }
    m << ".SH EXAMPLES\n.nf\n"
      << roff_block("candela render scene.dae -r 400 300 -s 64 -f quick.exr\n"
                    "    a quick look: 400x300, at most the cost of 64 samples per pixel\n"
                    "candela scene.dae\n"
                    "    the same as 'candela render scene.dae': full quality, to scene.exr\n"
                    "    (an earlier scene.exr is kept as scene.1.exr, the first free number)\n"
                    "candela -t 1 -s 16 -m 5 -f out.png scene.dae\n"
                    "    the CS184 path tracer's flags and order, an 8-bit PNG\n"
                    "candela render scene.dae --adaptive none -s 256 --half -f plate.exr\n"
                    "    exactly 256 samples in every pixel, half-float colour channels\n"
                    "candela render --resume out.exr.ckpt\n"
                    "    continue an interrupted render (bit-identical to an uninterrupted one)\n"
                    "candela render scene.dae --noise-threshold 0.04 --keep-checkpoint\n"
                    "candela render --resume scene.exr.ckpt --noise-threshold 0.02\n"
                    "    a quick render, then refined to the render to 0.02 (bit-identical)\n"
                    "candela probe scene.dae 120 80 -r 400 300\n"
                    "    where the light of pixel (120, 80) of a 400x300 render comes from\n"
                    "candela merge left.exr right.exr -o frame.exr\n"
                    "    assemble regions or add sample ranges rendered apart\n"
                    "candela info scene.dae\n"
                    "    what the scene holds and what a render will skip\n"
                    "candela render scene.dae -s 256 --look cs184 -f mine.png\n"
                    "    an 8-bit image through the CS184 course's exposure and gamma\n"
                    "candela compare student.png --scene scene.dae -m 5\n"
                    "    a course PNG against candela's render, split by light-path order\n"
                    "candela info --vs-cs184 scene.dae\n"
                    "    where this scene's image differs from the course's by design\n")
      << ".fi\n"
      << ".SH ENVIRONMENT\n"
      << ".TP\n.B CANDELA_IMAGE_MODULE\n"
      << "Path of the image module to load instead of the installed one "
         "(\\fIlibcandela_image.so\\fR, through which every image is read and written).\n"
      << ".PP\nNo other variable changes what candela does; the number of worker threads is "
         "\\fB\\-t\\fR alone (0, the default, uses every core).\n"
      << ".SH FILES\n"
      << ".TP\n.I PREFIX/lib/candela/libcandela_image.so\n"
      << "The image module (OpenImageIO), loaded on the first image read or written; an "
         "installed candela loads only this one (or \\fBCANDELA_IMAGE_MODULE\\fR).\n"
      << ".TP\n.I OUTPUT.ckpt\n"
      << "The checkpoint of an interrupted render, or of a finished one with "
         "\\fB\\-\\-keep\\-checkpoint\\fR (\\fB\\-\\-checkpoint\\fR names another), read "
         "by \\fB\\-\\-resume\\fR. While it is there, a new render to the same output is "
         "refused unless \\fB\\-\\-overwrite\\fR is given; even then it stays until the new "
         "render holds more samples.\n"
      << ".TP\n.I SCENE.N.exr\n"
      << "An earlier image at the default output name (no \\fB\\-f\\fR), kept under the "
         "first free number N when a new render writes that name.\n"
      << ".TP\n.I NAME_rate.png\n"
      << "The samples per pixel of an adaptive render, beside an 8-bit output or its "
         "\\fB\\-\\-preview\\fR.\n"
      << ".SH EXIT STATUS\n.nf\n"
      << roff_block(exit_status_help()) << ".fi\n"
      << ".SH SEE ALSO\n"
      << "The README and docs/ of the candela sources; \\fBoiiotool\\fR(1) for the EXR "
         "metadata (docs/exr-metadata.md).\n";
    return m.str();
}

} // namespace candela::app
