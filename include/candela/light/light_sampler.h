#pragma once
// Chooses one light of a scene for next-event estimation (the rule and its cost:
// docs/rendering.md, "Light selection").
//
// Finite lights (area, point, spot, emissive meshes and spheres) are weighed by their emitted
// power (light_power in light_sampling.h). Infinite lights (directional, ambient, environment)
// have no power a scene's size does not decide, so they are weighed apart: each infinite light
// that emits counts as one share beside one share for all finite lights together, and within each
// group the shares follow power. Within a group every emitting light gets at least
// kLightFloorShare / (its group's emitting lights) of the group, so no light's probability
// vanishes however weak it is beside the others.
//
// Probabilities are whole multiples of 2^-23 and the choice is an exact alias table driven by a
// raw 32-bit uniform (sampling/alias_table.h): the probability with which a light is realised is
// pmf() exactly, which the estimator and the MIS weights divide by.
#include "candela/sampling/alias_table.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candela {

/// Share of each group's selection spread evenly over its emitting lights (see above): a light
/// weaker than the rest by any factor is still chosen with probability >= 1/64 / (lights in its
/// group) of its group, at a variance cost of at most 1/64 on the lights that carry the power.
inline constexpr double kLightFloorShare = 1.0 / 64.0;
/// A light whose power is below this fraction of its group's total gets a warning: it is chosen
/// about as often as the floor share says, but adds almost nothing to the image.
inline constexpr double kNegligiblePowerShare = 1e-6;

/// A chosen light and the (discrete) probability of having chosen it.
struct LightChoice {
    std::uint32_t index; ///< index into Scene::lights
    float pmf;           ///< probability of this choice, in (0, 1]
};

class LightSampler {
  public:
    LightSampler() = default;
    /// Builds the selection table from scene.lights. Lights of zero power are never chosen;
    /// when every light has zero power the choice is uniform. Throws Error(ErrorKind::Scene)
    /// naming the light when a power is negative or not finite, and Error(ErrorKind::Internal)
    /// when a light's record is inconsistent with the scene (mesh or sphere index out of range,
    /// triangle CDF of the wrong size, environment light without a map), so that sampling never
    /// reads out of bounds.
    explicit LightSampler(const Scene& scene);

    /// Picks a light with one uniform 32-bit integer u. nullopt when the scene has no light.
    std::optional<LightChoice> sample(std::uint32_t u) const {
        if (n_ == 1) return LightChoice{0u, 1.f}; // inline: the common one-light scene
        return sample_table(u);
    }
    /// Probability that sample() returns light `index` (0 for an out-of-range index), exactly
    /// the fraction of the 2^32 values of u that choose it.
    float pmf(std::size_t index) const { return index < n_ ? table_.pmf(index) : 0.f; }
    std::size_t size() const { return n_; }
    /// The table (for tests that count the values of u choosing each light).
    const AliasTable& table() const { return table_; }

  private:
    std::optional<LightChoice> sample_table(std::uint32_t u) const;

    std::size_t n_ = 0;
    AliasTable table_;
};

/// The selection weight of every light before the floor: its power for a finite light, its
/// power through a unit cross-section (light_power) for an infinite one.
std::vector<double> light_selection_powers(const Scene& scene);

/// One warning per light whose power is below kNegligiblePowerShare of its group's total
/// (finite or infinite lights), worded "light K (kind) emits X of ...".
std::vector<std::string> negligible_light_warnings(const Scene& scene);

} // namespace candela
