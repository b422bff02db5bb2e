// A render one can watch: --write-every writes the image while the render runs and leaves the
// final image as it was; --display-server streams the film to a tev viewer, here a small server
// in the test that decodes tev's packets (the layout of io/tev_client.h, read from tev's
// src/Ipc.cpp) and puts the image back together; a viewer that is absent or goes away costs one
// warning. Runs the real `candela` executable.
#include "../support/cs184.h"
#include "app_support.h"

#include "candela/app/cli.h"
#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <arpa/inet.h>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

using namespace candela;
using namespace candela::test;

namespace {

const std::string kBox = project_scene("cornell-box.dae");

/// The longest a test waits for a render's first image or for its viewer's connection: a
/// 32 x 24 pass takes milliseconds, the image module's load a fraction of a second, even on a
/// loaded machine.
constexpr double kWaitSeconds = 60.0;

/// The lines of `text` that contain `needle`.
std::size_t count_lines(const std::string& text, const std::string& needle) {
    std::size_t n = 0;
    for (const std::string& line : lines_of(text))
        n += line.find(needle) != std::string::npos ? 1 : 0;
    return n;
}

/// Every channel of every pixel of `a` and `b` holds the same float.
void check_same_pixels(const ImageData& a, const ImageData& b) {
    REQUIRE(a.channel_names == b.channel_names);
    REQUIRE(a.width == b.width);
    REQUIRE(a.height == b.height);
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
}

/// A TCP socket listening on 127.0.0.1 at an ephemeral port; sets `port`.
int listen_on_loopback(int& port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(fd >= 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
    REQUIRE(::listen(fd, 1) == 0);
    socklen_t len = sizeof addr;
    REQUIRE(::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0);
    port = ntohs(addr.sin_port);
    return fd;
}

/// A stand-in for tev: listens on 127.0.0.1 at an ephemeral port, takes one connection and
/// keeps every byte it receives until the peer closes (or, with `close_after`, closes the
/// connection itself once it has that many bytes: a viewer that goes away).
class FakeViewer {
  public:
    explicit FakeViewer(std::size_t close_after = 0) : close_after_(close_after) {
        listen_fd_ = listen_on_loopback(port_);
        thread_ = std::thread([this] { serve(); });
    }
    ~FakeViewer() {
        if (thread_.joinable()) thread_.join();
        ::close(listen_fd_);
    }
    std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
    /// Waits for the connection's end; the bytes received.
    const std::vector<unsigned char>& received() {
        if (thread_.joinable()) thread_.join();
        return bytes_;
    }
    bool connected() const { return connected_; }

  private:
    void serve() {
        const auto end =
            std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitSeconds);
        auto left_ms = [&end] {
            return int(std::max<long long>(0, std::chrono::duration_cast<std::chrono::milliseconds>(
                                                  end - std::chrono::steady_clock::now())
                                                  .count()));
        };
        pollfd p{listen_fd_, POLLIN, 0};
        if (::poll(&p, 1, left_ms()) != 1) return;
        const int fd = ::accept(listen_fd_, nullptr, nullptr);
        if (fd < 0) return;
        connected_ = true;
        unsigned char buf[65536];
        while (close_after_ == 0 || bytes_.size() < close_after_) {
            pollfd q{fd, POLLIN, 0};
            if (::poll(&q, 1, left_ms()) != 1) break;
            const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
            if (n <= 0) break;
            bytes_.insert(bytes_.end(), buf, buf + n);
        }
        ::close(fd);
    }

    std::size_t close_after_;
    int listen_fd_ = -1;
    int port_ = 0;
    bool connected_ = false;
    std::vector<unsigned char> bytes_;
    std::thread thread_;
};

/// Reads tev's packets in order: little-endian numbers, NUL-terminated strings.
class PacketReader {
  public:
    PacketReader(const unsigned char* p, std::size_t n) : p_(p), n_(n) {}
    std::size_t left() const { return n_ - at_; }
    template <typename T> T number() {
        REQUIRE(left() >= sizeof(T));
        std::uint64_t u = 0;
        for (std::size_t k = 0; k < sizeof(T); ++k)
            u |= std::uint64_t(p_[at_ + k]) << (8 * k);
        at_ += sizeof(T);
        T v;
        if constexpr (sizeof(T) == 4) {
            const auto u32 = std::uint32_t(u);
            std::memcpy(&v, &u32, sizeof v);
        } else {
            std::memcpy(&v, &u, sizeof v);
        }
        return v;
    }
    std::uint8_t byte() {
        REQUIRE(left() >= 1);
        return p_[at_++];
    }
    std::string text() {
        std::string s;
        while (true) {
            const char c = char(byte());
            if (c == '\0') return s;
            s += c;
        }
    }

  private:
    const unsigned char* p_;
    std::size_t n_, at_ = 0;
};

/// The image a viewer would show after the packets in `bytes`: R, G, B of the one image they
/// create, row 0 at the top.
struct ViewerImage {
    std::string name;
    int width = 0, height = 0;
    std::vector<float> rgb;
    std::vector<bool> written; ///< per pixel: an update covered it
    int creates = 0, updates = 0;
};

ViewerImage decode(const std::vector<unsigned char>& bytes) {
    ViewerImage img;
    std::size_t at = 0;
    while (at < bytes.size()) {
        REQUIRE(bytes.size() - at >= 5);
        PacketReader head(&bytes[at], 4);
        const auto length = head.number<std::uint32_t>();
        REQUIRE(length >= 5);
        REQUIRE(at + length <= bytes.size());
        PacketReader r(&bytes[at + 4], length - 4);
        const std::uint8_t type = r.byte();
        if (type == 4) { // create image
            ++img.creates;
            r.byte(); // grab focus
            img.name = r.text();
            img.width = r.number<std::int32_t>();
            img.height = r.number<std::int32_t>();
            const auto channels = r.number<std::int32_t>();
            std::vector<std::string> names;
            for (int c = 0; c < channels; ++c)
                names.push_back(r.text());
            CHECK(names == std::vector<std::string>{"R", "G", "B"});
            img.rgb.assign(std::size_t(img.width) * img.height * 3, 0.f);
            img.written.assign(std::size_t(img.width) * img.height, false);
        } else {
            REQUIRE(type == 6); // update image, with channel offsets and strides
            REQUIRE(img.creates > 0);
            ++img.updates;
            r.byte(); // grab focus
            CHECK(r.text() == img.name);
            const auto channels = r.number<std::int32_t>();
            REQUIRE(channels == 3);
            std::vector<int> index;
            for (int c = 0; c < channels; ++c) {
                const std::string name = r.text();
                index.push_back(name == "R" ? 0 : name == "G" ? 1 : name == "B" ? 2 : -1);
                REQUIRE(index.back() >= 0);
            }
            const auto x = r.number<std::int32_t>(), y = r.number<std::int32_t>();
            const auto w = r.number<std::int32_t>(), h = r.number<std::int32_t>();
            REQUIRE(x >= 0);
            REQUIRE(y >= 0);
            REQUIRE(x + w <= img.width);
            REQUIRE(y + h <= img.height);
            std::vector<std::int64_t> offset, stride;
            for (int c = 0; c < channels; ++c)
                offset.push_back(r.number<std::int64_t>());
            for (int c = 0; c < channels; ++c)
                stride.push_back(r.number<std::int64_t>());
            std::vector<float> data(r.left() / 4);
            for (float& f : data)
                f = r.number<float>();
            for (int py = 0; py < h; ++py)
                for (int px = 0; px < w; ++px) {
                    const std::size_t p = std::size_t(py) * w + px;
                    const std::size_t dst = std::size_t(y + py) * img.width + (x + px);
                    for (int c = 0; c < channels; ++c) {
                        const std::size_t k = std::size_t(offset[c] + std::int64_t(p) * stride[c]);
                        REQUIRE(k < data.size());
                        img.rgb[dst * 3 + index[c]] = data[k];
                    }
                    img.written[dst] = true;
                }
        }
        at += length;
    }
    return img;
}

/// The settings of the small renders: 80 x 70 pixels, so that a frame is four tiles of tev's
/// packets, two of them partial.
const std::vector<std::string> kSmall = {"-r",         "80",   "70",         "-s", "16",
                                         "--adaptive", "none", "--pass-spp", "2"};

} // namespace

TEST_CASE("render: --write-every writes the image while the render runs", "[app][live]") {
    TempDir dir("write-every");
    const std::string out = dir / "live.exr";
    // Far longer than the test waits: the images it sees are the render's images so far.
    const int spp = 1 << 20;
    Proc render({"render", kBox, "-f", out, "-r", "32", "24", "-s", std::to_string(spp),
                 "--adaptive", "none", "--pass-spp", "1", "--write-every", "1e-3", "-t", "1",
                 "-q"});
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitSeconds);
    std::vector<float> seen; // the sample count of each image read
    while (seen.size() < 2 && std::chrono::steady_clock::now() < end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        if (!std::filesystem::exists(out)) continue;
        // Replaced by a rename, never written in place: every read finds a whole image.
        const ImageData img = read_image(out);
        REQUIRE(img.width == 32);
        const int n = img.channel_index("samples");
        REQUIRE(n >= 0);
        const float samples = img.at(0, 0, n);
        CHECK(img.meta("candela:interrupted") == "1");
        if (seen.empty() || samples > seen.back()) seen.push_back(samples);
    }
    render.signal(SIGKILL);
    REQUIRE(seen.size() == 2);
    CHECK(seen[0] >= 1.f);
    CHECK(seen[1] < float(spp));
}

TEST_CASE("render: --write-every leaves the final images as they were", "[app][live]") {
    TempDir dir("write-every-final");
    const std::string plain = dir / "plain.exr", watched = dir / "watched.exr";
    // The relative sampler (the default) with a preview: the image, the preview and the
    // sample-rate image, each written at every pass boundary and then at the end.
    const std::vector<std::string> settings = {"-r",         "40", "30",        "-s", "32",
                                               "--pass-spp", "1",  "--preview", "-q"};
    REQUIRE(run_candela(cat({"render", kBox, "-f", plain}, settings)).status == 0);
    const Result r =
        run_candela(cat({"render", kBox, "-f", watched, "--write-every", "1e-9"}, settings));
    INFO(r.err);
    REQUIRE(r.status == 0);
    check_same_pixels(read_image(plain), read_image(watched));
    check_same_pixels(read_image(dir / "plain.png"), read_image(dir / "watched.png"));
    check_same_pixels(read_image(dir / "plain_rate.png"), read_image(dir / "watched_rate.png"));
    CHECK(read_image(watched).meta("candela:interrupted") == "0");
}

TEST_CASE("render: --write-every refuses a period that is not > 0", "[app][live]") {
    for (const std::string v : {"0", "-1", "nan", "inf"}) {
        const Result r = run_candela({"render", kBox, "--write-every", v});
        INFO(v << ": " << r.err);
        CHECK(r.status == 2);
        CHECK_THAT(r.err, Catch::Contains("--write-every must be a finite number of seconds > 0"));
    }
    CHECK(parse_render_command_line({kBox, "--write-every", "0.5"}).write_every == 0.5);
}

TEST_CASE("render: --display-server streams the film to a tev viewer", "[app][live]") {
    TempDir dir("display-server");
    const std::string out = dir / "shown.exr";
    FakeViewer viewer;
    const Result r =
        run_candela(cat({"render", kBox, "-f", out, "--display-server", viewer.address()}, kSmall));
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(count_lines(r.err, "warning") == 0);
    const ViewerImage shown = decode(viewer.received());
    CHECK(shown.creates == 1);
    CHECK(shown.name == out);
    REQUIRE(shown.width == 80);
    REQUIRE(shown.height == 70);
    // Tiles of at most 64 pixels a side: four a frame, and more than one frame (the first pass
    // and the end).
    CHECK(shown.updates >= 8);
    CHECK(shown.updates % 4 == 0);
    CHECK(std::all_of(shown.written.begin(), shown.written.end(), [](bool w) { return w; }));
    // The last frame is the final image, float for float.
    const ImageData img = read_image(out);
    const int R = img.channel_index("R");
    REQUIRE(R >= 0);
    std::size_t differing = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                differing += img.at(x, y, R + c) !=
                             shown.rgb[(std::size_t(y) * shown.width + x) * 3 + std::size_t(c)];
    CHECK(differing == 0);
}

TEST_CASE("a display server that is absent or goes away costs one warning", "[app][live]") {
    TempDir dir("display-server-gone");
    const std::string plain = dir / "plain.exr", out = dir / "out.exr";
    REQUIRE(run_candela(cat({"render", kBox, "-f", plain}, kSmall)).status == 0);
    SECTION("no viewer at the port") {
        int port = 0;
        ::close(listen_on_loopback(port)); // a port free a moment ago: nobody listens there now
        const std::string address = "127.0.0.1:" + std::to_string(port);
        const Result r =
            run_candela(cat({"render", kBox, "-f", out, "--display-server", address}, kSmall));
        INFO(r.err);
        REQUIRE(r.status == 0);
        CHECK(count_lines(r.err, "warning") == 1);
        CHECK(count_lines(r.err, "display server " + address + ": cannot connect") == 1);
    }
    SECTION("a viewer that closes the connection after the first bytes") {
        FakeViewer leaving(16);
        const Result r = run_candela(
            cat({"render", kBox, "-f", out, "--display-server", leaving.address()}, kSmall));
        INFO(r.err);
        REQUIRE(r.status == 0);
        CHECK(leaving.connected());
        CHECK(count_lines(r.err, "warning") == 1);
        CHECK(count_lines(r.err, "streaming stopped") == 1);
    }
    check_same_pixels(read_image(plain), read_image(out));
}
