#pragma once
// A render's memory, estimated before anything large is allocated, so that an absurd request
// (a huge frame, a scene too big for the machine) fails with a clear message instead of being
// killed by the operating system half-way.
#include "candela/render/settings.h"

#include <cstdint>
#include <string>

namespace candela {

class Scene;

struct MemoryEstimate {
    std::uint64_t film = 0;  ///< per-pixel sums of the film (and the adaptive state)
    std::uint64_t accel = 0; ///< acceleration structure
    std::uint64_t total() const { return film + accel; }
};

/// Upper estimate of the memory a render of `scene` with `s` allocates beyond the scene itself.
MemoryEstimate estimate_render_memory(const Scene& scene, const RenderSettings& s);

/// The default --max-memory: three quarters of the machine's physical memory.
std::uint64_t default_max_memory();

/// Throws Error(Usage) naming both figures when the estimate exceeds `limit`.
void check_memory_budget(const MemoryEstimate& e, std::uint64_t limit);

} // namespace candela
