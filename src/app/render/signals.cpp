// The signal handling of `candela render` (signals.h).
#include "signals.h"

#include "candela/util/log.h"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <string>
#include <unistd.h>
#include <vector>

namespace candela::app {

namespace {

// The signal handler only touches lock-free atomics, strings built before it was installed and
// write(2), which are async-signal-safe.

std::atomic<bool> g_stop{false};
std::atomic<int> g_signals{0};
std::atomic<bool> g_fast_exit_armed{false};
std::atomic<int> g_wake_fd{-1};
std::atomic<bool> g_json_events{false}; ///< --progress json on this rank: signals are events too
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

void say(const char* text) {
    if (log_level() >= LogLevel::Warning) {
        ssize_t ignored = ::write(2, text, std::char_traits<char>::length(text));
        (void)ignored;
    }
}

/// The `signal` events of --progress json, [SIGTERM?][what this signal does], each one whole
/// line written by one write(2) so that it never splits another line. Set before a handler is
/// installed (build_signal_events()); the handler only reads them.
const char* g_signal_events[2][3] = {};

void build_signal_events() {
    static const std::vector<std::string> lines = [] {
        const char* const signals[2] = {"SIGINT", "SIGTERM"};
        const char* const actions[3] = {"stop after the current pass",
                                        "write the last finished pass and stop now",
                                        "already stopping"};
        std::vector<std::string> out;
        for (const char* signal : signals)
            for (int action = 0; action < 3; ++action) {
                nlohmann::ordered_json e = {{"event", "signal"}, {"signal", signal}};
                if (action < 2) e["count"] = action + 1;
                e["action"] = actions[action];
                out.push_back(e.dump() + "\n");
            }
        return out;
    }();
    for (int s = 0; s < 2; ++s)
        for (int action = 0; action < 3; ++action)
            g_signal_events[s][action] = lines[std::size_t(s * 3 + action)].c_str();
}

void json_signal_event(int sig, int action) {
    if (!g_json_events.load()) return;
    const char* line = g_signal_events[sig == SIGTERM ? 1 : 0][action];
    ssize_t ignored = ::write(1, line, std::char_traits<char>::length(line));
    (void)ignored;
}

extern "C" void on_signal(int sig) {
    const int n = g_signals.fetch_add(1) + 1;
    g_stop.store(true);
    const bool fast_exit = n >= 2 && g_fast_exit_armed.load();
    json_signal_event(sig, n == 1 ? 0 : n == 2 && fast_exit ? 1 : 2);
    if (n == 1) {
        say("\ncandela: stopping after the current pass (Ctrl-C again to write what is finished "
            "and stop now)\n");
        return;
    }
    if (fast_exit) {
        const int fd = g_wake_fd.load();
        if (fd >= 0) {
            const char byte = 's';
            ssize_t ignored = ::write(fd, &byte, 1);
            (void)ignored;
        }
    } else if (n == 2) {
        say("\ncandela: already writing the image; it will be done in a moment\n");
    }
}

} // namespace

std::atomic<bool>& render_stop_flag() {
    return g_stop;
}

void set_json_signal_events(bool on) {
    g_json_events = on;
}

SignalScope::SignalScope() {
    build_signal_events();
    g_stop = false;
    g_signals = 0;
    old_int_ = std::signal(SIGINT, on_signal);
    old_term_ = std::signal(SIGTERM, on_signal);
}

SignalScope::~SignalScope() {
    std::signal(SIGINT, old_int_);
    std::signal(SIGTERM, old_term_);
}

FastExit::FastExit(WriteFn write) : write_(std::move(write)) {
    if (::pipe(fds_) != 0) {
        fds_[0] = fds_[1] = -1;
        return;
    }
    g_wake_fd = fds_[1];
    thread_ = std::thread([this] {
        char c = 0;
        while (::read(fds_[0], &c, 1) < 0 && errno == EINTR) {
        }
        if (c != 's') return;
        const int status = write_();
        std::fflush(stdout);
        std::fflush(stderr);
        ::_exit(status);
    });
    g_fast_exit_armed = true;
}

void FastExit::disarm() {
    if (!thread_.joinable()) return;
    g_fast_exit_armed = false;
    const char quit = 'q';
    ssize_t ignored = ::write(fds_[1], &quit, 1);
    (void)ignored;
    thread_.join();
}

FastExit::~FastExit() {
    disarm();
    g_wake_fd = -1;
    if (fds_[0] >= 0) ::close(fds_[0]);
    if (fds_[1] >= 0) ::close(fds_[1]);
}

} // namespace candela::app
