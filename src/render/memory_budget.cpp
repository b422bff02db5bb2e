#include "candela/render/memory_budget.h"

#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <unistd.h>

namespace candela {

namespace {
/// Bytes per triangle of the largest accelerator (Embree's BVH measured about 67 B, the builtin
/// BVH 57 B; Embree's high-quality builds use more), with head-room for build-time buffers.
constexpr std::uint64_t kAccelBytesPerTriangle = 160;
/// Bytes per sphere in either accelerator (a user-geometry primitive or a prepared record),
/// plus the scene's own record (sizeof(Sphere), which holds an ellipsoid's two maps).
constexpr std::uint64_t kAccelBytesPerSphere = 96 + sizeof(Sphere);
} // namespace

MemoryEstimate estimate_render_memory(const Scene& scene, const RenderSettings& s) {
    MemoryEstimate e;
    const std::uint64_t w = s.region.full() ? std::uint64_t(s.width) : std::uint64_t(s.region.w);
    const std::uint64_t h = s.region.full() ? std::uint64_t(s.height) : std::uint64_t(s.region.h);
    const std::uint64_t px = w * h;
    // Film: radiance sums (3 doubles), counts (samples, drops and hits: 3 x u32), adaptive flag
    // (1 byte), optional sums.
    std::uint64_t per_pixel = 3 * 8 + 3 * 4 + 1;
    if (s.aovs.variance) per_pixel += 3 * 8;
    if (s.adaptive != AdaptiveKind::None) per_pixel += 2 * 8;
    if (s.aovs.albedo) per_pixel += 3 * 4;
    if (s.aovs.normal) per_pixel += 3 * 4;
    if (s.aovs.depth) per_pixel += 4;
    // Writing the EXR holds one float per channel (at most 19) next to the film; a checkpoint
    // copies the film once more.
    per_pixel += 19 * 4;
    e.film = 2 * px * per_pixel;
    e.accel = std::uint64_t(scene.triangle_count()) * kAccelBytesPerTriangle +
              std::uint64_t(scene.spheres.size()) * kAccelBytesPerSphere;
    return e;
}

std::uint64_t default_max_memory() {
    long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return std::uint64_t(8) << 30; // unknown: assume 8 GiB
    return std::uint64_t(pages) * std::uint64_t(page) / 4 * 3;
}

std::uint64_t parse_memory_size(const std::string& text) {
    const std::string what = "--max-memory: '" + text + "' ";
    std::size_t i = 0;
    while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.'))
        ++i;
    if (i == 0) throw Error(ErrorKind::Usage, "error: " + what + "is not a size (e.g. 8G, 512M)");
    double v = std::strtod(text.substr(0, i).c_str(), nullptr);
    std::string unit = text.substr(i);
    for (char& c : unit)
        c = char(std::toupper(static_cast<unsigned char>(c)));
    double scale = 1.0;
    if (unit.empty() || unit == "B")
        scale = 1.0;
    else if (unit == "K" || unit == "KB" || unit == "KIB")
        scale = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MIB")
        scale = 1024.0 * 1024.0;
    else if (unit == "G" || unit == "GB" || unit == "GIB")
        scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "T" || unit == "TB" || unit == "TIB")
        scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    else
        throw Error(ErrorKind::Usage, "error: " + what + "has an unknown unit");
    double bytes = v * scale;
    if (!std::isfinite(bytes) || bytes < 1.0 || bytes > 1.8e19)
        throw Error(ErrorKind::Usage, "error: " + what + "is out of range");
    return std::uint64_t(bytes);
}

std::string format_bytes(std::uint64_t b) {
    char buf[64];
    if (b >= (std::uint64_t(1) << 30))
        std::snprintf(buf, sizeof buf, "%.1f GiB", double(b) / double(std::uint64_t(1) << 30));
    else if (b >= (std::uint64_t(1) << 20))
        std::snprintf(buf, sizeof buf, "%.1f MiB", double(b) / double(std::uint64_t(1) << 20));
    else
        std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(b));
    return buf;
}

void check_memory_budget(const MemoryEstimate& e, std::uint64_t limit) {
    if (e.total() <= limit) return;
    throw Error(ErrorKind::Usage, "error: this render needs about " + format_bytes(e.total()) +
                                      " (film " + format_bytes(e.film) +
                                      ", acceleration structure " + format_bytes(e.accel) +
                                      "), more than --max-memory " + format_bytes(limit) +
                                      "; lower -r, drop --aov channels, or raise --max-memory");
}

} // namespace candela
