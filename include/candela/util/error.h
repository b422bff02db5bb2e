#pragma once
// candela's one exception type. Library code reports failures by throwing candela::Error (never
// by exit()); src/app/main.cpp catches it and maps its kind to the process exit status. An Error
// is data: its kind, where it happened (a file, and a line in it, when there is one) and a plain
// message. The one line a user sees is made of those once, at the edge (error_line()).
#include <optional>
#include <stdexcept>
#include <string>

namespace candela {

/// What went wrong, coarse enough to choose an exit status (docs/usage.md "Exit status").
enum class ErrorKind {
    Usage = 2,       ///< bad command line
    Scene = 3,       ///< scene file malformed or unsupported
    Io = 4,          ///< file could not be read or written
    Interrupted = 5, ///< stopped by a signal
    Internal = 70,   ///< a bug or an unexpected library failure
};

/// A place in an input file: `file` alone, or `file:line`.
struct SourceLoc {
    std::string file;
    int line = 0; ///< 1-based; 0 when unknown
    std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

class Error : public std::runtime_error {
  public:
    /// A failure that concerns no file in particular.
    Error(ErrorKind kind, std::string message);
    /// A failure in the file `where.file` (at `where.line` when it is > 0).
    Error(ErrorKind kind, SourceLoc where, std::string message);

    ErrorKind kind() const { return kind_; }
    /// What went wrong, without the place: "checkpoint is truncated".
    const std::string& message() const { return message_; }
    /// The file (and line) the failure concerns, if any.
    const std::optional<SourceLoc>& where() const { return where_; }
    // what() is the place and the message, "scene.dae:12: unknown element" (located_text()).

  private:
    ErrorKind kind_;
    std::optional<SourceLoc> where_;
    std::string message_;
};

/// `FILE[:LINE]: message`, or the message alone when the error has no place.
std::string located_text(const std::optional<SourceLoc>& where, const std::string& message);

/// The one line a user sees for a failure: `candela: error: [FILE[:LINE]: ]message` (docs/usage.md
/// "Exit status").
std::string error_line(const Error& e);
/// The same failure reported as a warning (a failed periodic checkpoint, which the render
/// survives): `candela: warning: [FILE[:LINE]: ]message`.
std::string warning_line(const Error& e);

/// The operating system's reason a file cannot be opened for reading ("it is a directory", or
/// strerror of the failed open), "" when it can.
std::string file_read_failure(const std::string& path);

} // namespace candela
