// Light selection for next-event estimation: each light's power, its share and the table or tree
// that chooses by them.
#include "candela/light/light_sampler.h"

#include "candela/light/light_sampling.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <cmath>
#include <cstdio>
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
/// light_sampler.h.
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
        char share[32];
        std::snprintf(share, sizeof share, "%.3g", power[k] / t);
        out.push_back(scene.source + ": light " + std::to_string(k) + " (" +
                      light_kind_name(scene.lights[k].kind) + ") emits " + share + " of the " +
                      (scene.lights[k].is_infinite() ? "infinite" : "finite") +
                      " lights' power: it adds almost nothing to the image, yet takes its floor "
                      "share of the light samples");
    }
    return out;
}

LightSampler::LightSampler(const Scene& scene, LightSamplerKind kind) {
    const std::size_t n = scene.lights.size();
    if (n == 0) return;
    const std::vector<double> power = light_selection_powers(scene);
    const std::vector<double> share = selection_shares(scene, power);
    n_ = n;
    split_slot_.assign(n, -1);
    std::size_t finite = 0;
    std::vector<std::uint32_t> infinite; // the emitting infinite lights
    for (std::size_t k = 0; k < n; ++k) {
        if (!(power[k] > 0.0)) continue;
        if (scene.lights[k].is_infinite())
            infinite.push_back(std::uint32_t(k));
        else
            ++finite;
    }
    tree_mode_ = n > 1 && finite > 0 &&
                 (kind == LightSamplerKind::Bvh ||
                  (kind == LightSamplerKind::Auto && finite >= kTreeMinLights));
    if (tree_mode_) {
        build_tree(scene, power, share);
        if (infinite.size() >= 2) {
            std::vector<std::uint32_t> fixed;
            for (std::uint32_t k : infinite_lights_)
                fixed.push_back(fixed_units_[k]);
            build_split(scene, infinite_lights_, tree_end_, kProbabilityUnits - tree_end_, fixed);
        }
        return;
    }
    std::vector<std::uint32_t> units = weights_to_units(share, 0.0);
    if (infinite.size() >= 2) {
        // The infinite lights' units become one range after every other light's (an entry of
        // the table past the last light), which the split shares out at each point.
        std::vector<std::uint32_t> fixed;
        std::uint32_t range = 0;
        for (std::uint32_t k : infinite) {
            fixed.push_back(units[k]);
            range += units[k];
            units[k] = 0;
        }
        units.push_back(range);
        table_ = UnitCdf(units);
        build_split(scene, infinite, table_.cdf(n), range, fixed);
        return;
    }
    table_ = UnitCdf(units);
}

void LightSampler::build_split(const Scene& scene, const std::vector<std::uint32_t>& lights,
                               std::uint32_t begin, std::uint32_t units,
                               const std::vector<std::uint32_t>& fixed) {
    split_lights_ = lights;
    split_fixed_ = fixed;
    split_begin_ = begin;
    split_range_ = units;
    for (std::size_t i = 0; i < lights.size(); ++i) {
        split_slot_[lights[i]] = std::int32_t(i);
        split_models_.push_back(infinite_irradiance_model(scene, scene.lights[lights[i]]));
    }
    // Every light's floor must be a unit at least, or a light that lights the point could be
    // left without any: otherwise (a range too small for this many lights), and with more
    // lights than the stack holds, the split stays fixed.
    split_oriented_ = lights.size() <= kMaxOrientedLights &&
                      double(units) * kLightFloorShare / double(lights.size()) >= 1.0;
    split_directional_ = false;
    for (const InfiniteIrradiance& m : split_models_)
        split_directional_ |= split_oriented_ && m.kind == LightKind::Directional;
}

InfiniteShares LightSampler::infinite_shares(const Vec3& n) const {
    InfiniteShares shares;
    if (!split_oriented_ || (n.x == 0.f && n.y == 0.f && n.z == 0.f)) return shares;
    for (std::size_t i = 0; i < split_models_.size(); ++i) {
        shares.irradiance[i] = light_irradiance(split_models_[i], n);
        shares.total += double(shares.irradiance[i]);
    }
    return shares;
}

std::uint32_t LightSampler::split_units(std::size_t slot, const InfiniteShares& shares) const {
    if (!(shares.total > 0.0)) return split_fixed_[slot];
    const double m = double(split_models_.size());
    const double share = (1.0 - kLightFloorShare) * double(shares.irradiance[slot]) / shares.total +
                         kLightFloorShare / m;
    // Rounded down: the units sum to at most the range, and the floor keeps each above zero.
    return std::uint32_t(share * double(split_range_));
}

std::optional<LightChoice> LightSampler::sample_split(std::uint32_t v, const Vec3& n,
                                                      const InfiniteShares* given) const {
    const InfiniteShares shares = given ? *given : infinite_shares(n);
    std::uint32_t begin = 0;
    for (std::size_t i = 0; i < split_models_.size(); ++i) {
        const std::uint32_t units = split_units(i, shares);
        if (v - begin < units)
            return LightChoice{split_lights_[i], float(units) * 0x1p-23f, v - begin, units};
        begin += units;
    }
    return std::nullopt;
}

void LightSampler::build_tree(const Scene& scene, const std::vector<double>& power,
                              const std::vector<double>& share) {
    // Units of the whole choice: the finite lights' group as one entry, each infinite light as
    // its own, in the shares of the power rule (so both rules weigh the groups alike).
    std::vector<double> entry_share = {0.0};
    std::vector<std::uint32_t> tree_lights;
    std::vector<LightCone> cones;
    fixed_units_.assign(n_, 0u);
    in_tree_.assign(n_, 0u);
    for (std::size_t k = 0; k < n_; ++k) {
        if (!(power[k] > 0.0)) continue;
        if (scene.lights[k].is_infinite()) {
            infinite_lights_.push_back(std::uint32_t(k));
            entry_share.push_back(share[k]);
        } else {
            entry_share[0] += share[k];
            tree_lights.push_back(std::uint32_t(k));
            cones.push_back(light_cone(scene, scene.lights[k], power[k]));
            in_tree_[k] = 1u;
        }
    }
    const std::vector<std::uint32_t> units = weights_to_units(entry_share, 0.0);
    const std::uint32_t finite_units = units[0];
    const auto m = std::uint32_t(tree_lights.size());
    // The floor: kLightFloorShare of the group, evenly; the tree keeps at least a unit per light.
    floor_units_ = std::uint32_t(double(finite_units) * kLightFloorShare / double(m));
    if (finite_units - floor_units_ * m < m) floor_units_ = 0;
    floor_lights_ = tree_lights;
    tree_begin_ = floor_units_ * m;
    tree_end_ = finite_units;
    std::uint32_t end = finite_units;
    for (std::size_t i = 0; i < infinite_lights_.size(); ++i) {
        fixed_units_[infinite_lights_[i]] = units[i + 1];
        end += units[i + 1];
        infinite_end_.push_back(end);
    }
    tree_ = LightTree(tree_lights, cones);
}

std::string describe_light_selection(const Scene& scene, LightSamplerKind kind) {
    const LightSampler sampler(scene, kind);
    std::size_t finite = 0;
    for (const Light& l : scene.lights)
        finite += !l.is_infinite();
    std::string text = enum_name(kLightSamplerKinds, sampler.kind());
    text += std::string(" (") + enum_name(kLightSamplerKinds, kind) + ": " +
            std::to_string(finite) + " finite light" + (finite == 1 ? "" : "s");
    if (sampler.kind() == LightSamplerKind::Bvh)
        text += ", " + std::to_string(sampler.tree().node_count()) + " tree nodes";
    if (sampler.oriented_lights() > 0)
        text += ", " + std::to_string(sampler.oriented_lights()) +
                " infinite lights split by orientation";
    return text + ")";
}

std::optional<LightChoice> LightSampler::sample_table(std::uint32_t u, const Vec3& n,
                                                      const InfiniteShares* shares) const {
    if (n_ == 0) return std::nullopt;
    const std::uint32_t k = table_.find(u);
    const std::uint32_t unit = u >> (32 - kProbabilityUnitBits);
    // Past the last light: the infinite lights' range.
    if (k == n_) return sample_split(unit - split_begin_, n, shares);
    return LightChoice{k, table_.pmf(k), unit - table_.cdf(k), table_.units(k)};
}

std::optional<LightChoice> LightSampler::sample_tree(std::uint32_t u, const Vec3& p, const Vec3& n,
                                                     const InfiniteShares* shares) const {
    const std::uint32_t v = u >> (32 - kProbabilityUnitBits); // a uniform unit
    if (v < tree_begin_) {
        const std::uint32_t k = floor_lights_[v / floor_units_];
        return LightChoice{k, pmf_tree(p, n, k), v % floor_units_, floor_units_};
    }
    if (v < tree_end_) {
        std::uint32_t units = 0, offset = 0;
        const std::int64_t k =
            tree_.sample(p, n, v - tree_begin_, tree_end_ - tree_begin_, &units, &offset);
        if (k < 0) return std::nullopt;
        return LightChoice{std::uint32_t(k), float(floor_units_ + units) * 0x1p-23f, offset, units};
    }
    if (infinite_split()) return sample_split(v - split_begin_, n, shares);
    std::uint32_t begin = tree_end_;
    for (std::size_t i = 0; i < infinite_lights_.size(); ++i) {
        if (v < infinite_end_[i])
            return LightChoice{infinite_lights_[i],
                               float(fixed_units_[infinite_lights_[i]]) * 0x1p-23f, v - begin,
                               infinite_end_[i] - begin};
        begin = infinite_end_[i];
    }
    return std::nullopt;
}

float LightSampler::pmf_tree(const Vec3& p, const Vec3& n, std::size_t index) const {
    if (index >= n_) return 0.f;
    if (fixed_units_[index] > 0) return float(fixed_units_[index]) * 0x1p-23f;
    if (!in_tree_[index]) return 0.f;
    const std::uint32_t units = tree_.units(p, n, std::uint32_t(index), tree_end_ - tree_begin_);
    return float(floor_units_ + units) * 0x1p-23f;
}

} // namespace candela
