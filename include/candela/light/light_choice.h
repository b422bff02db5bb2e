#pragma once
// Chooses one light of a scene for next-event estimation (the rule and its cost:
// docs/rendering.md, "Light selection"). Sampling a point on the chosen light is the job of
// light/light_sample.h.
//
// Finite lights (area, point, spot, emissive meshes and spheres) are weighed by their emitted
// power (light_power in light_sample.h). Infinite lights (directional, ambient, environment)
// have no power a scene's size does not decide, so they are weighed apart: each infinite light
// that emits counts as one share beside one share for all finite lights together, and within each
// group the shares follow power. Within a group every emitting light gets at least
// kLightFloorShare / (its group's emitting lights) of the group, so no light's probability
// vanishes however weak it is beside the others.
//
// With two or more emitting infinite lights, their summed share is split again at each shading
// point by the irradiance each gives a surface of the point's orientation (light_irradiance in
// light_sample.h, with the same floor): a wall facing away from the sun leaves the sun its floor
// and gives the sky the rest. The orientation is receiving_normal() (zero: the fixed split).
// InfiniteSplit states that split once; each rule holds one as the last range of its units.
//
// One class per rule of --light-sampler, each with sample(ctx, u) and pmf(ctx, light) over one
// LightChoiceContext (the shading point, its receiving orientation and, where the caller has
// them, the infinite lights' weights there):
//  * PowerLightChooser: in proportion to power alone, by an integer CDF of the shares' exact
//    units (sampling/unit_cdf.h: each light holds one interval of u, found by binary search);
//  * BvhLightChooser: in proportion to an estimate of each light's contribution at the shading
//    point, by descending a bounding volume hierarchy over the finite lights
//    (light/light_tree.h); the group's floor share is spread evenly over its lights, the rest
//    goes down the tree.
// LightChooser holds the rule a scene resolves to (auto: bvh when a scene has at least
// kTreeMinLights finite lights, power otherwise; a scene with one light builds neither) and
// passes each call to it with one branch, no virtual call. Both rules draw from one raw 32-bit
// uniform, and every probability is a whole multiple of 2^-23 realised exactly: the probability
// with which a light is chosen is pmf() exactly, which the estimator and the MIS weights divide
// by.
//
// Every light's values of u form intervals (one under power; under bvh one in the floor and one
// down the tree), so a choice also says where in its interval u fell (LightChoice::offset and
// ::units). spread_within() turns that place, with 32 fresh bits to fill in below it, into a
// 32-bit uniform that is exactly uniform given the choice and rises with u: the integrator draws
// one 2D point, chooses the light with its first coordinate and samples the light with that
// coordinate spread over the light, so the points that choose a light stay stratified over it
// (docs/rendering.md, "Light selection").
#include "candela/light/light_sample.h"
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
#include <variant>
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

/// The irradiance each infinite light of a split gives one orientation (InfiniteSplit::shares),
/// by slot, and their sum (0: the fixed split).
struct InfiniteShares {
    std::array<float, kMaxOrientedLights> irradiance{};
    double total = 0.0;
};

/// Where a light is chosen: everything a rule's sample() and pmf() read besides u and the light.
struct LightChoiceContext {
    Vec3 p{0.f}; ///< the shading point
    /// The unit normal of the hemisphere from which the surface at p receives light
    /// (receiving_normal(): the shading normal turned to the side of the outgoing direction, for
    /// a surface that only reflects), or zero for a surface that receives light from every
    /// direction (one that transmits too).
    Vec3 n{0.f};
    /// The infinite lights' weights at n where the caller has them (InfiniteSplit::shares(n),
    /// perhaps with its directional lights reweighed by weigh_directional()); null: shares(n).
    const InfiniteShares* shares = nullptr;
};

/// What both rules start from: each light's selection power (light_selection_powers()), its
/// share after the groups and the floor, and the emitting lights of each group.
struct LightWeights {
    std::vector<double> power;
    std::vector<double> share;
    std::vector<std::uint32_t> finite, infinite; ///< emitting lights, by scene index
};
/// The LightWeights of `scene` (the errors of light_selection_powers()).
LightWeights light_weights(const Scene& scene);

/// The split of the emitting infinite lights' units by the irradiance each gives the receiving
/// orientation, with the floor mixed in (docs/rendering.md, "Light selection"). It takes the last
/// units of a rule's range, [begin(), 2^23); at orientation n light `slot` gets its floored share
/// of the range rounded down, so a few units at the end may be left to no light.
class InfiniteSplit {
  public:
    InfiniteSplit() = default;
    /// Splits the units [begin, begin + range) among the scene lights `lights` (two or more
    /// emitting infinite lights), whose units at n = 0 (the fixed split) are `fixed`.
    InfiniteSplit(const Scene& scene, const std::vector<std::uint32_t>& lights,
                  const std::vector<std::uint32_t>& fixed, std::uint32_t begin,
                  std::uint32_t range);

    /// Whether there is a split: two or more emitting infinite lights.
    bool active() const { return !models_.empty(); }
    /// Whether light `index` takes part in the split.
    bool holds(std::size_t index) const { return index < slot_.size() && slot_[index] >= 0; }
    /// The first unit of the split's range.
    std::uint32_t begin() const { return begin_; }
    /// The infinite lights whose units follow the orientation (0 without a split, or when it
    /// stays fixed: more than kMaxOrientedLights of them).
    std::size_t oriented_lights() const { return oriented_ ? models_.size() : 0; }
    /// Whether a directional light takes part in a split by orientation (weigh_directional()
    /// changes something).
    bool has_directional() const { return directional_; }

    /// The irradiance each light of the split gives orientation n (total 0, the fixed split, for
    /// n = 0 or a split that stays fixed).
    InfiniteShares shares(const Vec3& n) const;
    /// Replaces, in oriented `shares`, the irradiance of each directional light of the split by
    /// `weight(dir, lum)` for its unit direction toward the light and the luminance of its
    /// radiance, and their total by the new sum (in slot order, as shares() sums). Unoriented
    /// shares (total 0, the fixed split) are left as they are.
    template <class Weight>
    void weigh_directional(InfiniteShares& shares, const Weight& weight) const {
        if (!(shares.total > 0.0) || !directional_) return;
        double total = 0.0;
        for (std::size_t i = 0; i < models_.size(); ++i) {
            const InfiniteIrradiance& m = models_[i];
            if (m.kind == LightKind::Directional)
                shares.irradiance[i] = std::max(0.f, float(weight(m.dir, m.lum)));
            total += double(shares.irradiance[i]);
        }
        shares.total = total;
    }

    /// The light whose units at ctx hold unit `v` of the range (counted from begin()), or
    /// nullopt in the few units no light takes (the rounding's).
    std::optional<LightChoice> sample(const LightChoiceContext& ctx, std::uint32_t v) const;
    /// The probability of light `index` (one the split holds) at ctx.
    float pmf(const LightChoiceContext& ctx, std::size_t index) const {
        const std::size_t slot = std::size_t(slot_[index]);
        if (ctx.shares) return float(units(slot, *ctx.shares)) * 0x1p-23f;
        return float(units(slot, shares(ctx.n))) * 0x1p-23f;
    }

  private:
    /// The units of the light in `slot` at the orientation of `shares`.
    std::uint32_t units(std::size_t slot, const InfiniteShares& shares) const;

    std::vector<InfiniteIrradiance> models_; ///< by slot
    std::vector<std::uint32_t> lights_;      ///< by slot: the light's index
    std::vector<std::uint32_t> fixed_;       ///< by slot: its units when n = 0
    std::vector<std::int32_t> slot_;         ///< by light: its slot, or -1
    std::uint32_t begin_ = 0, range_ = 0;    ///< the split's units [begin, begin + range)
    bool oriented_ = false;                  ///< false: every point gets the fixed split
    bool directional_ = false; ///< oriented, with a directional light among the split's
};

/// --light-sampler power: every light by its share alone, one interval of u each.
class PowerLightChooser {
  public:
    PowerLightChooser() = default;
    PowerLightChooser(const Scene& scene, const LightWeights& weights);

    /// The light chosen at ctx by the 32-bit uniform u; nullopt without lights, or in the few
    /// units the infinite lights' split leaves to none.
    std::optional<LightChoice> sample(const LightChoiceContext& ctx, std::uint32_t u) const;
    /// The probability that sample(ctx, .) returns light `index` (0 for an out-of-range index),
    /// exactly the fraction of the 2^32 values of u that choose it there.
    float pmf(const LightChoiceContext& ctx, std::size_t index) const {
        if (split_.holds(index)) return split_.pmf(ctx, index);
        return index < n_ ? table_.pmf(index) : 0.f;
    }
    /// The values of u that choose light `index` (not one of the split's): [first, second), as
    /// 64-bit numbers (the last light's interval ends at 2^32); empty for a light of no power.
    std::pair<std::uint64_t, std::uint64_t> u_interval(std::size_t index) const {
        constexpr int kLowBits = 32 - kProbabilityUnitBits;
        return {std::uint64_t(table_.cdf(index)) << kLowBits, std::uint64_t(table_.cdf(index + 1))
                                                                  << kLowBits};
    }
    const InfiniteSplit& split() const { return split_; }

  private:
    std::size_t n_ = 0;
    /// Light k holds units [cdf(k), cdf(k + 1)) of 2^23; with a split, an entry past the last
    /// light holds the split's range.
    UnitCdf table_;
    InfiniteSplit split_;
};

/// --light-sampler bvh: the 2^23 units of u >> 9 are laid out as [floor | tree | infinite
/// lights]: the finite lights' floor evenly, the rest of their share down the light tree at the
/// shading point, then each infinite light's fixed units or the split.
class BvhLightChooser {
  public:
    BvhLightChooser() = default;
    BvhLightChooser(const Scene& scene, const LightWeights& weights);

    /// As PowerLightChooser::sample(), and nullopt when u falls to lights that cannot light
    /// ctx.p.
    std::optional<LightChoice> sample(const LightChoiceContext& ctx, std::uint32_t u) const;
    /// As PowerLightChooser::pmf().
    float pmf(const LightChoiceContext& ctx, std::size_t index) const {
        if (split_.holds(index)) return split_.pmf(ctx, index);
        return tree_pmf(ctx, index);
    }
    const LightTree& tree() const { return tree_; }
    const InfiniteSplit& split() const { return split_; }

  private:
    float tree_pmf(const LightChoiceContext& ctx, std::size_t index) const;

    std::size_t n_ = 0;
    LightTree tree_;
    std::vector<std::uint32_t> fixed_units_;  ///< by light: an infinite light's units, else 0
    std::vector<std::uint32_t> floor_lights_; ///< emitting finite lights, for the floor
    std::vector<std::uint8_t> in_tree_;       ///< by light: 1 for an emitting finite light
    std::uint32_t floor_units_ = 0;           ///< each floor light's share of the floor
    std::uint32_t tree_begin_ = 0, tree_end_ = 0;
    /// The emitting infinite lights, and where each one's units end.
    std::vector<std::uint32_t> infinite_lights_, infinite_end_;
    InfiniteSplit split_;
};

/// The light choice of a render: the rule a scene and --light-sampler resolve to.
class LightChooser {
    std::variant<PowerLightChooser, BvhLightChooser> rule_;
    /// f(rule) for the rule in use: one branch on the variant's index (defined first, so that
    /// the members below can use its deduced type).
    template <class F> decltype(auto) visit(const F& f) const {
        if (const BvhLightChooser* tree = std::get_if<BvhLightChooser>(&rule_)) return f(*tree);
        return f(*std::get_if<PowerLightChooser>(&rule_));
    }

  public:
    LightChooser() = default;
    /// Builds the rule `kind` resolves to from scene.lights. Lights of zero power are never
    /// chosen; when every light has zero power the choice is uniform. Throws
    /// Error(ErrorKind::Scene) naming the light when a power is negative or not finite, and
    /// Error(ErrorKind::Internal) when a light's record is inconsistent with the scene (mesh or
    /// sphere index out of range, triangle tables of the wrong size, environment light without a
    /// map), so that sampling never reads out of bounds.
    explicit LightChooser(const Scene& scene, LightSamplerKind kind = LightSamplerKind::Power);

    /// The rule's sample(ctx, u).
    std::optional<LightChoice> sample(const LightChoiceContext& ctx, std::uint32_t u) const {
        // inline: the common one-light scene, whose interval is all of u's range
        if (n_ == 1)
            return LightChoice{0u, 1.f, u >> (32 - kProbabilityUnitBits), kProbabilityUnits};
        return visit([&](const auto& rule) { return rule.sample(ctx, u); });
    }
    /// The rule's pmf(ctx, index).
    float pmf(const LightChoiceContext& ctx, std::size_t index) const {
        return visit([&](const auto& rule) { return rule.pmf(ctx, index); });
    }
    /// The infinite lights' split of the rule (inactive without one).
    const InfiniteSplit& split() const {
        return visit([](const auto& rule) -> const InfiniteSplit& { return rule.split(); });
    }
    std::size_t size() const { return n_; }
    /// The rule in use: Power or Bvh (never Auto).
    LightSamplerKind kind() const {
        return bvh() ? LightSamplerKind::Bvh : LightSamplerKind::Power;
    }
    /// The rule itself, or null when the other one is in use.
    const PowerLightChooser* power() const { return std::get_if<PowerLightChooser>(&rule_); }
    const BvhLightChooser* bvh() const { return std::get_if<BvhLightChooser>(&rule_); }

  private:
    std::size_t n_ = 0;
};

/// The orientation LightChoiceContext::n takes at a shading point: the shading normal
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
