#pragma once
// A bounding volume hierarchy over a scene's finite lights for choosing one light in proportion
// to an estimate of its contribution at a shading point (the idea of Conty Estevez and Kulla,
// "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018, and of pbrt-v4's
// BVHLightSampler). Each node bounds its lights' positions (a box), the directions they emit in
// (a cone of axis w and half-angle theta_o, widened by theta_e, the angle beyond it that light
// still leaves), their total power, and where that power sits: its mean position mu and spread
// sigma^2 (the power-weighted mean squared distance of the emitting points from mu). Its
// importance at a point p with normal n is
//     power * cos(theta') * cos(theta'_i) / (|p - mu|^2 + sigma^2),
// the denominator being the power-weighted mean of the squared distance from p to the node's
// emitting points, so that the importance follows p inside the node's bounds as well as outside:
// a node whose power sits in one light near p weighs more there than one whose power is spread
// through the same box. theta' is the smallest angle the cone can make with a direction from
// the box to p, zero beyond theta_e, and theta'_i the smallest angle a direction into the box
// can make with n; inside the box's bounding sphere both are taken as zero. The angular factors
// are upper bounds over the node's lights, so a node whose importance is zero holds no light
// that can light p.
//
// A choice descends from the root, at each node splitting the range of a uniform integer in
// proportion to the two children's importances (every child with a positive importance keeps at
// least as many values as it has lights, so none becomes unreachable). The light's probability
// is the length of the range it ends with, in units of 2^-23: an exact integer that pmf()
// recomputes by following the same splits to that light.
#include "candela/math/vec.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <vector>

namespace candela {

/// Where a finite light can be and what it emits, for the light tree.
struct LightCone {
    Vec3 lo{0.f}, hi{0.f}; ///< box of the emitting points
    Vec3 axis{0.f, 0.f, 1.f};
    float cos_o = -1.f; ///< cosine of the cone's half-angle (-1: every direction)
    float cos_e = 0.f;  ///< cosine of the angle beyond the cone that emission still reaches
    double power = 0.0;
    bool two_sided = false; ///< emits along -axis alike (emissive meshes)
    Vec3 mean{0.f};         ///< power-weighted mean of the emitting points
    double spread2 = 0.0;   ///< power-weighted mean squared distance of those points from mean
};

/// The bounds of finite light `light` of `scene` with selection power `power`.
LightCone light_cone(const Scene& scene, const Light& light, double power);

class LightTree {
  public:
    LightTree() = default;
    /// Builds the tree over the lights `index` (scene indices) with their cones. At most 2^22
    /// lights (throws Error(Internal) beyond).
    LightTree(const std::vector<std::uint32_t>& index, const std::vector<LightCone>& cones);

    bool empty() const { return nodes_.empty(); }
    std::size_t node_count() const { return nodes_.size(); }

    /// Chooses a light for the point p with normal n (zero: no normal) from u in [0, range),
    /// range >= the number of lights. Returns the scene index of the light, or -1 when no light
    /// can light p; *units receives the length of the chosen light's range and *offset (when
    /// given) u's place in it, in [0, *units).
    std::int64_t sample(const Vec3& p, const Vec3& n, std::uint32_t u, std::uint32_t range,
                        std::uint32_t* units, std::uint32_t* offset = nullptr) const;
    /// The length of the range from which sample(p, n, ., range) returns scene light `light`
    /// (0 when it never does, or when the light is not in the tree).
    std::uint32_t units(const Vec3& p, const Vec3& n, std::uint32_t light,
                        std::uint32_t range) const;

    /// A node's cone in the form the importance reads (centre, bounding radius, sin theta_o).
    struct Bound {
        Vec3 centre{0.f}, axis{0.f, 0.f, 1.f};
        Vec3 mean{0.f};      ///< LightCone::mean
        float spread2 = 0.f; ///< LightCone::spread2
        float r2 = 0.f, r = 0.f;
        float cos_o = -1.f, sin_o = 0.f;
        float cos_e = 0.f; ///< already widened by the slack
        bool two_sided = false;
        double power = 0.0;
    };
    static Bound bound_of(const LightCone& c);
    /// The importance of light_cone_importance() from a node's Bound; n unit or zero.
    static double importance(const Bound& b, const Vec3& p, const Vec3& n);

  private:
    struct Node {
        Bound bound;
        LightCone cone;
        std::uint32_t right = 0;  ///< interior: index of the second child (the first is next)
        std::uint32_t light = 0;  ///< leaf: scene index of its light
        std::uint32_t leaves = 0; ///< lights below (1 for a leaf)
    };
    /// The path from the root to a light: bit k set when step k goes to the second child.
    struct Trail {
        std::uint64_t bits = 0;
        std::int32_t depth = -1; ///< -1: not in the tree
    };
    std::uint32_t build(std::vector<std::uint32_t>& order, std::size_t begin, std::size_t end,
                        const std::vector<std::uint32_t>& index,
                        const std::vector<LightCone>& cones, std::uint64_t bits, int depth);
    /// One descent, choosing by u (when follow is null) or along *follow.
    std::int64_t descend(const Vec3& p, const Vec3& n, std::uint32_t u, std::uint32_t range,
                         const Trail* follow, std::uint32_t* units,
                         std::uint32_t* offset = nullptr) const;

    std::vector<Node> nodes_;
    std::vector<Trail> trail_; ///< by scene light index
};

/// Importance of a node's cone at p with unit normal n (zero n: no normal factor), as above.
double light_cone_importance(const LightCone& c, const Vec3& p, const Vec3& n);

} // namespace candela
