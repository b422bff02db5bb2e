#pragma once
// Diagnostics on stderr. Warnings are de-duplicated by message text so that a repeated problem
// (say, 10,000 dropped degenerate triangles in one mesh) is reported once with a count.
#include <cstddef>
#include <string>

namespace candela {

class Diagnostics {
  public:
    /// When strict, warn() throws Error(Scene) instead of recording (the `--strict` flag).
    explicit Diagnostics(bool strict = false) : strict_(strict) {}
    /// Records a warning `where: warning: what`; identical messages are counted, not repeated.
    void warn(const std::string& where, const std::string& what);
    /// An informational line (`note:`), printed once.
    void note(const std::string& where, const std::string& what);
    /// Prints every recorded warning and note to stderr, once each, with repeat counts.
    void flush();
    std::size_t warning_count() const { return warnings_; }
    /// Distinct warning and note texts recorded since the last flush().
    std::size_t distinct_messages() const;
    bool strict() const { return strict_; }
    ~Diagnostics();

  private:
    struct Impl;
    bool strict_;
    std::size_t warnings_ = 0;
    Impl* impl_ = nullptr;
    Impl& impl();
};

/// Global verbosity for progress and summaries (`--quiet` sets it to false).
void set_verbose(bool on);
bool verbose();

} // namespace candela
