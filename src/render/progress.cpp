// Render progress on its own thread: a terminal bar, log lines or JSON events.
#include "candela/render/progress.h"

#include "candela/util/error.h"
#include "candela/util/stopwatch.h"
#include "candela/util/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sys/ioctl.h>
#include <unistd.h>

namespace candela {

namespace {

/// A terminal bar redraws four times a second: smooth to the eye, negligible cost.
constexpr std::chrono::milliseconds kBarPeriod{250};
/// Log lines every 10 s: a long render's log stays readable.
constexpr std::chrono::milliseconds kLinesPeriod{10000};
/// JSON lines every second: fine enough for a farm manager's progress display, few enough
/// lines that parsing them costs nothing.
constexpr std::chrono::milliseconds kJsonPeriod{1000};
/// Narrowest bar worth drawing: below it the line is the numbers alone.
constexpr int kMinBarWidth = 10;
/// Columns assumed when neither the terminal nor $COLUMNS says.
constexpr int kDefaultColumns = 80;

/// The largest fraction any progress display of the process has reported.
std::atomic<double> g_reported{0.0};

/// The `progress` event of --progress json, one line on stdout.
void print_progress_event(double fraction, std::uint64_t done, std::uint64_t total, double elapsed,
                          double eta) {
    const nlohmann::ordered_json e = {{"event", "progress"},
                                      {"fraction", printed_number(fraction, "{:.6f}")},
                                      {"samples", done},
                                      {"samples_total", total},
                                      {"elapsed_s", printed_number(elapsed, "{:.3f}")},
                                      {"eta_s", printed_number(eta, "{:.3f}")}};
    fmt::print("{}\n", e.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::fflush(stdout);
}

} // namespace

double reported_progress_fraction() {
    return g_reported.load();
}

ProgressMode resolve_progress_mode(ProgressMode requested, bool quiet) {
    if (requested == ProgressMode::Json) return requested;
    if (quiet) return ProgressMode::None;
    if (requested == ProgressMode::Auto)
        return ::isatty(2) != 0 ? ProgressMode::Bar : ProgressMode::Lines;
    return requested;
}

std::string format_duration(double seconds) {
    const long long whole = std::llround(std::max(0.0, seconds));
    if (seconds < 59.95) return fmt::format("{:.1f}s", std::max(0.0, seconds));
    if (whole < 3600) return fmt::format("{}:{:02}", whole / 60, whole % 60);
    return fmt::format("{}:{:02}:{:02}", whole / 3600, whole / 60 % 60, whole % 60);
}

std::string progress_bar_line(double fraction, double elapsed, double eta, int columns) {
    const std::string tail = fmt::format("{:5.1f}%  {} elapsed  ETA {}", 100.0 * fraction,
                                         format_duration(elapsed), format_duration(eta));
    const int room = std::max(1, columns - 1);
    const int bar = room - int(tail.size()) - 3; // "[", "] "
    if (bar < kMinBarWidth) return tail.substr(0, std::size_t(room));
    const int fill = int(std::clamp(fraction, 0.0, 1.0) * bar);
    return "[" + std::string(std::size_t(fill), '=') + std::string(std::size_t(bar - fill), ' ') +
           "] " + tail;
}

int terminal_columns() {
    winsize ws{};
    if (::ioctl(2, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
    if (const char* env = std::getenv("COLUMNS")) {
        const int c = std::atoi(env);
        if (c > 0) return c;
    }
    return kDefaultColumns;
}

Progress::Progress(std::uint64_t total, ProgressMode mode, double time_budget)
    : total_(total), mode_(mode), time_budget_(time_budget) {
    if (mode_ == ProgressMode::None || mode_ == ProgressMode::Auto) return;
    clock_.restart();
    thread_ = std::thread([this] { loop(); });
}

Progress::~Progress() {
    finish();
}

void Progress::finish() {
    if (!thread_.joinable()) return;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
    print(true);
}

void Progress::loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto period = mode_ == ProgressMode::Bar    ? kBarPeriod
                        : mode_ == ProgressMode::Json ? kJsonPeriod
                                                      : kLinesPeriod;
    while (!cv_.wait_for(lock, period, [this] { return stop_; }))
        print(false);
}

double progress_fraction(std::uint64_t done, std::uint64_t total, double elapsed,
                         double time_budget, double reported) {
    total = std::max(done, total);
    double frac = total ? double(done) / double(total) : 1.0;
    // The time budget ends the render at the latest when it runs out.
    if (time_budget > 0.0 && frac < 1.0)
        frac = std::max(frac, std::min(1.0, elapsed / time_budget));
    return std::max(frac, reported);
}

void Progress::print(bool final) {
    const std::uint64_t done = done_.load();
    const std::uint64_t total = std::max(done, total_.load());
    const double el = clock_.seconds();
    // The ETA follows the current estimate of the total; the fraction shown never goes back.
    const double estimate = total ? double(done) / double(total) : 1.0;
    double eta = estimate > 0.0 ? el * (1.0 - estimate) / estimate : 0.0;
    if (time_budget_ > 0.0 && estimate < 1.0) eta = std::min(eta, std::max(0.0, time_budget_ - el));
    const double frac = progress_fraction(done, total, el, time_budget_, reported_.load());
    reported_.store(frac);
    // Only this thread (or finish(), after joining it) reports: no other writer to race.
    if (frac > g_reported.load()) g_reported.store(frac);
    switch (mode_) {
    case ProgressMode::Bar:
        fmt::print(stderr, "\r{}{}", progress_bar_line(frac, el, eta, terminal_columns()),
                   final ? "\n" : "");
        std::fflush(stderr);
        break;
    case ProgressMode::Lines:
        if (!final) {
            fmt::print(stderr, "progress: {:5.1f}%  {} elapsed  ETA {}\n", 100.0 * frac,
                       format_duration(el), format_duration(eta));
            std::fflush(stderr);
        }
        break;
    case ProgressMode::Json:
        print_progress_event(frac, done, total, el, eta);
        break;
    case ProgressMode::Auto:
    case ProgressMode::None:
        break;
    }
}

} // namespace candela
