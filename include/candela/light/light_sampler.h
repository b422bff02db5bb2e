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
// With two or more emitting infinite lights, their summed share is split again at each shading
// point by the irradiance each gives a surface of the point's orientation (light_irradiance in
// light_sampling.h, with the same floor): a wall facing away from the sun leaves the sun its floor
// and gives the sky the rest. The orientation is receiving_normal() (zero: the fixed split).
//
// Two rules choose among the finite lights (--light-sampler):
//  * power: in proportion to power alone, by an integer CDF of the shares' exact units
//    (sampling/unit_cdf.h: each light holds one interval of u, found by binary search);
//  * bvh: in proportion to an estimate of each light's contribution at the shading point, by
//    descending a bounding volume hierarchy over the finite lights (light/light_tree.h); the
//    group's floor share is spread evenly over its lights, the rest goes down the tree.
// Both draw from one raw 32-bit uniform, and every probability is a whole multiple of 2^-23
// realised exactly: the probability with which a light is chosen is pmf() exactly, which the
// estimator and the MIS weights divide by. The default (auto) is bvh when a scene has at least
// kTreeMinLights finite lights, power otherwise; a scene with one light builds neither.
//
// Every light's values of u form intervals (one under power; under bvh one in the floor and one
// down the tree), so a choice also says where in its interval u fell (LightChoice::offset and
// ::units). spread_within() turns that place, with 32 fresh bits to fill in below it, into a
// 32-bit uniform that is exactly uniform given the choice and rises with u: the integrator draws
// one 2D point, chooses the light with its first coordinate and samples the light with that
// coordinate spread over the light, so the points that choose a light stay stratified over it
// (docs/rendering.md, "Light selection").
#include "candela/light/light_sampling.h"
#include "candela/light/light_tree.h"
#include "candela/math/vec.h"
#include "candela/sampling/unit_cdf.h"
#include "candela/scene/scene.h"
#include "candela/util/enum_table.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace candela {

/// Share of each group's selection spread evenly over its emitting lights (see above): a light
/// weaker than the rest by any factor is still chosen with probability >= 1/64 / (lights in its
/// group) of its group, at a variance cost of at most 1/64 on the lights that carry the power.
inline constexpr double kLightFloorShare = 1.0 / 64.0;
/// A light whose power is below this fraction of its group's total gets a warning: it is chosen
/// about as often as the floor share says, but adds almost nothing to the image.
inline constexpr double kNegligiblePowerShare = 1e-6;

/// Emitting finite lights from which `auto` chooses with the tree: below this, a light's place
/// rarely changes its share much and the power table's O(1) choice is cheaper than a descent.
inline constexpr std::size_t kTreeMinLights = 8;

enum class LightSamplerKind { Auto, Power, Bvh };
/// --light-sampler (util/enum_table.h).
inline constexpr EnumTable<LightSamplerKind, 3> kLightSamplerKinds = {{
    {LightSamplerKind::Auto, "auto", "bvh from 8 finite lights on, else power"},
    {LightSamplerKind::Power, "power", "by emitted power alone"},
    {LightSamplerKind::Bvh, "bvh", "by a light hierarchy's estimate at the shading point"},
}};

/// A chosen light and the (discrete) probability of having chosen it.
struct LightChoice {
    std::uint32_t index;  ///< index into Scene::lights
    float pmf;            ///< probability of this choice, in (0, 1]
    std::uint32_t offset; ///< the unit of the interval that held u, in [0, units)
    std::uint32_t units;  ///< the length of that interval, in units of 2^-23
};

/// u's place in the `units` units of a choice (2^9 values of u each, u in unit `offset`), with
/// `fill` as 32 further bits below it, spread over [0, 2^32): every output value comes from
/// exactly units * 2^9 of the units * 2^9 * 2^32 equally likely (place, fill) pairs, so it is
/// exactly uniform for a uniform fill, and it rises with u's place. A whole-range choice
/// (units = 2^23, offset = u >> 9) gives u itself.
constexpr std::uint32_t spread_within(std::uint32_t offset, std::uint32_t units, std::uint32_t u,
                                      std::uint32_t fill) {
    constexpr int kLowBits = 32 - kProbabilityUnitBits;
    const std::uint64_t span = std::uint64_t(units) << kLowBits; // <= 2^32
    const std::uint64_t place =
        (std::uint64_t(offset) << kLowBits) | (u & ((std::uint32_t(1) << kLowBits) - 1u)); // < span
    return std::uint32_t(((place << 32) | fill) / span);
}

/// The most emitting infinite lights whose share is split by orientation (their irradiances are
/// kept on the stack); with more, they keep the fixed split.
inline constexpr std::size_t kMaxOrientedLights = 8;

/// The irradiance each infinite light gives one orientation (LightSampler::infinite_shares), by
/// slot, and their sum (0: the fixed split).
struct InfiniteShares {
    std::array<float, kMaxOrientedLights> irradiance{};
    double total = 0.0;
};

class LightSampler {
  public:
    LightSampler() = default;
    /// Builds the selection table from scene.lights. Lights of zero power are never chosen;
    /// when every light has zero power the choice is uniform. Throws Error(ErrorKind::Scene)
    /// naming the light when a power is negative or not finite, and Error(ErrorKind::Internal)
    /// when a light's record is inconsistent with the scene (mesh or sphere index out of range,
    /// triangle tables of the wrong size, environment light without a map), so that sampling never
    /// reads out of bounds.
    explicit LightSampler(const Scene& scene, LightSamplerKind kind = LightSamplerKind::Power);

    /// Picks a light for the shading point p with one uniform 32-bit integer u. n is the unit
    /// normal of the hemisphere from which the surface at p receives light (receiving_normal():
    /// the shading normal turned to the side of the outgoing direction, for a surface that only
    /// reflects), or zero for a surface that receives light from every direction (one that
    /// transmits too). nullopt when the scene has no light, when (bvh) u falls to lights that
    /// cannot light p, or in the units the infinite lights' split leaves to none.
    std::optional<LightChoice> sample(std::uint32_t u, const Vec3& p, const Vec3& n) const {
        return sample(u, p, n, nullptr);
    }
    /// sample(u, p, n) with the infinite lights' split taken from `shares` where given
    /// (infinite_shares(n) with its directional lights weighed by weigh_directional()) instead
    /// of from n.
    std::optional<LightChoice> sample(std::uint32_t u, const Vec3& p, const Vec3& n,
                                      const InfiniteShares* shares) const {
        // inline: the common one-light scene, whose interval is all of u's range
        if (n_ == 1)
            return LightChoice{0u, 1.f, u >> (32 - kProbabilityUnitBits), kProbabilityUnits};
        if (!tree_mode_) return sample_table(u, n, shares);
        return sample_tree(u, p, n, shares);
    }
    /// Probability that sample(., p, n) returns light `index` (0 for an out-of-range index),
    /// exactly the fraction of the 2^32 values of u that choose it there.
    float pmf(const Vec3& p, const Vec3& n, std::size_t index) const {
        if (index < n_ && split_slot_[index] >= 0) return pmf(p, n, index, infinite_shares(n));
        if (!tree_mode_) return pmf(index);
        return pmf_tree(p, n, index);
    }
    /// pmf(p, n, index) given infinite_shares(n), which several calls at one point can share.
    float pmf(const Vec3& p, const Vec3& n, std::size_t index, const InfiniteShares& shares) const {
        if (index < n_ && split_slot_[index] >= 0)
            return float(split_units(std::size_t(split_slot_[index]), shares)) * 0x1p-23f;
        if (!tree_mode_) return pmf(index);
        return pmf_tree(p, n, index);
    }
    /// The irradiance each infinite light of the split gives orientation n (infinite_split();
    /// total 0, the fixed split, for n = 0 or without a split by orientation).
    InfiniteShares infinite_shares(const Vec3& n) const;
    /// Whether a directional light takes part in a split by orientation (weigh_directional()
    /// changes something).
    bool split_has_directional() const { return split_directional_; }
    /// Replaces, in oriented `shares`, the irradiance of each directional light of the split by
    /// `weight(dir, lum)` for its unit direction toward the light and the luminance of its
    /// radiance, and their total by the new sum (in slot order, as infinite_shares() sums).
    /// Unoriented shares (total 0, the fixed split) are left as they are.
    template <class Weight>
    void weigh_directional(InfiniteShares& shares, const Weight& weight) const {
        if (!(shares.total > 0.0) || !split_directional_) return;
        double total = 0.0;
        for (std::size_t i = 0; i < split_models_.size(); ++i) {
            const InfiniteIrradiance& m = split_models_[i];
            if (m.kind == LightKind::Directional)
                shares.irradiance[i] = std::max(0.f, float(weight(m.dir, m.lum)));
            total += double(shares.irradiance[i]);
        }
        shares.total = total;
    }
    /// The probability of light `index` wherever the choice is made, or 0 where it depends on
    /// the point (see pmf(p, n, index)): a finite light's under bvh, an infinite light's when the
    /// infinite lights' share is split by orientation (infinite_split()).
    float pmf(std::size_t index) const {
        if (index >= n_ || split_slot_[index] >= 0) return 0.f;
        return tree_mode_ ? float(fixed_units_[index]) * 0x1p-23f : table_.pmf(index);
    }
    /// Whether the infinite lights' share is split at each point by the irradiance each gives
    /// the surface's orientation (light_irradiance): with two or more emitting infinite lights.
    bool infinite_split() const { return !split_models_.empty(); }
    /// The infinite lights whose split follows the orientation (0 without a split, or when it
    /// stays fixed: more than kMaxOrientedLights of them).
    std::size_t oriented_lights() const { return split_oriented_ ? split_models_.size() : 0; }
    std::size_t size() const { return n_; }
    /// The rule in use: Power or Bvh (never Auto).
    LightSamplerKind kind() const {
        return tree_mode_ ? LightSamplerKind::Bvh : LightSamplerKind::Power;
    }
    /// Under power selection, the values of u that choose light `index`: [first, second), as
    /// 64-bit numbers (the last light's interval ends at 2^32); empty for a light of no power.
    std::pair<std::uint64_t, std::uint64_t> u_interval(std::size_t index) const {
        constexpr int kLowBits = 32 - kProbabilityUnitBits;
        return {std::uint64_t(table_.cdf(index)) << kLowBits, std::uint64_t(table_.cdf(index + 1))
                                                                  << kLowBits};
    }
    /// The light tree (empty under power selection).
    const LightTree& tree() const { return tree_; }

  private:
    std::optional<LightChoice> sample_table(std::uint32_t u, const Vec3& n,
                                            const InfiniteShares* shares) const;
    std::optional<LightChoice> sample_tree(std::uint32_t u, const Vec3& p, const Vec3& n,
                                           const InfiniteShares* shares) const;
    float pmf_tree(const Vec3& p, const Vec3& n, std::size_t index) const;
    void build_tree(const Scene& scene, const std::vector<double>& power,
                    const std::vector<double>& share);

    std::size_t n_ = 0;
    bool tree_mode_ = false;
    UnitCdf table_; ///< power selection: light k holds units [cdf(k), cdf(k + 1)) of 2^23
    // bvh: the 2^23 units of u >> 9 are laid out as [floor | tree | infinite lights].
    LightTree tree_;
    std::vector<std::uint32_t> fixed_units_;  ///< by light: an infinite light's units, else 0
    std::vector<std::uint32_t> floor_lights_; ///< emitting finite lights, for the floor
    std::vector<std::uint8_t> in_tree_;       ///< by light: 1 for an emitting finite light
    std::uint32_t floor_units_ = 0;           ///< each floor light's share of the floor
    std::uint32_t tree_begin_ = 0, tree_end_ = 0;
    std::vector<std::uint32_t> infinite_lights_, infinite_end_; ///< and where each one's units end

    // The split of the infinite lights' units by orientation (docs/rendering.md, "Light
    // selection"): under power they follow the finite lights' units, under bvh the tree's.
    void build_split(const Scene& scene, const std::vector<std::uint32_t>& lights,
                     std::uint32_t begin, std::uint32_t units,
                     const std::vector<std::uint32_t>& fixed);
    /// The units of the infinite light in `slot` at the orientation of `shares`.
    std::uint32_t split_units(std::size_t slot, const InfiniteShares& shares) const;
    /// The infinite light whose units at orientation n hold unit `v` of the split's range (v
    /// counted from its start), or nullopt in the few units no light takes (the rounding's).
    std::optional<LightChoice> sample_split(std::uint32_t v, const Vec3& n,
                                            const InfiniteShares* shares) const;

    std::vector<InfiniteIrradiance> split_models_;    ///< by slot
    std::vector<std::uint32_t> split_lights_;         ///< by slot: the light's index
    std::vector<std::uint32_t> split_fixed_;          ///< by slot: its units when n = 0
    std::vector<std::int32_t> split_slot_;            ///< by light: its slot, or -1
    std::uint32_t split_begin_ = 0, split_range_ = 0; ///< the split's units [begin, begin + range)
    bool split_oriented_ = false;                     ///< false: every point gets the fixed split
    bool split_directional_ = false; ///< oriented, with a directional light among the split's
};

/// The orientation LightSampler::sample() and pmf() take at a shading point: the shading normal
/// ns turned to the side of the outgoing direction wo for a surface that only reflects (its
/// BSDF is zero for light from the other side), zero for one that transmits too.
inline Vec3 receiving_normal(const Vec3& ns, const Vec3& wo, bool transmits) {
    if (transmits) return Vec3(0.f);
    return dot(ns, wo) < 0.f ? -ns : ns;
}

/// The selection weight of every light before the floor: its power for a finite light, its
/// power through a unit cross-section (light_power) for an infinite one.
std::vector<double> light_selection_powers(const Scene& scene);

/// One line on the rule `kind` resolves to for `scene`, e.g. "bvh (auto: 120 finite lights,
/// 239 tree nodes)", "power (auto: 2 finite lights)" or "power (auto: 0 finite lights, 2
/// infinite lights split by orientation)".
std::string describe_light_selection(const Scene& scene, LightSamplerKind kind);

/// One warning per light whose power is below kNegligiblePowerShare of its group's total
/// (finite or infinite lights), worded "light K (kind) emits X of ...".
std::vector<std::string> negligible_light_warnings(const Scene& scene);

} // namespace candela
