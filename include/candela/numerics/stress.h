#pragma once
// The numerical-stability stress suite: each case runs a stiff or extreme configuration and
// returns what it measured next to what is expected. The Catch2 tests in tests/numerics assert
// on these results, and tools/numerics_report prints them as the tables of docs/numerics.md, so
// the documented figures and the tested ones come from the same code.
#include <string>
#include <vector>

namespace candela::numerics {

/// One row of the report: a case run with one method (backend, triangle test, setting).
struct StressResult {
    std::string group;          ///< e.g. "watertightness", "stiff transport"
    std::string name;           ///< the case, e.g. "sphere:20000 translated 1e5, edge rays"
    std::string method;         ///< e.g. "builtin watertight", "embree robust"
    std::string expected;       ///< the expected behaviour, e.g. "0 leaks", "|z| < 4"
    std::string measured;       ///< what was measured, e.g. "0 of 40000", "z = 0.7, 4.99 vs 5"
    bool pass = false;          ///< measured meets expected (rows that only report set true)
    bool reported_only = false; ///< a figure with no requirement (e.g. Moller-Trumbore leaks)
};

/// How much work a case does: tests run Quick, the report tool Full (same cases, more rays).
enum class StressSize { Quick, Full };

} // namespace candela::numerics

namespace candela::numerics {

/// The results as Markdown: one table per group (in first-seen order) with the columns
/// case | method | expected | measured | result.
std::string format_markdown(const std::vector<StressResult>& results);

/// Number of rows that have a requirement and fail it.
int count_failures(const std::vector<StressResult>& results);

} // namespace candela::numerics
