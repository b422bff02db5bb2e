// The rule that no output of a command replaces one of its inputs or another of its outputs
// (output_paths.h).
#include "output_paths.h"

#include "candela/util/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unistd.h>

namespace candela {

namespace fs = std::filesystem;

namespace {

/// `p` absolute and normal, with the symbolic links of its existing part resolved.
fs::path resolved(const std::string& p) {
    std::error_code ec;
    fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
    if (ec) r = fs::absolute(p, ec).lexically_normal();
    return r;
}

} // namespace

bool same_file_or_path(const std::string& a, const std::string& b) {
    if (a.empty() || b.empty()) return false;
    std::error_code ec;
    const bool a_exists = fs::exists(a, ec), b_exists = fs::exists(b, ec);
    if (a_exists && b_exists) return fs::equivalent(a, b, ec) && !ec;
    // One is there and the other is not: two files, unless a dangling name resolves to it.
    return resolved(a) == resolved(b);
}

void check_distinct_files(const std::vector<NamedPath>& inputs,
                          const std::vector<NamedPath>& outputs) {
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const NamedPath& out = outputs[i];
        if (out.path.empty()) continue;
        auto refuse = [&out](const NamedPath& other) {
            throw Error(ErrorKind::Usage, out.role + " and " + other.role + " name the same file " +
                                              out.path +
                                              "; refusing to write it (nothing was written)");
        };
        for (const NamedPath& in : inputs)
            if (same_file_or_path(out.path, in.path)) refuse(in);
        for (std::size_t j = 0; j < i; ++j)
            if (same_file_or_path(out.path, outputs[j].path)) refuse(outputs[j]);
    }
}

std::string numbered_name(const std::string& path, int n) {
    const fs::path p(path);
    return (p.parent_path() /
            (p.stem().string() + "." + std::to_string(n) + p.extension().string()))
        .string();
}

std::vector<std::pair<std::string, std::string>>
keep_numbered_backups(const std::vector<std::string>& paths) {
    std::vector<std::string> present;
    std::error_code ec;
    for (const std::string& p : paths)
        if (fs::exists(p, ec)) present.push_back(p);
    std::vector<std::pair<std::string, std::string>> kept;
    if (present.empty()) return kept;
    // The first number free for every file kept; should another process take a name meanwhile,
    // link fails with EEXIST and that file takes the next number.
    int first = 1;
    for (bool free = false; !free; first += free ? 0 : 1) {
        free = true;
        for (const std::string& p : present)
            free = free && !fs::exists(numbered_name(p, first), ec);
    }
    for (const std::string& p : present)
        for (int n = first;; ++n) {
            const std::string to = numbered_name(p, n);
            if (::link(p.c_str(), to.c_str()) == 0) {
                ::unlink(p.c_str());
            } else if (errno == EEXIST) {
                continue;
            } else if (fs::exists(to, ec)) {
                continue;
            } else if (std::rename(p.c_str(), to.c_str()) != 0) { // no links on this file system
                throw Error(ErrorKind::Io, SourceLoc{p},
                            "cannot keep the earlier file as " + to + ": " + std::strerror(errno) +
                                " (nothing was written)");
            }
            kept.emplace_back(p, to);
            break;
        }
    return kept;
}

} // namespace candela
