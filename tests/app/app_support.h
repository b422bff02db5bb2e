#pragma once
// Running the real `candela` executable (CANDELA_BINARY) from tests: its exit status, its
// stdout and stderr apart, its wall time, a working directory of choice, and signals sent while
// it runs.
#include "../support/temp_dir.h"
#include "candela/util/stopwatch.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <poll.h>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace candela::test {

/// A running candela process with its stdout and stderr on pipes.
class Proc {
  public:
    using Clock = std::chrono::steady_clock;

    explicit Proc(const std::vector<std::string>& args, const std::string& cwd = "") {
        int out[2], err[2];
        REQUIRE(::pipe(out) == 0);
        REQUIRE(::pipe(err) == 0);
        clock_.restart();
        pid_ = ::fork();
        REQUIRE(pid_ >= 0);
        if (pid_ == 0) {
            ::dup2(out[1], 1);
            ::dup2(err[1], 2);
            ::close(out[0]);
            ::close(err[0]);
            ::close(out[1]);
            ::close(err[1]);
            if (!cwd.empty() && ::chdir(cwd.c_str()) != 0) ::_exit(127);
            std::vector<std::string> copy = args;
            std::string bin = CANDELA_BINARY;
            std::vector<char*> argv{bin.data()};
            for (std::string& a : copy)
                argv.push_back(a.data());
            argv.push_back(nullptr);
            ::execv(bin.c_str(), argv.data());
            ::_exit(127);
        }
        ::close(out[1]);
        ::close(err[1]);
        out_fd_ = out[0];
        err_fd_ = err[0];
    }
    ~Proc() {
        if (!done_) {
            ::kill(pid_, SIGKILL);
            int st = 0;
            ::waitpid(pid_, &st, 0);
        }
        ::close(out_fd_);
        ::close(err_fd_);
    }
    Proc(const Proc&) = delete;
    Proc& operator=(const Proc&) = delete;

    void signal(int sig) { ::kill(pid_, sig); }

    /// Reads until stdout (or stderr) contains `text` or `seconds` pass; true when found.
    bool wait_for(const std::string& text, double seconds, bool on_stderr = false) {
        const Clock::time_point end = Clock::now() + to_duration(seconds);
        const std::string& s = on_stderr ? err : out;
        while (s.find(text) == std::string::npos) {
            if (Clock::now() >= end || !pump(end)) return s.find(text) != std::string::npos;
        }
        return true;
    }

    /// Waits for the exit (at most `seconds`, then kills); returns the exit status, or -1 when
    /// it did not exit normally or in time.
    int wait(double seconds = 600.0) {
        const Clock::time_point end = Clock::now() + to_duration(seconds);
        while (pump(end)) {
        }
        int st = 0;
        while (true) {
            pid_t r = ::waitpid(pid_, &st, WNOHANG);
            if (r == pid_) break;
            if (Clock::now() >= end) {
                ::kill(pid_, SIGKILL);
                ::waitpid(pid_, &st, 0);
                done_ = true;
                return -1;
            }
            ::usleep(2000);
        }
        done_ = true;
        seconds_ = clock_.seconds();
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }

    double seconds() const { return seconds_; }

    std::string out, err;

  private:
    static Clock::duration to_duration(double seconds) {
        return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    }

    /// Reads what is available on either pipe, waiting at most until `end`; false when both
    /// pipes are closed or time is up.
    bool pump(Clock::time_point end) {
        pollfd fds[2] = {{out_fd_, POLLIN, 0}, {err_fd_, POLLIN, 0}};
        int open_fds = (out_open_ ? 1 : 0) + (err_open_ ? 1 : 0);
        if (open_fds == 0) return false;
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
        if (left.count() <= 0) return false;
        fds[0].fd = out_open_ ? out_fd_ : -1;
        fds[1].fd = err_open_ ? err_fd_ : -1;
        if (::poll(fds, 2, int(std::min<long long>(left.count(), 100))) < 0) return false;
        char buf[4096];
        for (int k = 0; k < 2; ++k) {
            if (!(fds[k].revents & (POLLIN | POLLHUP))) continue;
            ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
            if (n > 0)
                (k == 0 ? out : err).append(buf, std::size_t(n));
            else
                (k == 0 ? out_open_ : err_open_) = false;
        }
        return true;
    }

    pid_t pid_ = -1;
    int out_fd_ = -1, err_fd_ = -1;
    bool out_open_ = true, err_open_ = true, done_ = false;
    double seconds_ = 0.0;
    candela::Stopwatch clock_;
};

struct Result {
    int status = -1;
    std::string out, err;
    double seconds = 0.0;
};

/// Runs candela to completion.
inline Result run_candela(const std::vector<std::string>& args, const std::string& cwd = "") {
    Proc p(args, cwd);
    Result r;
    r.status = p.wait();
    r.out = p.out;
    r.err = p.err;
    r.seconds = p.seconds();
    return r;
}

/// `a` followed by `b`: a command line from its parts.
inline std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

/// The contents of a file.
inline std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The lines of `text`.
inline std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        lines.push_back(text.substr(start, end - start));
        start = end + 1;
    }
    return lines;
}

/// Checks a refusal: exit status `status` and one line on stderr, `candela: error: ...`
/// containing `needle`.
inline void check_one_line(const Result& r, int status, const std::string& needle) {
    INFO("stderr: " << r.err);
    CHECK(r.status == status);
    const std::vector<std::string> lines = lines_of(r.err);
    REQUIRE(lines.size() == 1);
    CHECK_THAT(lines[0], Catch::StartsWith("candela: error: "));
    CHECK_THAT(lines[0], Catch::Contains(needle));
}

} // namespace candela::test
