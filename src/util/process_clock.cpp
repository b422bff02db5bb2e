// Time since the process started, read from the kernel's record of the process start.
#include "candela/util/process_clock.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>
#include <unistd.h>

namespace candela {

namespace {

using Clock = std::chrono::steady_clock;

/// The earliest moment the program itself can note: its static initialisation.
const Clock::time_point g_static_init = Clock::now();

/// Field 22 of /proc/self/stat, the process's start in clock ticks since boot; -1 when it
/// cannot be read. The second field (the command name, in parentheses) may hold spaces, so the
/// fields are counted from the last ')'.
long long start_ticks_since_boot() {
    std::FILE* f = std::fopen("/proc/self/stat", "r");
    if (!f) return -1;
    char buf[1024];
    const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
    std::fclose(f);
    buf[n] = '\0';
    const std::string stat(buf);
    std::size_t pos = stat.rfind(')');
    if (pos == std::string::npos) return -1;
    // A space comes before each of fields 3, 4, ... after ')': the 20th is field 22's.
    constexpr int kStartField = 22, kFirstFieldAfterName = 3;
    for (int field = kFirstFieldAfterName; field <= kStartField; ++field) {
        pos = stat.find(' ', pos + 1);
        if (pos == std::string::npos) return -1;
    }
    long long ticks = -1;
    if (std::sscanf(stat.c_str() + pos, " %lld", &ticks) != 1) return -1;
    return ticks;
}

/// The process's start on the steady clock, worked out once.
Clock::time_point process_start() {
    const long long ticks = start_ticks_since_boot();
    const long ticks_per_second = ::sysconf(_SC_CLK_TCK);
    timespec boot{};
    if (ticks < 0 || ticks_per_second <= 0 || ::clock_gettime(CLOCK_BOOTTIME, &boot) != 0)
        return g_static_init;
    const Clock::time_point now = Clock::now();
    // The tick count is rounded down: the start lies within the tick, on average at its middle.
    const double start_since_boot = (double(ticks) + 0.5) / double(ticks_per_second);
    const double since_start = double(boot.tv_sec) + 1e-9 * double(boot.tv_nsec) - start_since_boot;
    const Clock::time_point start = now - std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(since_start));
    return std::min(start, g_static_init);
}

} // namespace

double process_seconds() {
    static const Clock::time_point start = process_start();
    return std::chrono::duration<double>(Clock::now() - start).count();
}

} // namespace candela
