#pragma once
// Interrupts of `candela render`: the first SIGINT/SIGTERM asks the render to stop at the next
// pass boundary; the second writes the image of the last finished pass (and its checkpoint) at
// once and ends the process.
#include <atomic>
#include <functional>
#include <thread>

namespace candela::app {

/// Set by the first signal: the render stops at the next pass boundary.
std::atomic<bool>& render_stop_flag();

/// With --progress json on this rank, signals are events on stdout too.
void set_json_signal_events(bool on);

/// Installs the handler for SIGINT and SIGTERM for its lifetime (and clears the stop flag).
class SignalScope {
  public:
    SignalScope();
    ~SignalScope();
    SignalScope(const SignalScope&) = delete;
    SignalScope& operator=(const SignalScope&) = delete;

  private:
    void (*old_int_)(int);
    void (*old_term_)(int);
};

/// Waits, on its own thread, for the second Ctrl-C; then writes the last finished pass (image
/// and checkpoint) with `write` and ends the process at once with the status it returns.
class FastExit {
  public:
    using WriteFn = std::function<int()>;
    explicit FastExit(WriteFn write);
    /// Stops listening: from here on the main thread writes the outputs itself.
    void disarm();
    ~FastExit();
    FastExit(const FastExit&) = delete;
    FastExit& operator=(const FastExit&) = delete;

  private:
    WriteFn write_;
    int fds_[2] = {-1, -1};
    std::thread thread_;
};

} // namespace candela::app
