#pragma once
// candela's one exception type. Library code reports failures by throwing candela::Error (never
// by exit()); src/app/main.cpp catches it and maps its kind to the process exit status.
#include <stdexcept>
#include <string>

namespace candela {

/// What went wrong, coarse enough to choose an exit status (README "Exit status").
enum class ErrorKind {
    Usage = 2,       ///< bad command line
    Scene = 3,       ///< scene file malformed or unsupported
    Io = 4,          ///< file could not be read or written
    Interrupted = 5, ///< stopped by a signal
    Internal = 70,   ///< a bug or an unexpected library failure
};

class Error : public std::runtime_error {
  public:
    Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    ErrorKind kind() const { return kind_; }

  private:
    ErrorKind kind_;
};

/// A place in an input file, for messages of the form `file:line: error: what`.
struct SourceLoc {
    std::string file;
    int line = 0; ///< 1-based; 0 when unknown
    std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

/// The one line a user sees for a failure: `candela: error: [FILE:LINE: ]message`. Library
/// messages come in the forms `file:line: error: what`, `error: what` and `candela: error:
/// what`; all are brought to this shape (README "Exit status").
std::string user_error_line(const std::string& message);

/// The operating system's reason a file cannot be opened for reading ("it is a directory", or
/// strerror of the failed open), "" when it can.
std::string file_read_failure(const std::string& path);

/// Throws Error(kind) with the message `file:line: error: what`.
[[noreturn]] inline void fail_at(ErrorKind kind, const SourceLoc& loc, const std::string& what) {
    throw Error(kind, loc.str() + ": error: " + what);
}

} // namespace candela
