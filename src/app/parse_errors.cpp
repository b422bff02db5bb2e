// CLI11's parse errors in candela's own words: the flag as the user knows it, what was wrong
// with its value, and the nearest valid name for a mistyped option or command.
#include "candela/app/cli.h"
#include "candela/util/enum_table.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <optional>
#include <string>
#include <vector>

namespace candela {

namespace {

/// The parse being described: the app whose arguments failed and how messages name it.
struct ParseContext {
    const CLI::App& top;
    const CLI::App* app; ///< the subcommand being parsed, else `top`
    bool dispatcher;     ///< `top` is candela itself (it has subcommands), not one command's app
    std::string cmd;     ///< "render: " in front of what concerns a subcommand as a whole
    std::string what;    ///< CLI11's own message
};

ParseContext context_of(const CLI::App& top, const CLI::ParseError& e) {
    const CLI::App* app = &top;
    while (!app->get_subcommands().empty())
        app = app->get_subcommands().front();
    const bool dispatcher =
        app == &top && !top.get_subcommands([](const CLI::App*) { return true; }).empty();
    return {top, app, dispatcher, app->get_name().empty() ? std::string() : app->get_name() + ": ",
            e.what()};
}

/// The names of `o` as typed: "--long" and "-s" forms.
std::vector<std::string> typed_names(const CLI::Option* o) {
    std::vector<std::string> names;
    for (const std::string& l : o->get_lnames())
        names.push_back("--" + l);
    for (const std::string& s : o->get_snames())
        names.push_back("-" + s);
    return names;
}

std::vector<std::string> option_names(const CLI::App* a) {
    std::vector<std::string> names;
    for (const CLI::Option* o : a->get_options())
        for (const std::string& n : typed_names(o))
            names.push_back(n);
    return names;
}

/// The option as messages show it: "-s/--spp", or a positional's name in capitals.
std::string display(const CLI::Option* o) {
    if (o->get_lnames().empty() && o->get_snames().empty()) {
        std::string n = o->get_name();
        std::transform(n.begin(), n.end(), n.begin(),
                       [](unsigned char c) { return char(std::toupper(c)); });
        return n;
    }
    std::string s;
    for (const std::string& n : o->get_snames())
        s += (s.empty() ? "-" : "/-") + n;
    for (const std::string& n : o->get_lnames())
        s += (s.empty() ? "--" : "/--") + n;
    return s;
}

/// The option an error message names (the longest name found in it).
const CLI::Option* option_in_message(const ParseContext& c) {
    const CLI::Option* best = nullptr;
    std::size_t best_len = 0;
    for (const CLI::Option* o : c.app->get_options()) {
        std::vector<std::string> names = typed_names(o);
        if (names.empty()) names.push_back(o->get_name());
        for (const std::string& n : names)
            if (n.size() > best_len && c.what.find(n) != std::string::npos) {
                best = o;
                best_len = n.size();
            }
    }
    return best;
}

/// CLI11's type name of `o` without its decoration ("INT", "FLOAT", ...).
std::string type_of(const CLI::Option* o) {
    const std::string t = o->get_type_name();
    return t.substr(0, t.find(' '));
}

std::string type_phrase(const CLI::Option* o, bool plural) {
    const std::string t = type_of(o);
    if (t == "INT") return std::string(plural ? "whole numbers" : "a whole number");
    if (t == "UINT")
        return std::string(plural ? "non-negative whole numbers" : "a non-negative whole number");
    if (t == "FLOAT") return std::string(plural ? "numbers" : "a number");
    return std::string(plural ? "values" : "a value");
}

/// Arguments left over: an unknown option, an unknown command or a stray argument.
std::optional<std::string> extras_message(const ParseContext& c) {
    const std::vector<std::string> extra = c.app->remaining();
    for (const std::string& arg : extra)
        if (arg.size() > 1 && arg[0] == '-') {
            const std::string name = arg.substr(0, arg.find('='));
            // The CS184 habit: -f names the output file; merge and converge call it -o.
            if (name == "-f")
                for (const CLI::Option* o : c.app->get_options())
                    if (o->check_lname("output") && o->check_sname("o"))
                        return c.cmd + "unknown option '-f'; the output file is '-o' here";
            const std::string near = nearest_name(name, option_names(c.app));
            return c.cmd + "unknown option '" + name + "'" +
                   (near.empty() ? "" : "; did you mean '" + near + "'?");
        }
    if (extra.empty()) return std::nullopt;
    if (c.dispatcher) {
        std::vector<std::string> subs;
        for (const CLI::App* s : c.top.get_subcommands([](const CLI::App*) { return true; }))
            subs.push_back(s->get_name());
        const std::string near = nearest_name(extra.front(), subs);
        return "unknown command '" + extra.front() + "'" +
               (near.empty() ? "" : "; did you mean '" + near + "'?");
    }
    return c.cmd + "unexpected argument '" + extra.front() + "'";
}

/// A required option or argument not given.
std::optional<std::string> required_message(const ParseContext& c) {
    if (c.dispatcher)
        return std::string("no command given (render, info, check, bench, converge or "
                           "merge)");
    for (const CLI::Option* o : c.app->get_options())
        if (o->get_required() && o->count() == 0) return c.cmd + display(o) + " is missing";
    return std::nullopt;
}

/// Every value is a whole number (an optional sign, then digits).
bool all_whole_numbers(const std::vector<std::string>& values) {
    return !values.empty() && std::all_of(values.begin(), values.end(), [](const std::string& v) {
        const std::size_t first = v.size() > 1 && (v[0] == '-' || v[0] == '+') ? 1 : 0;
        return v.size() > first && v.find_first_not_of("0123456789", first) == std::string::npos;
    });
}

/// A value CLI11 could not convert, or the wrong number of values, for option `o`.
std::string value_message(const CLI::Option* o, bool mismatch) {
    const int expected = o->get_expected_max();
    const std::vector<std::string> got = o->results();
    std::string values;
    for (const std::string& v : got)
        values += (values.empty() ? "'" : " '") + v + "'";
    if (mismatch && expected == 1 && got.size() > 1)
        return display(o) + " was given " + std::to_string(got.size()) + " times; give it once";
    // A list option's maximum is CLI11's internal "any number" (2^29), never shown.
    constexpr int kLongestFixedList = 16;
    if (expected > kLongestFixedList)
        return display(o) + " takes one or more " + type_phrase(o, true) +
               (values.empty() ? "" : "; got " + values);
    if (expected > 1)
        return display(o) + " takes " + std::to_string(expected) + " " + type_phrase(o, true) +
               (values.empty() ? "" : "; got " + values);
    if (mismatch) return display(o) + " needs " + type_phrase(o, false);
    // CS184's -o is the accumulate flag; a file name there means -f was meant.
    const std::string hint =
        o->check_lname("accumulate") ? " (CS184's -o is 0 or 1; the output file is -f)" : "";
    // A whole number CLI11 could not convert is beyond the option's type, not malformed.
    const bool integral_type = type_of(o) == "INT" || type_of(o) == "UINT";
    if (integral_type && all_whole_numbers(got))
        return display(o) + ": " + values + " is out of range";
    return display(o) + ": " + (values.empty() ? "the value" : values) + " is not " +
           type_phrase(o, false) + hint;
}

} // namespace

std::string describe_parse_error(const CLI::App& top, const CLI::ParseError& e) {
    const ParseContext c = context_of(top, e);
    if (dynamic_cast<const CLI::ExtrasError*>(&e))
        if (std::optional<std::string> m = extras_message(c)) return *m;
    if (dynamic_cast<const CLI::RequiredError*>(&e)) {
        // An unknown option is the likelier mistake (`merge ... -f out.exr` leaves -o missing).
        if (std::optional<std::string> m = extras_message(c)) return *m;
        if (std::optional<std::string> m = required_message(c)) return *m;
    }
    const bool mismatch = dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr;
    if (mismatch || dynamic_cast<const CLI::ConversionError*>(&e))
        if (const CLI::Option* o = option_in_message(c)) return value_message(o, mismatch);
    return c.cmd + c.what;
}

} // namespace candela
