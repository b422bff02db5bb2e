// A render's memory, estimated before anything large is allocated, and the --max-memory check.
#include "candela/render/memory_budget.h"

#include "candela/render/adaptive.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

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
    if (make_pass_policy(s)->reads_film()) per_pixel += 2 * 8;
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

void check_memory_budget(const MemoryEstimate& e, std::uint64_t limit) {
    if (e.total() <= limit) return;
    throw Error(ErrorKind::Usage, "this render needs about " + format_bytes(e.total()) + " (film " +
                                      format_bytes(e.film) + ", acceleration structure " +
                                      format_bytes(e.accel) + "), more than --max-memory " +
                                      format_bytes(limit) +
                                      "; lower -r, drop --aov channels, or raise --max-memory");
}

} // namespace candela
