#pragma once
// The one rule every command follows before it writes a file: no file it writes may be a file
// it reads, or another file it writes. Paths name the same file when they reach the same file
// (device and inode: "./a.exr", "a.exr", a hard link or a symbolic link to it), or, for a file
// not there yet, when their absolute, normalized paths (symbolic links of the existing part
// resolved) agree.
#include <string>
#include <utility>
#include <vector>

namespace candela {

/// A file a command reads or writes, and how a message names it: the flag ("-f/--output"), or
/// the argument ("the image being compared").
struct NamedPath {
    std::string role;
    std::string path; ///< "" = not used this time (skipped)
};

/// Whether `a` and `b` name the same file, as the rule above decides it.
bool same_file_or_path(const std::string& a, const std::string& b);

/// Throws Error(Usage) "OUTPUT-ROLE and OTHER-ROLE name the same file PATH" when an output
/// names the same file as an input or an earlier output. Touches no file.
void check_distinct_files(const std::vector<NamedPath>& inputs,
                          const std::vector<NamedPath>& outputs);

/// `path` with `n` before its extension: "a/b.exr", 1 -> "a/b.1.exr".
std::string numbered_name(const std::string& path, int n);

/// Keeps the files of `paths` that exist under numbered names (numbered_name), one number for
/// all of them, the first that none of them uses yet: each is linked to its new name and then
/// unlinked (renamed where the file system has no links), so no file is ever replaced. Returns
/// the (old, new) names. Throws Error(Io) when a file cannot be kept.
std::vector<std::pair<std::string, std::string>>
keep_numbered_backups(const std::vector<std::string>& paths);

} // namespace candela
