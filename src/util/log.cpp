// Warnings and notes on stderr, counted and de-duplicated, and the log level.
#include "candela/util/log.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <atomic>
#include <cstdio>
#include <fmt/format.h>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace candela {

struct Diagnostics::Impl {
    struct Entry {
        std::string text;
        std::size_t count;
    };
    std::vector<Entry> entries; ///< in first-seen order, which is the order they are printed
    std::unordered_map<std::string, std::size_t> index; ///< text -> position in entries
    std::mutex mutex;
    void add(const std::string& text) {
        std::lock_guard<std::mutex> lock(mutex);
        auto [it, inserted] = index.emplace(text, entries.size());
        if (inserted)
            entries.push_back({text, 1});
        else
            ++entries[it->second].count;
    }
};

Diagnostics::Impl& Diagnostics::impl() const {
    CANDELA_CHECK(impl_ != nullptr, "Diagnostics used after it was moved from");
    return *impl_;
}

Diagnostics::Diagnostics(bool strict) : strict_(strict), impl_(std::make_unique<Impl>()) {}

Diagnostics::Diagnostics(Diagnostics&& other) noexcept
    : strict_(other.strict_), warnings_(other.warnings_.exchange(0)),
      impl_(std::move(other.impl_)) {}

Diagnostics::~Diagnostics() {
    flush();
}

void Diagnostics::warn(const SourceLoc& where, const std::string& what) {
    if (strict_) throw Error(ErrorKind::Scene, where, strict_text(what));
    warnings_.fetch_add(1);
    if (log_level() < LogLevel::Warning) return;
    impl().add(warning_text(where.str() + ": " + what));
}

void Diagnostics::note(const SourceLoc& where, const std::string& what) {
    // Notes are informational: only `-v` (log level verbose) shows them.
    if (log_level() < LogLevel::Verbose) return;
    impl().add("candela: note: " + where.str() + ": " + what);
}

std::size_t Diagnostics::distinct_messages() const {
    if (!impl_) return 0;
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->entries.size();
}

void Diagnostics::flush() {
    if (!impl_) return;
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (const auto& e : impl_->entries) {
        if (e.count > 1)
            fmt::print(stderr, "{} ({} times)\n", e.text, e.count);
        else
            fmt::print(stderr, "{}\n", e.text);
    }
    impl_->entries.clear();
    impl_->index.clear();
}

namespace {
std::atomic<LogLevel> g_level{LogLevel::Info};
}
void set_log_level(LogLevel level) {
    g_level = level;
}
LogLevel log_level() {
    return g_level;
}
LogLevel parse_log_level(const std::string& name) {
    for (LogLevel l : {LogLevel::Error, LogLevel::Warning, LogLevel::Info, LogLevel::Verbose})
        if (name == log_level_name(l)) return l;
    throw Error(ErrorKind::Usage, "--log-level: unknown value '" + name +
                                      "' (expected one of: error, warning, info, verbose)");
}
const char* log_level_name(LogLevel level) {
    switch (level) {
    case LogLevel::Error:
        return "error";
    case LogLevel::Warning:
        return "warning";
    case LogLevel::Info:
        return "info";
    case LogLevel::Verbose:
        return "verbose";
    }
    return "info";
}
void set_verbose(bool on) {
    g_level = on ? LogLevel::Verbose : LogLevel::Warning;
}
bool verbose() {
    return g_level.load() >= LogLevel::Info;
}

std::string warning_text(const std::string& what, const char* who) {
    return std::string(who) + ": warning: " + what;
}

std::string strict_text(const std::string& what) {
    return what + " (--strict)";
}

void print_warning(const std::string& what, const char* who) {
    if (log_level() < LogLevel::Warning) return;
    const std::string line = warning_text(what, who) + "\n";
    std::fputs(line.c_str(), stderr);
}

void warn_or_refuse(const std::string& what, bool strict, ErrorKind kind) {
    if (strict) throw Error(kind, strict_text(what));
    print_warning(what);
}

} // namespace candela
