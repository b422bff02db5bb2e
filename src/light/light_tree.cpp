// The light tree: a hierarchy of bounding cones over the finite lights, built and traversed.
#include "candela/light/light_tree.h"

#include "candela/math/constants.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

namespace {

/// Widening of every emission bound (cosine units, about 2.6 degrees at theta_e = 90): the bounds
/// are computed in float, and a point just inside a spot's cone or a rectangle's plane must not
/// get importance zero from a rounding.
constexpr float kConeSlack = 1e-3f;
/// Lower bound on a squared distance (the importance's denominator): a point at a point light.
constexpr double kMinDistance2 = 1e-30;
/// The tree's depth is the length of a Trail's bit path.
constexpr int kMaxDepth = 63;

/// cos(max(0, a - b)) from the cosines and sines of a and b (angles in [0, pi]).
inline float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 1.f; // a < b
    return cos_a * cos_b + sin_a * sin_b;
}

/// sin(max(0, a - b)) likewise.
inline float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 0.f;
    return sin_a * cos_b - cos_a * sin_b;
}

/// The smallest cone holding both (pbrt-v4's DirectionCone union, written from its geometry).
void merge_cones(LightCone& a, const LightCone& b) {
    const double theta_a = std::acos(std::clamp(double(a.cos_o), -1.0, 1.0));
    const double theta_b = std::acos(std::clamp(double(b.cos_o), -1.0, 1.0));
    const double theta_d =
        std::acos(std::clamp(double(dot(a.axis, b.axis)), -1.0, 1.0)); // between the axes
    a.cos_e = std::min(a.cos_e, b.cos_e);
    a.two_sided = a.two_sided || b.two_sided;
    if (theta_a >= kPiD || theta_d + theta_b <= theta_a) return; // a holds b
    if (theta_b >= kPiD || theta_d + theta_a <= theta_b) {       // b holds a
        a.axis = b.axis;
        a.cos_o = b.cos_o;
        return;
    }
    const double theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if (theta_o >= kPiD) {
        a.cos_o = -1.f;
        return;
    }
    // Turn a's axis toward b's by theta_o - theta_a.
    const double turn = theta_o - theta_a;
    const Vec3 ortho = b.axis - a.axis * dot(a.axis, b.axis);
    const float len = length(ortho);
    if (!(len > 0.f)) {
        a.cos_o = -1.f;
        return;
    }
    a.axis = normalize(a.axis * float(std::cos(turn)) + ortho * float(std::sin(turn) / len));
    a.cos_o = float(std::cos(theta_o));
}

/// Where two nodes' power sits together: the power-weighted mean of their means, and the spread
/// about it (each node's own spread plus its mean's squared distance from the joint one). Nodes
/// without power weigh alike.
void merge_moments(LightCone& c, const LightCone& a, const LightCone& b) {
    const bool powered = a.power + b.power > 0.0;
    const double wa = powered ? a.power / (a.power + b.power) : 0.5, wb = 1.0 - wa;
    double mean[3], spread2 = 0.0;
    for (int k = 0; k < 3; ++k)
        mean[k] = wa * double(a.mean[k]) + wb * double(b.mean[k]);
    const auto add = [&](const LightCone& node, double w) {
        double off2 = 0.0;
        for (int k = 0; k < 3; ++k)
            off2 += (double(node.mean[k]) - mean[k]) * (double(node.mean[k]) - mean[k]);
        spread2 += w * (node.spread2 + off2);
    };
    add(a, wa);
    add(b, wb);
    c.mean = Vec3(float(mean[0]), float(mean[1]), float(mean[2]));
    c.spread2 = spread2;
}

LightCone merged(const LightCone& a, const LightCone& b) {
    LightCone c = a;
    c.lo = vmin(a.lo, b.lo);
    c.hi = vmax(a.hi, b.hi);
    c.power = a.power + b.power;
    merge_cones(c, b);
    merge_moments(c, a, b);
    return c;
}

/// The integer split of `range` between two children of importances il, ir and light counts
/// nl, nr: the first child's share, or -1 when neither can light the point.
std::int64_t split_range(std::uint32_t range, double il, double ir, std::uint32_t nl,
                         std::uint32_t nr) {
    if (!(il > 0.0) && !(ir > 0.0)) return -1;
    if (!(ir > 0.0)) return range;
    if (!(il > 0.0)) return 0;
    const double want = std::nearbyint(double(range) * (il / (il + ir)));
    // Each child keeps at least one value per light, so no light below becomes unreachable
    // (the caller guarantees range >= nl + nr).
    const double lo = double(std::min(nl, range)), hi = double(range) - double(nr);
    return std::int64_t(std::clamp(want, lo, std::max(lo, hi)));
}

} // namespace

LightTree::Bound LightTree::bound_of(const LightCone& c) {
    Bound b;
    b.centre = (c.lo + c.hi) * 0.5f;
    b.r2 = 0.25f * length_squared(c.hi - c.lo);
    b.r = std::sqrt(b.r2);
    b.axis = c.axis;
    b.cos_o = c.cos_o;
    b.sin_o = std::sqrt(std::max(0.f, 1.f - c.cos_o * c.cos_o));
    b.cos_e = c.cos_e - kConeSlack;
    b.two_sided = c.two_sided;
    b.power = c.power;
    b.mean = c.mean;
    b.spread2 = float(c.spread2);
    return b;
}

double LightTree::importance(const Bound& b, const Vec3& p, const Vec3& n) {
    const Vec3 to_p = p - b.centre;
    const float d2 = length_squared(to_p);
    // The power-weighted mean squared distance from p to the node's emitting points (at least
    // kMinDistance2, for a point light at p). In double: a power of 1e9 over a distance of
    // 1e-15 overflows a float.
    const double spread_d2 =
        std::max(double(length_squared(p - b.mean)) + double(b.spread2), kMinDistance2);
    // Inside the bounding sphere every direction may reach a light: no angular bound.
    if (!(d2 > b.r2)) return b.power / spread_d2;
    const float inv_d = 1.f / std::sqrt(d2);
    // theta_b: half-angle of the cone of directions from p into the bounding sphere.
    const float sin_b = std::min(1.f, b.r * inv_d);
    const float cos_b = std::sqrt(std::max(0.f, 1.f - sin_b * sin_b));
    float cos_p = 1.f; // cos(theta'), the emission factor
    if (b.cos_o > -1.f) {
        float cos_w = std::clamp(dot(b.axis, to_p) * inv_d, -1.f, 1.f);
        if (b.two_sided) cos_w = std::abs(cos_w);
        const float sin_w = std::sqrt(std::max(0.f, 1.f - cos_w * cos_w));
        // theta_w - theta_o, then minus theta_b.
        const float cos_x = cos_sub_clamped(sin_w, cos_w, b.sin_o, b.cos_o);
        const float sin_x = sin_sub_clamped(sin_w, cos_w, b.sin_o, b.cos_o);
        cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if (cos_p <= b.cos_e) return 0.0;
        cos_p = std::max(cos_p, 0.f);
    }
    float cos_n = 1.f; // cos(theta'_i), the surface factor (n is unit or zero)
    if (n.x != 0.f || n.y != 0.f || n.z != 0.f) {
        const float cos_i = std::min(1.f, std::abs(dot(n, to_p)) * inv_d);
        const float sin_i = std::sqrt(std::max(0.f, 1.f - cos_i * cos_i));
        cos_n = std::max(cos_sub_clamped(sin_i, cos_i, sin_b, cos_b), 0.f) + kConeSlack;
    }
    return b.power * double(cos_p * cos_n) / spread_d2;
}

double light_cone_importance(const LightCone& c, const Vec3& p, const Vec3& n) {
    return LightTree::importance(LightTree::bound_of(c), p, n);
}

LightCone light_cone(const Scene& scene, const Light& light, double power) {
    LightCone c;
    c.power = power;
    c.cos_e = 0.f; // pi/2: every finite light's emission fades to zero at most 90 degrees out
    switch (light.kind) {
    case LightKind::Point:
        c.lo = c.hi = light.p;
        break;
    case LightKind::Spot:
        c.lo = c.hi = light.p;
        c.axis = light.n;
        c.cos_o = 1.f;
        c.cos_e = light.cos_total;
        break;
    case LightKind::Area: {
        for (float s : {-0.5f, 0.5f})
            for (float t : {-0.5f, 0.5f}) {
                const Vec3 q = light.p + light.dx * s + light.dy * t;
                c.lo = s == -0.5f && t == -0.5f ? q : vmin(c.lo, q);
                c.hi = s == -0.5f && t == -0.5f ? q : vmax(c.hi, q);
            }
        c.axis = light.n;
        c.cos_o = 1.f;
        break;
    }
    case LightKind::Mesh: {
        const Mesh& mesh = scene.meshes[light.geom_id];
        Bounds3 b;
        for (std::uint32_t idx : mesh.indices)
            b.grow(mesh.positions[idx]);
        c.lo = b.lo;
        c.hi = b.hi;
        break;
    }
    case LightKind::Sphere: {
        if (light.geom_id < scene.spheres.size()) {
            const Bounds3 b = scene.spheres[light.geom_id].bounds();
            c.lo = b.lo;
            c.hi = b.hi;
        } else {
            c.lo = light.p - Vec3(light.radius);
            c.hi = light.p + Vec3(light.radius);
        }
        break;
    }
    default:
        throw Error(ErrorKind::Internal,
                    std::string("light tree: infinite light kind ") + light_kind_name(light.kind));
    }
    // One light's power is taken as spread evenly through its box: the mean is the box's centre
    // and the spread the box's second moment about it, (dx^2 + dy^2 + dz^2) / 12 (exact for an
    // axis-aligned rectangle; r^2 for a sphere of radius r; zero for a point or a spot).
    c.mean = (c.lo + c.hi) * 0.5f;
    c.spread2 = double(length_squared(c.hi - c.lo)) / 12.0;
    return c;
}

LightTree::LightTree(const std::vector<std::uint32_t>& index, const std::vector<LightCone>& cones) {
    if (index.empty()) return;
    CANDELA_CHECK(index.size() <= (std::size_t(1) << 22) && index.size() == cones.size(),
                  "light tree: " + std::to_string(index.size()) + " lights");
    std::uint32_t max_light = 0;
    for (std::uint32_t k : index)
        max_light = std::max(max_light, k);
    trail_.assign(std::size_t(max_light) + 1, Trail{});
    std::vector<std::uint32_t> order(index.size());
    for (std::uint32_t i = 0; i < order.size(); ++i)
        order[i] = i;
    nodes_.reserve(2 * index.size());
    build(order, 0, order.size(), index, cones, 0, 0);
}

std::uint32_t LightTree::build(std::vector<std::uint32_t>& order, std::size_t begin,
                               std::size_t end, const std::vector<std::uint32_t>& index,
                               const std::vector<LightCone>& cones, std::uint64_t bits, int depth) {
    const auto at = std::uint32_t(nodes_.size());
    nodes_.emplace_back();
    if (end - begin == 1) {
        const std::uint32_t k = order[begin];
        nodes_[at].cone = cones[k];
        nodes_[at].bound = bound_of(cones[k]);
        nodes_[at].light = index[k];
        nodes_[at].leaves = 1;
        trail_[index[k]] = Trail{bits, depth};
        return at;
    }
    // Median split on the longest axis of the lights' centres: a balanced tree (depth
    // ceil(log2 n)) in O(n log n).
    Bounds3 centres;
    for (std::size_t i = begin; i < end; ++i)
        centres.grow((cones[order[i]].lo + cones[order[i]].hi) * 0.5f);
    const Vec3 extent = centres.hi - centres.lo;
    const int axis =
        extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(order.begin() + std::ptrdiff_t(begin), order.begin() + std::ptrdiff_t(mid),
                     order.begin() + std::ptrdiff_t(end), [&](std::uint32_t a, std::uint32_t b) {
                         return cones[a].lo[axis] + cones[a].hi[axis] <
                                cones[b].lo[axis] + cones[b].hi[axis];
                     });
    CANDELA_CHECK(depth < kMaxDepth, "light tree: too deep");
    const std::uint32_t left = build(order, begin, mid, index, cones, bits, depth + 1);
    const std::uint32_t right =
        build(order, mid, end, index, cones, bits | (std::uint64_t(1) << depth), depth + 1);
    nodes_[at].right = right;
    nodes_[at].leaves = std::uint32_t(end - begin);
    nodes_[at].cone = merged(nodes_[left].cone, nodes_[right].cone);
    nodes_[at].bound = bound_of(nodes_[at].cone);
    return at;
}

std::int64_t LightTree::descend(const Vec3& p, const Vec3& n, std::uint32_t u, std::uint32_t range,
                                const Trail* follow, std::uint32_t* units,
                                std::uint32_t* offset) const {
    std::uint32_t node = 0;
    for (int depth = 0; nodes_[node].leaves > 1; ++depth) {
        const std::uint32_t left = node + 1, right = nodes_[node].right;
        const std::int64_t t = split_range(range, importance(nodes_[left].bound, p, n),
                                           importance(nodes_[right].bound, p, n),
                                           nodes_[left].leaves, nodes_[right].leaves);
        if (t < 0) return -1;
        const bool second = follow ? ((follow->bits >> depth) & 1u) != 0 : u >= std::uint32_t(t);
        if (second) {
            u -= std::uint32_t(t);
            range -= std::uint32_t(t);
            node = right;
        } else {
            range = std::uint32_t(t);
            node = left;
        }
        if (range == 0) return -1;
    }
    *units = range;
    if (offset) *offset = u;
    return nodes_[node].light;
}

std::int64_t LightTree::sample(const Vec3& p, const Vec3& n, std::uint32_t u, std::uint32_t range,
                               std::uint32_t* units, std::uint32_t* offset) const {
    if (nodes_.empty()) return -1;
    return descend(p, n, u, range, nullptr, units, offset);
}

std::uint32_t LightTree::units(const Vec3& p, const Vec3& n, std::uint32_t light,
                               std::uint32_t range) const {
    if (light >= trail_.size() || trail_[light].depth < 0) return 0;
    std::uint32_t units = 0;
    return descend(p, n, 0, range, &trail_[light], &units) == std::int64_t(light) ? units : 0;
}

} // namespace candela
