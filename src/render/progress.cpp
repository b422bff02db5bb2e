#include "candela/render/progress.h"

#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
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

} // namespace

ProgressMode parse_progress_mode(const std::string& name) {
    return parse_enum(kProgressModes, "--progress", name);
}

ProgressMode resolve_progress_mode(ProgressMode requested, bool quiet) {
    if (requested == ProgressMode::Json) return requested;
    if (quiet) return ProgressMode::None;
    if (requested == ProgressMode::Auto)
        return ::isatty(2) != 0 ? ProgressMode::Bar : ProgressMode::Lines;
    return requested;
}

std::string json_quote(const std::string& s) {
    return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
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

void Progress::print(bool final) {
    const std::uint64_t done = done_.load();
    const std::uint64_t total = std::max(done, total_.load());
    double frac = total ? double(done) / double(total) : 1.0;
    const double el = clock_.seconds();
    double eta = frac > 0.0 ? el * (1.0 - frac) / frac : 0.0;
    if (time_budget_ > 0.0 && frac < 1.0) {
        // The time budget ends the render at the latest when it runs out.
        frac = std::max(frac, std::min(1.0, el / time_budget_));
        eta = std::min(eta, std::max(0.0, time_budget_ - el));
    }
    switch (mode_) {
    case ProgressMode::Bar: {
        const int width = 40;
        const int fill = int(frac * width);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  %6.1fs elapsed  ETA %6.1fs", fill,
                     "========================================", width - fill, "", 100.0 * frac, el,
                     eta);
        if (final) std::fprintf(stderr, "\n");
        std::fflush(stderr);
        break;
    }
    case ProgressMode::Lines:
        if (!final) {
            std::fprintf(stderr, "progress: %5.1f%%  %.1fs elapsed  ETA %.1fs\n", 100.0 * frac, el,
                         eta);
            std::fflush(stderr);
        }
        break;
    case ProgressMode::Json:
        std::printf("{\"event\":\"progress\",\"fraction\":%.6f,\"samples\":%llu,\"samples_total\":"
                    "%llu,\"elapsed_s\":%.3f,\"eta_s\":%.3f}\n",
                    frac, (unsigned long long)done, (unsigned long long)total, el, eta);
        std::fflush(stdout);
        break;
    case ProgressMode::Auto:
    case ProgressMode::None:
        break;
    }
}

} // namespace candela
