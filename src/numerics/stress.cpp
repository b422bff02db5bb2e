// The numerical-stability stress suite: its list of cases and the report of what each measured.
#include "candela/numerics/stress.h"

#include <algorithm>

namespace candela::numerics {

namespace {

/// Table cells must not contain the column separator.
std::string cell(const std::string& s) {
    std::string out;
    out.reserve(s.size());
    for (char c : s) {
        if (c == '|')
            out += "\\|";
        else
            out += c;
    }
    return out;
}

} // namespace

std::string format_markdown(const std::vector<StressResult>& results) {
    std::vector<std::string> groups;
    for (const StressResult& r : results)
        if (std::find(groups.begin(), groups.end(), r.group) == groups.end())
            groups.push_back(r.group);

    std::string md;
    for (const std::string& g : groups) {
        md += "### " + g + "\n\n";
        md += "| case | method | expected | measured | result |\n";
        md += "|---|---|---|---|---|\n";
        for (const StressResult& r : results) {
            if (r.group != g) continue;
            const char* verdict = r.reported_only ? "reported" : (r.pass ? "pass" : "**FAIL**");
            md += "| " + cell(r.name) + " | " + cell(r.method) + " | " + cell(r.expected) + " | " +
                  cell(r.measured) + " | " + verdict + " |\n";
        }
        md += "\n";
    }
    return md;
}

int count_failures(const std::vector<StressResult>& results) {
    return static_cast<int>(
        std::count_if(results.begin(), results.end(),
                      [](const StressResult& r) { return !r.reported_only && !r.pass; }));
}

} // namespace candela::numerics
