#pragma once
// Wall-clock time elapsed since a starting point, on the monotonic clock.
#include <chrono>

namespace candela {

class Stopwatch {
  public:
    using Clock = std::chrono::steady_clock;

    /// Starts timing now.
    Stopwatch() : start_(Clock::now()) {}

    /// Starts timing again from now.
    void restart() { start_ = Clock::now(); }

    /// Seconds since construction or the last restart().
    double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  private:
    Clock::time_point start_;
};

} // namespace candela
