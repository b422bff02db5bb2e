// Light choice for next-event estimation: each light's power and share, the infinite lights'
// split, and the two rules (a table of units, a light tree) that choose by them.
#include "candela/light/light_choice.h"

#include "candela/light/light_sample.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <string>

namespace candela {

namespace {

/// "light 3 (mesh)", for messages.
std::string light_label(const Scene& scene, std::size_t k) {
    return "light " + std::to_string(k) + " (" + light_kind_name(scene.lights[k].kind) + ")";
}

/// Checks that a light's references into the scene are usable by sample_li: indices from the
/// scene stage, checked in every build (util/check.h).
void validate_light(const Scene& scene, std::size_t k) {
    const Light& light = scene.lights[k];
    const auto label = [&] { return scene.source + ": " + light_label(scene, k); };
    if (light.kind == LightKind::Mesh) {
        CANDELA_CHECK(light.geom_id < scene.meshes.size(),
                      label() + " refers to mesh " + std::to_string(light.geom_id) + " of " +
                          std::to_string(scene.meshes.size()));
        const Mesh& mesh = scene.meshes[light.geom_id];
        CANDELA_CHECK(light.tri_choice.size() == mesh.triangle_count() &&
                          light.tri_area_per_pmf.size() == mesh.triangle_count(),
                      label() + " has " + std::to_string(light.tri_choice.size()) +
                          " triangle choices and " + std::to_string(light.tri_area_per_pmf.size()) +
                          " triangle densities for " + std::to_string(mesh.triangle_count()) +
                          " triangles");
        for (std::uint32_t idx : mesh.indices)
            CANDELA_CHECK(idx < mesh.positions.size(), label() + ": mesh index out of range");
    } else if (light.kind == LightKind::Sphere) {
        CANDELA_CHECK(light.geom_id < scene.spheres.size(),
                      label() + " refers to sphere " + std::to_string(light.geom_id) + " of " +
                          std::to_string(scene.spheres.size()));
    } else if (light.kind == LightKind::Environment) {
        CANDELA_CHECK(scene.env != nullptr, label() + " has no environment map");
    }
}

} // namespace

std::vector<double> light_selection_powers(const Scene& scene) {
    const std::size_t n = scene.lights.size();
    std::vector<double> power(n);
    for (std::size_t k = 0; k < n; ++k) {
        validate_light(scene, k);
        const float p = light_power(scene, scene.lights[k]);
        if (!std::isfinite(p) || p < 0.f)
            throw Error(ErrorKind::Scene, SourceLoc{scene.source},
                        light_label(scene, k) + " has invalid power " + std::to_string(p));
        power[k] = double(p);
    }
    return power;
}

namespace {

/// Each light's selection probability before rounding to units: the groups and the floor of
/// light_choice.h.
std::vector<double> selection_shares(const Scene& scene, const std::vector<double>& power) {
    const std::size_t n = power.size();
    double finite_total = 0.0;
    std::size_t finite_emitting = 0, infinite_emitting = 0;
    double infinite_total = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        if (!(power[k] > 0.0)) continue;
        if (scene.lights[k].is_infinite()) {
            infinite_total += power[k];
            ++infinite_emitting;
        } else {
            finite_total += power[k];
            ++finite_emitting;
        }
    }
    std::vector<double> share(n, 0.0);
    const double groups = double(infinite_emitting) + (finite_emitting > 0 ? 1.0 : 0.0);
    if (groups == 0.0) return std::vector<double>(n, 1.0 / double(n)); // all dark: uniform
    const double finite_share = finite_emitting > 0 ? 1.0 / groups : 0.0;
    const double infinite_share = double(infinite_emitting) / groups;
    for (std::size_t k = 0; k < n; ++k) {
        if (!(power[k] > 0.0)) continue;
        const bool inf = scene.lights[k].is_infinite();
        const double total = inf ? infinite_total : finite_total;
        const double m = double(inf ? infinite_emitting : finite_emitting);
        share[k] = (inf ? infinite_share : finite_share) *
                   ((1.0 - kLightFloorShare) * power[k] / total + kLightFloorShare / m);
    }
    return share;
}

} // namespace

std::vector<std::string> negligible_light_warnings(const Scene& scene) {
    std::vector<std::string> out;
    if (scene.lights.size() < 2) return out;
    const std::vector<double> power = light_selection_powers(scene);
    double total[2] = {0.0, 0.0}; // finite, infinite
    for (std::size_t k = 0; k < power.size(); ++k)
        total[scene.lights[k].is_infinite()] += power[k];
    for (std::size_t k = 0; k < power.size(); ++k) {
        const double t = total[scene.lights[k].is_infinite()];
        if (!(t > 0.0) || power[k] >= kNegligiblePowerShare * t) continue;
        out.push_back(scene.source + ": light " + std::to_string(k) + " (" +
                      light_kind_name(scene.lights[k].kind) + ") emits " +
                      fmt::format("{:.3g}", power[k] / t) + " of the " +
                      (scene.lights[k].is_infinite() ? "infinite" : "finite") +
                      " lights' power: it adds almost nothing to the image, yet takes its floor "
                      "share of the light samples");
    }
    return out;
}

LightWeights light_weights(const Scene& scene) {
    LightWeights w;
    w.power = light_selection_powers(scene);
    w.share = selection_shares(scene, w.power);
    for (std::size_t k = 0; k < w.power.size(); ++k) {
        if (!(w.power[k] > 0.0)) continue;
        (scene.lights[k].is_infinite() ? w.infinite : w.finite).push_back(std::uint32_t(k));
    }
    return w;
}

LightChooser::LightChooser(const Scene& scene, LightSamplerKind kind) {
    n_ = scene.lights.size();
    if (n_ == 0) return;
    const LightWeights weights = light_weights(scene);
    const std::size_t finite = weights.finite.size();
    const bool tree = n_ > 1 && finite > 0 &&
                      (kind == LightSamplerKind::Bvh ||
                       (kind == LightSamplerKind::Auto && finite >= kTreeMinLights));
    if (tree)
        rule_.emplace<BvhLightChooser>(scene, weights);
    else
        rule_.emplace<PowerLightChooser>(scene, weights);
}

// ---------------------------------------------------------------------------------------------
// The infinite lights' split
// ---------------------------------------------------------------------------------------------
InfiniteSplit::InfiniteSplit(const Scene& scene, const std::vector<std::uint32_t>& lights,
                             const std::vector<std::uint32_t>& fixed, std::uint32_t begin,
                             std::uint32_t range)
    : lights_(lights), fixed_(fixed), slot_(scene.lights.size(), -1), begin_(begin), range_(range) {
    for (std::size_t i = 0; i < lights.size(); ++i) {
        slot_[lights[i]] = std::int32_t(i);
        models_.push_back(infinite_irradiance_model(scene, scene.lights[lights[i]]));
    }
    // Every light's floor must be a unit at least, or a light that lights the point could be
    // left without any: otherwise (a range too small for this many lights), and with more
    // lights than the stack holds, the split stays fixed.
    oriented_ = lights.size() <= kMaxOrientedLights &&
                double(range) * kLightFloorShare / double(lights.size()) >= 1.0;
    for (const InfiniteIrradiance& m : models_)
        directional_ |= oriented_ && m.kind == LightKind::Directional;
}

InfiniteShares InfiniteSplit::shares(const Vec3& n) const {
    InfiniteShares shares;
    if (!oriented_ || (n.x == 0.f && n.y == 0.f && n.z == 0.f)) return shares;
    for (std::size_t i = 0; i < models_.size(); ++i) {
        shares.irradiance[i] = light_irradiance(models_[i], n);
        shares.total += double(shares.irradiance[i]);
    }
    return shares;
}

std::uint32_t InfiniteSplit::units(std::size_t slot, const InfiniteShares& shares) const {
    if (!(shares.total > 0.0)) return fixed_[slot];
    const double m = double(models_.size());
    const double share = (1.0 - kLightFloorShare) * double(shares.irradiance[slot]) / shares.total +
                         kLightFloorShare / m;
    // Rounded down: the units sum to at most the range, and the floor keeps each above zero.
    return std::uint32_t(share * double(range_));
}

std::optional<LightChoice> InfiniteSplit::sample(const LightChoiceContext& ctx,
                                                 std::uint32_t v) const {
    const InfiniteShares shares = ctx.shares ? *ctx.shares : this->shares(ctx.n);
    std::uint32_t begin = 0;
    for (std::size_t i = 0; i < models_.size(); ++i) {
        const std::uint32_t units = this->units(i, shares);
        if (v - begin < units)
            return LightChoice{lights_[i], float(units) * 0x1p-23f, v - begin, units};
        begin += units;
    }
    return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// power
// ---------------------------------------------------------------------------------------------
PowerLightChooser::PowerLightChooser(const Scene& scene, const LightWeights& weights)
    : n_(scene.lights.size()) {
    std::vector<std::uint32_t> units = weights_to_units(weights.share, 0.0);
    if (weights.infinite.size() < 2) {
        table_ = UnitCdf(units);
        return;
    }
    // The infinite lights' units become one range after every other light's (an entry of the
    // table past the last light), which the split shares out at each point.
    std::vector<std::uint32_t> fixed;
    std::uint32_t range = 0;
    for (std::uint32_t k : weights.infinite) {
        fixed.push_back(units[k]);
        range += units[k];
        units[k] = 0;
    }
    units.push_back(range);
    table_ = UnitCdf(units);
    split_ = InfiniteSplit(scene, weights.infinite, fixed, table_.cdf(n_), range);
}

std::optional<LightChoice> PowerLightChooser::sample(const LightChoiceContext& ctx,
                                                     std::uint32_t u) const {
    if (n_ == 0) return std::nullopt;
    const std::uint32_t k = table_.find(u);
    const std::uint32_t unit = u >> (32 - kProbabilityUnitBits);
    // Past the last light: the infinite lights' range.
    if (k == n_) return split_.sample(ctx, unit - split_.begin());
    return LightChoice{k, table_.pmf(k), unit - table_.cdf(k), table_.units(k)};
}

// ---------------------------------------------------------------------------------------------
// bvh
// ---------------------------------------------------------------------------------------------
BvhLightChooser::BvhLightChooser(const Scene& scene, const LightWeights& weights)
    : n_(scene.lights.size()) {
    // Units of the whole choice: the finite lights' group as one entry, each infinite light as
    // its own, in the shares of the power rule (so both rules weigh the groups alike).
    std::vector<double> entry_share = {0.0};
    std::vector<LightCone> cones;
    fixed_units_.assign(n_, 0u);
    in_tree_.assign(n_, 0u);
    for (std::uint32_t k : weights.finite) {
        entry_share[0] += weights.share[k];
        cones.push_back(light_cone(scene, scene.lights[k], weights.power[k]));
        in_tree_[k] = 1u;
    }
    for (std::uint32_t k : weights.infinite)
        entry_share.push_back(weights.share[k]);
    const std::vector<std::uint32_t> units = weights_to_units(entry_share, 0.0);
    const std::uint32_t finite_units = units[0];
    const auto m = std::uint32_t(weights.finite.size());
    // The floor: kLightFloorShare of the group, evenly; the tree keeps at least a unit per light.
    floor_units_ = std::uint32_t(double(finite_units) * kLightFloorShare / double(m));
    if (finite_units - floor_units_ * m < m) floor_units_ = 0;
    floor_lights_ = weights.finite;
    tree_begin_ = floor_units_ * m;
    tree_end_ = finite_units;
    std::uint32_t end = finite_units;
    infinite_lights_ = weights.infinite;
    std::vector<std::uint32_t> fixed;
    for (std::size_t i = 0; i < weights.infinite.size(); ++i) {
        fixed_units_[weights.infinite[i]] = units[i + 1];
        fixed.push_back(units[i + 1]);
        end += units[i + 1];
        infinite_end_.push_back(end);
    }
    tree_ = LightTree(weights.finite, cones);
    if (weights.infinite.size() >= 2)
        split_ =
            InfiniteSplit(scene, weights.infinite, fixed, tree_end_, kProbabilityUnits - tree_end_);
}

std::optional<LightChoice> BvhLightChooser::sample(const LightChoiceContext& ctx,
                                                   std::uint32_t u) const {
    const std::uint32_t v = u >> (32 - kProbabilityUnitBits); // a uniform unit
    if (v < tree_begin_) {
        const std::uint32_t k = floor_lights_[v / floor_units_];
        return LightChoice{k, tree_pmf(ctx, k), v % floor_units_, floor_units_};
    }
    if (v < tree_end_) {
        std::uint32_t units = 0, offset = 0;
        const std::int64_t k =
            tree_.sample(ctx.p, ctx.n, v - tree_begin_, tree_end_ - tree_begin_, &units, &offset);
        if (k < 0) return std::nullopt;
        return LightChoice{std::uint32_t(k), float(floor_units_ + units) * 0x1p-23f, offset, units};
    }
    if (split_.active()) return split_.sample(ctx, v - split_.begin());
    std::uint32_t begin = tree_end_;
    for (std::size_t i = 0; i < infinite_end_.size(); ++i) {
        if (v < infinite_end_[i]) {
            const std::uint32_t k = infinite_lights_[i];
            return LightChoice{k, float(fixed_units_[k]) * 0x1p-23f, v - begin,
                               infinite_end_[i] - begin};
        }
        begin = infinite_end_[i];
    }
    return std::nullopt;
}

float BvhLightChooser::tree_pmf(const LightChoiceContext& ctx, std::size_t index) const {
    if (index >= n_) return 0.f;
    if (fixed_units_[index] > 0) return float(fixed_units_[index]) * 0x1p-23f;
    if (!in_tree_[index]) return 0.f;
    const std::uint32_t units =
        tree_.units(ctx.p, ctx.n, std::uint32_t(index), tree_end_ - tree_begin_);
    return float(floor_units_ + units) * 0x1p-23f;
}

std::string describe_light_selection(const Scene& scene, LightSamplerKind kind) {
    const LightChooser chooser(scene, kind);
    std::size_t finite = 0;
    for (const Light& l : scene.lights)
        finite += !l.is_infinite();
    std::string text = enum_name(kLightSamplerKinds, chooser.kind());
    text += std::string(" (") + enum_name(kLightSamplerKinds, kind) + ": " +
            std::to_string(finite) + " finite light" + (finite == 1 ? "" : "s");
    if (const BvhLightChooser* bvh = chooser.bvh())
        text += ", " + std::to_string(bvh->tree().node_count()) + " tree nodes";
    if (chooser.split().oriented_lights() > 0)
        text += ", " + std::to_string(chooser.split().oriented_lights()) +
                " infinite lights split by orientation";
    return text + ")";
}

} // namespace candela
