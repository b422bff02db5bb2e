// Lookups in the tables of named choices, and the nearest name for a misspelt one.
#include "candela/util/enum_table.h"

#include "candela/util/error.h"

#include <algorithm>

namespace candela {

namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
    // Optimal string alignment distance: insertions, deletions, substitutions and adjacent
    // transpositions each cost 1.
    const std::size_t n = a.size(), m = b.size();
    std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
    for (std::size_t i = 0; i <= n; ++i)
        d[i][0] = i;
    for (std::size_t j = 0; j <= m; ++j)
        d[0][j] = j;
    for (std::size_t i = 1; i <= n; ++i)
        for (std::size_t j = 1; j <= m; ++j) {
            const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[n][m];
}

} // namespace

void throw_unknown_choice(const std::string& flag, const std::string& value,
                          const std::vector<std::string>& names) {
    std::string list;
    for (const std::string& n : names)
        list += (list.empty() ? "" : ", ") + n;
    const std::string near = nearest_name(value, names);
    throw Error(ErrorKind::Usage, flag + ": unknown value '" + value +
                                      "' (expected one of: " + list + ")" +
                                      (near.empty() ? "" : "; did you mean '" + near + "'?"));
}

std::string choice_text(const std::vector<std::pair<std::string, std::string>>& choices,
                        const ChoiceStyle& style) {
    std::string s;
    for (std::size_t i = 0; i < choices.size(); ++i) {
        if (i > 0) s += i + 1 == choices.size() ? style.last : style.separator;
        s += choices[i].first;
        if (style.with_help && !choices[i].second.empty())
            s += style.open + choices[i].second + style.close;
    }
    return s;
}

std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates) {
    if (word.empty()) return "";
    // A unique candidate that the word begins (a shortened long option).
    std::string prefixed;
    int prefix_count = 0;
    for (const std::string& c : candidates)
        if (c.size() > word.size() && c.rfind(word, 0) == 0 && word.size() >= 3) {
            prefixed = c;
            ++prefix_count;
        }
    if (prefix_count == 1) return prefixed;
    // Otherwise the closest by edit distance, if within a third of the word (at least 1, at
    // most 3 edits): close enough to be a typo, far enough not to suggest nonsense.
    const std::size_t limit = std::clamp<std::size_t>(word.size() / 3, 1, 3);
    std::string best;
    std::size_t best_d = limit + 1;
    for (const std::string& c : candidates) {
        const std::size_t d = edit_distance(word, c);
        if (d < best_d) {
            best_d = d;
            best = c;
        }
    }
    return best_d <= limit ? best : "";
}

} // namespace candela
