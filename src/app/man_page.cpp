// `candela help --man`: the manual page, made of the --help texts themselves, so the installed
// page (CMakeLists.txt) can never disagree with what the binary says.
#include "commands.h"

#include "candela/app/cli.h"
#include "candela/version.h"

#include <CLI/CLI.hpp>

#include <sstream>

namespace candela::app {

namespace {

/// Text for a roff no-fill block: backslashes and hyphens escaped, control characters at the
/// start of a line neutralised.
std::string roff_block(const std::string& text) {
    std::ostringstream out;
    std::istringstream in(text);
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
    m << ".SH EXIT STATUS\n.nf\n"
      << roff_block(exit_status_help()) << ".fi\n"
      << ".SH SEE ALSO\n"
      << "The README and docs/ of the candela sources; \\fBoiiotool\\fR(1) for the EXR "
         "metadata (docs/exr-metadata.md).\n";
    return m.str();
}

} // namespace candela::app
