#pragma once
// Render progress on a separate thread: a bar with ETA on a terminal, a plain line every few
// seconds otherwise (logs), or one JSON object per line on stdout for render-farm managers
// (`--progress json`, docs/usage.md "What candela prints").
#include "candela/util/enum_table.h"
#include "candela/util/stopwatch.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace candela {

enum class ProgressMode {
    Auto,  ///< Bar on a terminal, Lines otherwise
    Bar,   ///< one updating line with a bar and ETA (stderr)
    Lines, ///< a line every 10 seconds (stderr)
    Json,  ///< a JSON object per line every second (stdout)
    None
};
/// --progress (util/enum_table.h).
inline constexpr EnumTable<ProgressMode, 5> kProgressModes = {{
    {ProgressMode::Auto, "auto", "a bar on a terminal, lines otherwise"},
    {ProgressMode::Bar, "bar", ""},
    {ProgressMode::Lines, "lines", ""},
    {ProgressMode::Json, "json", "one JSON object per line on stdout, for render farms"},
    {ProgressMode::None, "none", ""},
}};

constexpr const char* progress_mode_name(ProgressMode mode) {
    return enum_name(kProgressModes, mode);
}
/// The mode a render uses: quiet silences every mode but an explicit Json (a farm manager
/// that asked for it still gets it), Auto becomes Bar on a terminal and Lines otherwise.
ProgressMode resolve_progress_mode(ProgressMode requested, bool quiet);

/// A duration for people: seconds with a tenth below a minute ("42.3s"), then m:ss ("4:12"),
/// then h:mm:ss ("1:02:03").
std::string format_duration(double seconds);

/// The progress bar's line, at most `columns` - 1 characters (the last column of a terminal
/// would wrap on some terminals): `[====    ]  65.0%  4:12 elapsed  ETA 1:03`, the bar as wide as
/// the rest leaves room for and left out when the terminal is too narrow for a useful bar.
std::string progress_bar_line(double fraction, double elapsed, double eta, int columns);

/// The width of the terminal on stderr, else $COLUMNS, else 80.
int terminal_columns();

/// The fraction a progress report shows: done / total (a total below done counts as done),
/// moved on by the time budget (seconds, 0 for none) as `elapsed` nears it, and never below
/// `reported`, the largest fraction shown before: an adaptive render's estimate of its total can
/// grow between two reports, and a fraction that goes back reads as lost work.
double progress_fraction(std::uint64_t done, std::uint64_t total, double elapsed,
                         double time_budget, double reported);

/// The largest fraction a progress display of this process has reported (0 before the first
/// report). A process renders one image: a later report of it, such as the JSON `done` event,
/// says no less.
double reported_progress_fraction();

class Progress {
  public:
    /// Reports progress towards `total` samples; `mode` must be resolved (not Auto).
    /// `time_budget` (seconds, 0 for none) bounds the ETA and moves the fraction on with time.
    Progress(std::uint64_t total, ProgressMode mode, double time_budget = 0.0);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void add(std::uint64_t n) { done_.fetch_add(n, std::memory_order_relaxed); }
    std::uint64_t done() const { return done_.load(std::memory_order_relaxed); }
    /// A new estimate of the samples the whole run will take (an adaptive render learns it as it
    /// goes: the ETA then follows the estimate, not the worst case).
    void retarget(std::uint64_t total) { total_.store(total, std::memory_order_relaxed); }
    /// The render reached its end (whatever stopped it but an interrupt): the last line says 100 %.
    void complete() { retarget(done()); }
    /// Stops the thread and prints the final state (idempotent).
    void finish();

  private:
    void loop();
    void print(bool final);

    std::atomic<std::uint64_t> total_;
    ProgressMode mode_;
    double time_budget_;
    std::atomic<std::uint64_t> done_{0};
    std::atomic<double> reported_{0.0};
    Stopwatch clock_;
    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
};

} // namespace candela
