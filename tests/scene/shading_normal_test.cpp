// The shading-normal correction (adapt_shading_normal): the viewer is never below the shading
// surface, the shading normal stays on the geometric normal's side, the bend is continuous, and
// hits that need no correction are left alone.
#include "candela/scene/interaction.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace candela;

namespace {

SurfaceInteraction hit(const Vec3& ng, const Vec3& ns, const Vec3& wo) {
    SurfaceInteraction si;
    si.ng = normalize(ng);
    si.ns = normalize(ns);
    si.wo = normalize(wo);
    si.frame = Frame(si.ns);
    return si;
}

} // namespace

TEST_CASE("shading normals: the viewer stays above the shading surface", "[scene][quick]") {
    const Vec3 ng(0, 0, 1);
    SECTION("a viewer well above the shading surface: unchanged") {
        SurfaceInteraction si = hit(ng, Vec3(0.3f, 0, 1), Vec3(0.2f, 0.1f, 1));
        const Vec3 before = si.ns;
        adapt_shading_normal(si);
        CHECK(si.ns == before);
    }
    for (float side : {1.f, -1.f}) {
        // A silhouette: the viewer is 10 degrees above the geometric plane (on either side) and
        // the interpolated normal leans 40 degrees away from it.
        const float a = deg_to_rad(10.f);
        const Vec3 wo(std::cos(a), 0.f, side * std::sin(a));
        SurfaceInteraction si = hit(ng, Vec3(-side * std::sin(0.7f), 0, std::cos(0.7f)), wo);
        REQUIRE(side * dot(si.wo, si.ns) < 0.f); // below the shading surface before
        adapt_shading_normal(si);
        const float cos_g = std::abs(dot(si.wo, si.ng));
        INFO("side " << side << ": wo.ns = " << dot(si.wo, si.ns));
        CHECK(side * dot(si.wo, si.ns) >= 0.5f * kShadingBendFraction * cos_g);
        CHECK(dot(si.ns, si.ng) > 0.f);                        // still on ng's side
        CHECK(std::abs(length(si.ns) - 1.f) < 1e-6f);          // unit
        CHECK(std::abs(dot(si.frame.n, si.ns) - 1.f) < 1e-6f); // the frame follows
    }
    SECTION("continuous at the threshold") {
        // Shading normals that put the viewer just above and just below the threshold tau.
        const Vec3 wo = normalize(Vec3(1.f, 0.f, 0.2f));
        const float tau = kShadingBendFraction * dot(wo, ng);
        auto normal_with_cos = [&](float c) {
            // A unit normal in the x-z plane with dot(wo, n) = c and n.z > 0.
            const float phi = std::atan2(wo.z, wo.x);
            const float t = std::acos(c) + phi;
            return Vec3(std::cos(t), 0.f, std::sin(t));
        };
        SurfaceInteraction above = hit(ng, normal_with_cos(tau + 1e-4f), wo);
        SurfaceInteraction below = hit(ng, normal_with_cos(tau - 1e-4f), wo);
        const Vec3 ns_above = above.ns;
        adapt_shading_normal(above);
        adapt_shading_normal(below);
        CHECK(above.ns == ns_above);
        CHECK(length(below.ns - above.ns) < 1e-3f);
    }
    SECTION("a viewer in the geometric plane gets the geometric normal") {
        SurfaceInteraction si = hit(ng, Vec3(0.3f, 0, 1), Vec3(1, 0, 0));
        adapt_shading_normal(si);
        CHECK(si.ns == ng);
    }
}
