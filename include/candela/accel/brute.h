#pragma once
// Linear scan over every triangle and sphere: slow, simple, and the oracle other backends are
// tested against.
#include "candela/accel/accel.h"

namespace candela {

class BruteAccel final : public Accel {
  public:
    /// `scene` must outlive the accelerator; `test` selects the triangle test.
    BruteAccel(const Scene& scene, TriangleTest test);
    std::optional<Hit> intersect(const Ray& ray) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3 bounds() const override;
    const char* name() const override { return "brute"; }
    /// Zero: the scan reads the scene's own arrays.
    std::size_t memory_bytes() const override { return 0; }

  private:
    template <TriangleTest kTest, bool kAnyHit> bool trace(const Ray& ray, Hit& hit) const;
    const Scene& scene_;
    TriangleTest test_;
};

} // namespace candela
