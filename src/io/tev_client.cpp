// The tev viewer's TCP client (io/tev_client.h), on POSIX sockets.
#include "candela/io/tev_client.h"

#include "candela/util/error.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>
#include <utility>

namespace candela {

namespace {

/// A packet being built: its length is patched into the first four bytes at the end.
class PacketWriter {
  public:
    explicit PacketWriter(TevPacket type) {
        u32(0);
        bytes_.push_back(static_cast<unsigned char>(type));
    }
    void flag(bool b) { bytes_.push_back(b ? 1 : 0); }
    void text(const std::string& s) {
        bytes_.insert(bytes_.end(), s.begin(), s.end());
        bytes_.push_back(0);
    }
    void u32(std::uint32_t v) {
        for (int k = 0; k < 4; ++k)
            bytes_.push_back(static_cast<unsigned char>(v >> (8 * k)));
    }
    void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
    void i64(std::int64_t v) {
        const auto u = static_cast<std::uint64_t>(v);
        for (int k = 0; k < 8; ++k)
            bytes_.push_back(static_cast<unsigned char>(u >> (8 * k)));
    }
    /// `n` floats, each as the little-endian bytes of its IEEE 754 bits.
    void floats(const float* f, std::size_t n) {
        std::size_t at = bytes_.size();
        bytes_.resize(at + 4 * n);
        for (std::size_t i = 0; i < n; ++i) {
            std::uint32_t u;
            std::memcpy(&u, &f[i], sizeof u);
            for (int k = 0; k < 4; ++k)
                bytes_[at++] = static_cast<unsigned char>(u >> (8 * k));
        }
    }
    std::vector<unsigned char>& finish() {
        const auto n = static_cast<std::uint32_t>(bytes_.size());
        for (int k = 0; k < 4; ++k)
            bytes_[std::size_t(k)] = static_cast<unsigned char>(n >> (8 * k));
        return bytes_;
    }

  private:
    std::vector<unsigned char> bytes_;
};

/// A socket descriptor closed on scope exit unless released.
struct SocketGuard {
    int fd;
    ~SocketGuard() {
        if (fd >= 0) ::close(fd);
    }
    int release() { return std::exchange(fd, -1); }
};

/// Connects `fd` to `addr`, waiting at most `seconds`; returns 0 or the errno of the failure.
int connect_within(int fd, const addrinfo& addr, double seconds) {
    const int flags = ::fcntl(fd, F_GETFL, 0);
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) != 0) return errno;
    if (::connect(fd, addr.ai_addr, addr.ai_addrlen) != 0) {
        if (errno != EINPROGRESS) return errno;
        pollfd p{fd, POLLOUT, 0};
        const int ready = ::poll(&p, 1, int(std::ceil(seconds * 1000.0)));
        if (ready == 0) return ETIMEDOUT;
        if (ready < 0) return errno;
        int err = 0;
        socklen_t len = sizeof err;
        if (::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0) return errno;
        if (err != 0) return err;
    }
    return ::fcntl(fd, F_SETFL, flags) == 0 ? 0 : errno;
}

} // namespace

std::string TevAddress::str() const {
    const bool v6 = host.find(':') != std::string::npos;
    return (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

std::optional<TevAddress> parse_tev_address(const std::string& text) {
    const std::size_t colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0) return std::nullopt;
    std::string host = text.substr(0, colon);
    const std::string port = text.substr(colon + 1);
    if (host.size() > 2 && host.front() == '[' && host.back() == ']')
        host = host.substr(1, host.size() - 2);
    if (host.empty() || port.empty() || port.size() > 5 ||
        !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
    const int p = std::stoi(port);
    if (p < 1 || p > 65535) return std::nullopt;
    return TevAddress{host, p};
}

TevClient::TevClient(const TevAddress& address, double connect_seconds, double send_seconds)
    : where_("display server " + address.str()) {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    const int gai =
        ::getaddrinfo(address.host.c_str(), std::to_string(address.port).c_str(), &hints, &found);
    if (gai != 0) throw Error(ErrorKind::Io, where_ + ": " + ::gai_strerror(gai));
    std::string why;
    for (addrinfo* a = found; a && fd_ < 0; a = a->ai_next) {
        SocketGuard s{::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol)};
        const int err = s.fd < 0 ? errno : connect_within(s.fd, *a, connect_seconds);
        if (err == 0)
            fd_ = s.release();
        else
            why = std::strerror(err);
    }
    ::freeaddrinfo(found);
    if (fd_ < 0) throw Error(ErrorKind::Io, where_ + ": cannot connect: " + why);
    timeval tv{};
    tv.tv_sec = static_cast<time_t>(send_seconds);
    tv.tv_usec = static_cast<suseconds_t>((send_seconds - double(tv.tv_sec)) * 1e6);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    const int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

TevClient::~TevClient() {
    if (fd_ >= 0) ::close(fd_);
}

void TevClient::abort() {
    ::shutdown(fd_, SHUT_RDWR);
}

void TevClient::send_packet(const std::vector<unsigned char>& packet) {
    std::size_t sent = 0;
    while (sent < packet.size()) {
        const ssize_t n = ::send(fd_, packet.data() + sent, packet.size() - sent, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const bool timed_out = n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
            throw Error(ErrorKind::Io, where_ + ": " +
                                           (timed_out ? std::string("it stopped reading")
                                                      : std::string(std::strerror(errno))));
        }
        sent += std::size_t(n);
    }
}

void TevClient::create_image(const std::string& name, int width, int height,
                             const std::vector<std::string>& channels, bool grab_focus) {
    PacketWriter p(TevPacket::CreateImage);
    p.flag(grab_focus);
    p.text(name);
    p.i32(width);
    p.i32(height);
    p.i32(static_cast<std::int32_t>(channels.size()));
    for (const std::string& c : channels)
        p.text(c);
    send_packet(p.finish());
}

void TevClient::update_image(const std::string& name, const std::vector<std::string>& channels,
                             int x, int y, int width, int height,
                             const std::vector<float>& pixels) {
    const std::size_t nc = channels.size();
    for (int ty = 0; ty < height; ty += kTevTileSize)
        for (int tx = 0; tx < width; tx += kTevTileSize) {
            const int w = std::min(kTevTileSize, width - tx);
            const int h = std::min(kTevTileSize, height - ty);
            PacketWriter p(TevPacket::UpdateImage);
            p.flag(false);
            p.text(name);
            p.i32(static_cast<std::int32_t>(nc));
            for (const std::string& c : channels)
                p.text(c);
            p.i32(x + tx);
            p.i32(y + ty);
            p.i32(w);
            p.i32(h);
            // The tile's pixels interleaved as in `pixels`: channel c at offset c, stride nc.
            for (std::size_t c = 0; c < nc; ++c)
                p.i64(static_cast<std::int64_t>(c));
            for (std::size_t c = 0; c < nc; ++c)
                p.i64(static_cast<std::int64_t>(nc));
            for (int row = ty; row < ty + h; ++row)
                p.floats(&pixels[(std::size_t(row) * width + tx) * nc], std::size_t(w) * nc);
            send_packet(p.finish());
        }
}

} // namespace candela
