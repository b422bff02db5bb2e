#pragma once
// Embree called directly, with no Accel in between: the ceiling `candela bench` holds candela's
// traversal against. Its scene is built from the very shared buffers EmbreeAccel uses, and its
// rays are converted as EmbreeAccel converts them, so both trace exactly the same rays. Embree's
// own types stay inside src/accel/.
#include "candela/accel/accel.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace candela {

class Scene;

class RawEmbree {
  public:
    /// Builds an Embree scene of its own over `scene` (which must outlive it) on a device of
    /// instruction set `isa` ("" for embree_default_isa()), with all threads.
    RawEmbree(const Scene& scene, const std::string& isa, bool robust,
              AccelOptions::Quality quality);
    ~RawEmbree();
    RawEmbree(const RawEmbree&) = delete;
    RawEmbree& operator=(const RawEmbree&) = delete;

    /// The device's configuration string.
    const std::string& config() const;
    /// One rtcIntersect1 call per ray of rays[0, n), in a tight loop: how many hit.
    std::uint64_t count_hits(const Ray* rays, std::size_t n) const;
    /// One rtcOccluded1 call per ray of rays[0, n): how many are occluded.
    std::uint64_t count_occluded(const Ray* rays, std::size_t n) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace candela
