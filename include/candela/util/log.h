#pragma once
// Diagnostics on stderr. Warnings are de-duplicated by message text so that a repeated problem
// (say, 10,000 dropped degenerate triangles in one mesh) is reported once with a count. Lines
// read `candela: warning: FILE:LINE: what` and `candela: note: FILE:LINE: what`, the shape of
// error lines (util/error.h). Any thread may warn or note at the same time as others.
#include "candela/util/error.h"

#include <atomic>
#include <cstddef>
#include <memory>
#include <string>

namespace candela {

class Diagnostics {
  public:
    /// When strict, warn() throws Error(Scene) instead of recording (the `--strict` flag).
    explicit Diagnostics(bool strict = false);
    /// Records a warning about `where`; identical messages are counted, not repeated. Printed at
    /// log level warning and above.
    void warn(const SourceLoc& where, const std::string& what);
    /// An informational line, printed once, and only at log level verbose (`-v`).
    void note(const SourceLoc& where, const std::string& what);
    /// Prints every recorded warning and note to stderr, once each, with repeat counts.
    void flush();
    /// Warnings recorded so far (repeats included), at any log level.
    std::size_t warning_count() const { return warnings_.load(); }
    /// Distinct warning and note texts recorded since the last flush().
    std::size_t distinct_messages() const;
    bool strict() const { return strict_; }
    /// Prints what is still recorded (flush()).
    ~Diagnostics();
    /// Not copyable: each recorded message is printed once, by its one owner. Moving hands the
    /// messages over; the moved-from object prints nothing and may not record again.
    Diagnostics(const Diagnostics&) = delete;
    Diagnostics& operator=(const Diagnostics&) = delete;
    Diagnostics(Diagnostics&& other) noexcept;
    Diagnostics& operator=(Diagnostics&&) = delete;

  private:
    struct Impl;
    bool strict_;
    std::atomic<std::size_t> warnings_{0};
    std::unique_ptr<Impl> impl_; ///< made by the constructor, so no thread races to make it
    Impl& impl() const;
};

/// How much candela says on stderr (`--log-level`, `-q`, `-v`), each level including the ones
/// before it: errors; warnings (`-q`); progress, summaries and the files written (the default);
/// notes about the scene and what a render leaves out (`-v`).
enum class LogLevel { Error = 0, Warning = 1, Info = 2, Verbose = 3 };

void set_log_level(LogLevel level);
LogLevel log_level();
/// Parses "error", "warning", "info" or "verbose"; throws Error(Usage) naming the flag.
LogLevel parse_log_level(const std::string& name);
const char* log_level_name(LogLevel level);

/// The one shape of a warning line, `WHO: warning: WHAT` (WHO a command, "candela" by
/// default; Diagnostics and warning_line() put a file and line before WHAT).
std::string warning_text(const std::string& what, const char* who = "candela");
/// What a warning becomes under --strict: the message of the Error that stops the run.
std::string strict_text(const std::string& what);
/// Prints warning_text() on stderr at log level warning and above.
void print_warning(const std::string& what, const char* who = "candela");
/// A warning that --strict turns into an error: throws Error(kind, strict_text(what)) when
/// `strict`, else print_warning().
void warn_or_refuse(const std::string& what, bool strict, ErrorKind kind);

/// set_verbose(true) shows everything (LogLevel::Verbose), set_verbose(false) only errors and
/// warnings (LogLevel::Warning).
void set_verbose(bool on);
/// Progress and summaries are printed (log level info or above).
bool verbose();

} // namespace candela
