#pragma once
// What a render counts: the integrator adds its ray queries, the pass loop its samples, each
// thread into its own copy; the copies are summed, and a group of processes sums them over its
// ranks (RenderGroup::reduce). Integer sums, so the totals do not depend on the order.
#include <cstdint>

namespace candela {

struct RenderCounters {
    std::uint64_t samples = 0;     ///< camera samples taken (including dropped ones)
    std::uint64_t camera_rays = 0; ///< closest-hit queries of camera rays
    std::uint64_t rays = 0;        ///< closest-hit queries (camera rays included)
    std::uint64_t shadow_rays = 0; ///< occlusion queries
    std::uint64_t dropped = 0;     ///< non-finite samples dropped
    /// Sampler requests made outside the vertex's plan (SampleBatch): each costs a Sampler call
    /// of its own, never a different value; a complete plan keeps this at zero.
    std::uint64_t sampler_fallbacks = 0;
};

/// Every counter of RenderCounters, once: the sum below and the group's reduction walk this list.
inline constexpr std::uint64_t RenderCounters::*kRenderCounterFields[] = {
    &RenderCounters::samples,     &RenderCounters::camera_rays, &RenderCounters::rays,
    &RenderCounters::shadow_rays, &RenderCounters::dropped,     &RenderCounters::sampler_fallbacks};

inline RenderCounters& operator+=(RenderCounters& a, const RenderCounters& b) {
    for (std::uint64_t RenderCounters::*f : kRenderCounterFields)
        a.*f += b.*f;
    return a;
}

} // namespace candela
