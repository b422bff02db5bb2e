#pragma once
// Chooses one light of a scene for next-event estimation, with probability proportional to its
// emitted power (light_power in light_sampling.h).
#include "candela/sampling/distribution.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace candela {

/// A chosen light and the (discrete) probability of having chosen it.
struct LightChoice {
    std::uint32_t index; ///< index into Scene::lights
    float pmf;           ///< probability of this choice, in (0, 1]
};

class LightSampler {
  public:
    LightSampler() = default;
    /// Builds the selection table from scene.lights. Probabilities are proportional to
    /// light_power(); when every light has zero power the choice is uniform. Throws
    /// Error(ErrorKind::Scene) naming the light when a power is negative or not finite, and
    /// Error(ErrorKind::Internal) when a light's record is inconsistent with the scene (mesh or
    /// sphere index out of range, triangle CDF of the wrong size, environment light without a
    /// map), so that sampling never reads out of bounds.
    explicit LightSampler(const Scene& scene);

    /// Picks a light with one uniform u in [0,1). nullopt when the scene has no light.
    std::optional<LightChoice> sample(float u) const {
        if (n_ == 1) return LightChoice{0u, pmf_[0]}; // inline: the common one-light scene
        return sample_table(u);
    }
    /// Probability that sample() returns light `index` (0 for an out-of-range index).
    float pmf(std::size_t index) const;
    std::size_t size() const { return n_; }

  private:
    std::optional<LightChoice> sample_table(float u) const;

    std::size_t n_ = 0;
    Distribution1D dist_;    ///< over light indices, by power (uniform when all powers are 0)
    std::vector<float> pmf_; ///< dist_.pmf(k) of every light, looked up on every MIS weight
};

} // namespace candela
