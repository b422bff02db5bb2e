#pragma once
// What the files of the render command line share (cli.cpp, parse_errors.cpp and render/'s
// options.cpp, checks.cpp, resume_options.cpp): the usage error, the limits of the
// range checks, the choice options kept as given, and the table of options a checkpoint stores.
#include "candela/app/cli.h"
#include "candela/util/enum_table.h"

#include <climits>
#include <functional>
#include <string>
#include <vector>

namespace candela::cli {

/// Largest accepted image edge: far above any real frame, far below sizes whose film (about
/// 100 bytes per pixel with every channel) would not fit in memory.
constexpr int kMaxImageEdge = 32768;
/// Largest accepted pixel count (256 Mpixel).
constexpr long long kMaxPixels = 1ll << 28;
/// The largest seed or sample index (render/setting_table.h).
using ::candela::kMaxIndex;

/// Throws Error(Usage) with `what`.
[[noreturn]] void usage(const std::string& what);

/// `p` made absolute and normal ("" stays "").
std::string absolute_path(const std::string& p);

/// A choice option's value as given: its name, or the unknown value finalize_render_args reports.
template <typename E, std::size_t N>
std::vector<std::string> choice(const RenderArgs& a, const std::string& flag,
                                const EnumTable<E, N>& table, E value) {
    const auto it = a.unknown_choices.find(flag);
    return {it != a.unknown_choices.end() ? it->second : std::string(enum_name(table, value))};
}

/// Throws the error of a choice option whose value names none of its choices.
template <typename E, std::size_t N>
void check_choice(const RenderArgs& a, const std::string& flag, const EnumTable<E, N>& table) {
    const auto it = a.unknown_choices.find(flag);
    if (it != a.unknown_choices.end()) throw_unknown_choice(flag, it->second, enum_names(table));
}

/// One render option as the checkpoint and the resume check see it: its values in canonical
/// form, and whether it may change on --resume.
struct OptionSpec {
    const char* name;    ///< CLI11 name: the long form, or "scene"
    const char* display; ///< as messages show it, e.g. "-s/--spp"
    bool runtime;        ///< changes how or where the render runs, never its pixels
    std::function<std::vector<std::string>(const RenderArgs&)> values;
};

/// Every render option, in the order a checkpoint stores them.
const std::vector<OptionSpec>& option_specs();
/// The option named `name` (its long form, or "scene"); nullptr when there is none.
const OptionSpec* find_spec(const std::string& name);

} // namespace candela::cli
