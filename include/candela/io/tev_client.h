#pragma once
// A client of the tev HDR viewer's TCP protocol (the `--display-server` of pbrt-v4 and of
// candela render): it creates an image in a running viewer and updates it tile by tile.
//
// Every packet is a little-endian uint32 holding the packet's whole length (these four bytes
// included), a one-byte type and the type's fields; strings end with a NUL byte, integers are
// little-endian, flags one byte (0 or 1). The two packets used:
//   create image (type 4): grab focus, image name, int32 width, int32 height, int32 channel
//     count, the channel names;
//   update image (type 6): grab focus, image name, int32 channel count, the channel names,
//     int32 x, y, width, height of the tile (row 0 at the top), int64 offset per channel,
//     int64 stride per channel, then the tile's floats: channel c of pixel p (row by row) is
//     float number offset[c] + p * stride[c].
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// A viewer's address, from "HOST:PORT" ("[::1]:14158" for a numeric IPv6 host).
struct TevAddress {
    std::string host;
    int port = 0;
    std::string str() const; ///< as given, HOST:PORT
};
/// The address in `text`, or nothing when it is not HOST:PORT with a port in 1..65535.
std::optional<TevAddress> parse_tev_address(const std::string& text);

/// The packet types candela sends (tev's numbering).
enum class TevPacket : std::uint8_t { CreateImage = 4, UpdateImage = 6 };

/// Pixels per side of the tiles an image is sent in: 64 x 64 RGB floats are 48 KiB a packet.
constexpr int kTevTileSize = 64;

/// A connection to a viewer. A failure throws Error(Io) naming the address and the reason;
/// neither connecting nor sending waits longer than the timeouts given.
class TevClient {
  public:
    /// Connects to `address`, giving up after `connect_seconds`; a send that cannot go on for
    /// `send_seconds` fails.
    TevClient(const TevAddress& address, double connect_seconds, double send_seconds);
    ~TevClient();
    TevClient(const TevClient&) = delete;
    TevClient& operator=(const TevClient&) = delete;

    /// Creates (or replaces) the image `name` of width x height pixels with `channels`.
    void create_image(const std::string& name, int width, int height,
                      const std::vector<std::string>& channels, bool grab_focus);

    /// Sends `pixels` (width x height pixels of channels.size() interleaved floats, row 0 at
    /// the top) into image `name` at (x, y), in tiles of at most kTevTileSize pixels a side.
    void update_image(const std::string& name, const std::vector<std::string>& channels, int x,
                      int y, int width, int height, const std::vector<float>& pixels);

    /// Ends every send under way and to come at once (from another thread): they fail.
    void abort();

  private:
    void send_packet(const std::vector<unsigned char>& packet);

    std::string where_;
    int fd_ = -1;
};

} // namespace candela
