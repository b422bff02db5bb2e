// How candela's --help reads: the render options in topic groups (one table, by flag), the
// top-level usage with the `candela SCENE.dae` form, and every help text wrapped to the
// terminal's width. The manual page and the shell completion read the same CLI11 app.
#include "commands.h"

#include "candela/render/setting_table.h"

#include <CLI/CLI.hpp>

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>

namespace candela::app {

namespace {

/// Columns assumed when stdout is not a terminal and $COLUMNS does not say: the width a help
/// text piped into a file or a pager must fit.
constexpr int kDefaultHelpColumns = 80;
/// Narrowest width the help is wrapped to: below it the description column (CLI11 starts it
/// 30 columns in) would leave only a word or two per line.
constexpr int kMinHelpColumns = 50;
/// Where an option's description starts (CLI11's name column): names longer than this put
/// their description on the next line, indented to it.
constexpr std::size_t kDescriptionColumn = 30;

/// The render options' groups, in the order --help shows them. A render setting is in the group
/// its row names (render/setting_table.h); any other option is put in a group by adding its
/// long flag (its first name when it has no long form) to one of these lists. An option in no
/// group is listed under kUngrouped, which a test refuses. A name no option has is passed over.
const std::vector<OptionGroup>& groups_table() {
    static const std::vector<OptionGroup> groups = {
        {"Input and output",
         {"--output", "--env", "--preview", "--overwrite", "--write-every", "--display-server"}},
        {"Sampling", {}},
        {"Light transport", {}},
        {"Camera",
         {"--resolution", "--region", "--framing", "--camera", "--camera-file", "--look-from",
          "--look-at", "--fov", "--lens-radius", "--focal-distance"}},
        {"EXR", {"--half", "--compression", "--background-depth"}},
        {"8-bit images", {"--look", "--tonemap", "--exposure"}},
        {"Checkpoints and resuming",
         {"--resume", "--checkpoint", "--checkpoint-every", "--keep-checkpoint"}},
        {"Ray traversal", {}},
        {"Running and diagnostics",
         {"--quiet", "--verbose", "--log-level", "--strict", "--max-memory", "--help"}},
    };
    return groups;
}

/// The flag an option is grouped by: its first long name, else its first short one.
std::string group_key(const CLI::Option& o) {
    if (!o.get_lnames().empty()) return "--" + o.get_lnames().front();
    if (!o.get_snames().empty()) return "-" + o.get_snames().front();
    return o.get_name();
}

/// CLI11's formatter with the groups in the table's order and, for the top-level help, a usage
/// that shows both forms of a render. (Every app candela declares has a name, so CLI11's
/// heading for unnamed option groups is not needed.)
class HelpFormatter : public CLI::Formatter {
  public:
    HelpFormatter() { column_width(kDescriptionColumn); }

    std::string make_usage(const CLI::App* app, std::string name) const override {
        if (app->get_parent() != nullptr) return CLI::Formatter::make_usage(app, name);
        return "Usage: " + name + " COMMAND [FLAGS]\n       " + name +
               " SCENE.dae [FLAGS]   (= " + name + " render SCENE.dae [FLAGS])\n";
    }

    /// CLI11's help, but with the option groups in the table's order.
    std::string make_help(const CLI::App* app, std::string name,
                          CLI::AppFormatMode mode) const override {
        if (mode == CLI::AppFormatMode::Sub) return make_expanded(app);
        return make_description(app) + make_usage(app, name) + make_positionals(app) +
               ordered_groups(app, mode) + make_subcommands(app, mode) + "\n" + make_footer(app);
    }

  private:
    std::string ordered_groups(const CLI::App* app, CLI::AppFormatMode mode) const {
        std::vector<std::string> groups = app->get_groups();
        const auto rank = [](const std::string& g) {
            const auto& t = groups_table();
            const auto it = std::find_if(t.begin(), t.end(),
                                         [&g](const OptionGroup& og) { return og.heading == g; });
            return std::size_t(it - t.begin());
        };
        std::stable_sort(
            groups.begin(), groups.end(),
            [&rank](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
        std::string out;
        for (const std::string& group : groups) {
            std::vector<const CLI::Option*> opts =
                app->get_options([app, mode, &group](const CLI::Option* o) {
                    return o->get_group() == group && o->nonpositional() &&
                           (mode != CLI::AppFormatMode::Sub ||
                            (app->get_help_ptr() != o && app->get_help_all_ptr() != o));
                });
            if (group.empty() || opts.empty()) continue;
            out += make_group(group, false, opts); // each begins with a blank line
        }
        return out;
    }
};

/// Where the continuation of a help line starts: under the description of an option line
/// ("  -s,--spp INT   Samples ..."), under the text of a line that is only a description
/// (indented to the description column), else two columns in from the line's own indent.
std::size_t continuation_indent(const std::string& line, std::size_t width) {
    const std::size_t lead = line.find_first_not_of(' ');
    if (lead == std::string::npos) return 0;
    if (lead >= kDescriptionColumn && lead < width / 2) return lead;
    const std::size_t gap = line.find("  ", lead);
    if (gap != std::string::npos) {
        const std::size_t desc = line.find_first_not_of(' ', gap);
        if (desc != std::string::npos && desc < width / 2) return desc;
    }
    return lead + 2;
}

} // namespace

const std::vector<OptionGroup>& render_option_groups() {
    return groups_table();
}

void group_render_options(CLI::App& render) {
    for (CLI::Option* o : render.get_options()) {
        if (o->get_positional()) continue;
        const std::string key = group_key(*o);
        std::string heading = kUngrouped;
        for (const OptionGroup& g : groups_table())
            if (std::find(g.flags.begin(), g.flags.end(), key) != g.flags.end() ||
                (find_setting(key) && find_setting(key)->group == g.heading))
                heading = g.heading;
        o->group(heading);
    }
}

void use_help_formatter(CLI::App& app) {
    app.formatter(std::make_shared<HelpFormatter>());
}

int help_columns() {
    winsize ws{};
    if (::isatty(1) && ::ioctl(1, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
        return std::max(int(ws.ws_col), kMinHelpColumns);
    if (const char* env = std::getenv("COLUMNS")) {
        const int c = std::atoi(env);
        if (c > 0) return std::max(c, kMinHelpColumns);
    }
    return kDefaultHelpColumns;
}

std::string wrap_help(const std::string& text, std::size_t width) {
    std::string out;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        const std::string indent(continuation_indent(line, width), ' ');
        while (line.size() > width) {
            std::size_t cut = line.rfind(' ', width);
            std::size_t keep = 0; // the characters of `line` this output line takes
            if (cut != std::string::npos && cut > indent.size()) {
                const std::size_t end = line.find_last_not_of(' ', cut);
                keep = end == std::string::npos ? cut : end + 1;
            } else {
                // One word longer than the room (a list of choices): break it after a comma.
                const std::size_t comma = line.rfind(',', width - 1);
                if (comma == std::string::npos || comma <= indent.size()) break;
                keep = cut = comma + 1;
            }
            out += line.substr(0, keep) + "\n";
            const std::size_t next = line.find_first_not_of(' ', cut);
            line = indent + (next == std::string::npos ? "" : line.substr(next));
        }
        out += line + "\n";
    }
    return out;
}

int print_help(const std::string& help, std::FILE* to) {
    std::fputs(wrap_help(help, std::size_t(help_columns())).c_str(), to);
    return 0;
}

} // namespace candela::app
