#pragma once
// Tables of the named choices of a user-visible enum (--accel embree, --sampler sobol, ...): one
// constexpr array per enum, in the header of the stage that owns it, from which parsing, printing
// and the --help text of the choices all come.
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// One choice: its value, the name the command line and the EXR metadata use, and a short help
/// phrase ("" when the name says it all).
template <typename E> struct EnumChoice {
    E value;
    const char* name;
    const char* help;
};

template <typename E, std::size_t N> using EnumTable = std::array<EnumChoice<E>, N>;

/// The name of `value` in `table` ("?" when the table lacks it).
template <typename E, std::size_t N>
constexpr const char* enum_name(const EnumTable<E, N>& table, E value) {
    for (const EnumChoice<E>& c : table)
        if (c.value == value) return c.name;
    return "?";
}

/// The value named `name`, or nullopt.
template <typename E, std::size_t N>
std::optional<E> find_enum(const EnumTable<E, N>& table, const std::string& name) {
    for (const EnumChoice<E>& c : table)
        if (name == c.name) return c.value;
    return std::nullopt;
}

/// Every name of `table`, in its order.
template <typename E, std::size_t N>
std::vector<std::string> enum_names(const EnumTable<E, N>& table) {
    std::vector<std::string> names;
    for (const EnumChoice<E>& c : table)
        names.emplace_back(c.name);
    return names;
}

/// Throws Error(Usage): "FLAG: unknown value 'VALUE' (expected one of: a, b, c)", with
/// "; did you mean 'x'?" when one of `names` is close to `value`.
[[noreturn]] void throw_unknown_choice(const std::string& flag, const std::string& value,
                                       const std::vector<std::string>& names);

/// The value named `value`; an unknown name throws as throw_unknown_choice() does.
template <typename E, std::size_t N>
E parse_enum(const EnumTable<E, N>& table, const std::string& flag, const std::string& value) {
    if (const std::optional<E> e = find_enum(table, value)) return *e;
    throw_unknown_choice(flag, value, enum_names(table));
}

/// How choice_text() lists choices: "a (help a), b or c (help c)" by default.
struct ChoiceStyle {
    const char* separator = ", "; ///< between choices
    const char* last = " or ";    ///< before the last choice
    const char* open = " (";      ///< between a name and its help
    const char* close = ")";      ///< after a help
    bool with_help = true;        ///< false: the names alone
};

/// The choices {name, help} as one phrase for --help.
std::string choice_text(const std::vector<std::pair<std::string, std::string>>& choices,
                        const ChoiceStyle& style);

/// The choices of `table` as one phrase for --help.
template <typename E, std::size_t N>
std::string enum_choices(const EnumTable<E, N>& table, const ChoiceStyle& style = {}) {
    std::vector<std::pair<std::string, std::string>> choices;
    for (const EnumChoice<E>& c : table)
        choices.emplace_back(c.name, c.help);
    return choice_text(choices, style);
}

/// The candidate closest to `word` by edit distance (or the only one `word` begins), "" when
/// none is close enough to be what was meant.
std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates);

} // namespace candela
