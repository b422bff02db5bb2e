// The named draws of a path vertex (render/vertex_draws.h): the dimensions the integrator's one
// declaration gives each draw are the layout rendering.md documents ("Sample dimensions"), which
// every rendered image depends on, and the plan of a vertex holds the planned draws alone, each
// in its form. (That the plan covers every draw the estimators make is wavefront_test's.)
#include "../support/cs184.h"
#include "render_support.h"

#include "candela/render/integrator.h"
#include "candela/render/vertex_draws.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// The integrator's layout for `s` on lights.dae (several lights, delta and infinite among them).
struct Declared {
    DimensionLayout dims;
    std::uint32_t lights = 0;            ///< Scene::lights.size()
    std::uint32_t all_light_samples = 0; ///< -l per non-delta light, one per delta light
};

Declared declared(const RenderSettings& s) {
    Diagnostics diag;
    const Scene scene = load_scene(project_scene("lights.dae"), BuildOptions{}, diag);
    const std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    const Integrator integrator(scene, *accel, s);
    Declared d{integrator.dimensions(), std::uint32_t(scene.lights.size()), 0};
    for (const Light& l : scene.lights)
        d.all_light_samples += l.is_delta() ? 1u : std::uint32_t(s.light_samples);
    return d;
}

RenderSettings settings(IntegratorKind kind, int light_samples, bool hemisphere) {
    RenderSettings s;
    s.width = s.height = 4;
    s.integrator = kind;
    s.light_samples = light_samples;
    s.hemisphere = hemisphere;
    return s;
}

} // namespace

TEST_CASE("vertex draws: the path integrator's dimensions", "[render][sampler][quick]") {
    const Declared d = declared(settings(IntegratorKind::Path, 2, false));
    REQUIRE(d.lights > 1);
    using D = VertexDraw;
    // Per light sample a fill and the 2-D point (3 dimensions), then the BSDF direction (2), its
    // lobe (1) and the roulette number (1).
    CHECK(d.dims.stride() == 3 * 2 + 4);
    CHECK(d.dims.vertex(0) == DimensionLayout::kFirstVertex);
    CHECK(d.dims.vertex(2) == DimensionLayout::kFirstVertex + 2 * d.dims.stride());
    const std::uint32_t v1 = d.dims.vertex(1);
    CHECK(d.dims.dim(D::light_fill, 1, 0) == v1);
    CHECK(d.dims.dim(D::light_point, 1, 0) == v1 + 1);
    CHECK(d.dims.dim(D::light_fill, 1, 1) == v1 + 3);
    CHECK(d.dims.dim(D::light_point, 1, 1) == v1 + 4);
    CHECK(d.dims.dim(D::bsdf_direction, 1) == v1 + 6);
    CHECK(d.dims.dim(D::bsdf_lobe, 1) == v1 + 8);
    CHECK(d.dims.dim(D::roulette, 1) == v1 + 9);
    CHECK_FALSE(d.dims.declared(D::hemisphere_direction));
}

TEST_CASE("vertex draws: the direct integrator's and -H's dimensions", "[render][sampler][quick]") {
    using D = VertexDraw;
    const Declared direct = declared(settings(IntegratorKind::Direct, 3, false));
    // Every light's samples, 2 dimensions each, then the BSDF direction and lobe: no roulette.
    const std::uint32_t light_dims = 2 * direct.all_light_samples;
    CHECK(direct.dims.stride() == light_dims + 3);
    CHECK(direct.dims.dim(D::light_point, 0, 1) == DimensionLayout::kFirstVertex + 2);
    CHECK(direct.dims.dim(D::bsdf_direction, 0) == DimensionLayout::kFirstVertex + light_dims);
    CHECK_FALSE(direct.dims.declared(D::light_fill));
    CHECK_FALSE(direct.dims.declared(D::roulette));

    // -H: |lights| x -l hemisphere directions of 2 dimensions.
    const Declared hemi = declared(settings(IntegratorKind::Path, 2, true));
    const std::uint32_t hemi_dims = 2 * hemi.lights * 2;
    CHECK(hemi.dims.stride() == hemi_dims + 4);
    CHECK(hemi.dims.dim(D::hemisphere_direction, 0, 1) == DimensionLayout::kFirstVertex + 2);
    CHECK(hemi.dims.dim(D::roulette, 0) == DimensionLayout::kFirstVertex + hemi_dims + 3);
    CHECK_FALSE(hemi.dims.declared(D::light_point));
}

TEST_CASE("vertex draws: a plan holds the planned draws, each in its form", "[sampler][quick]") {
    using D = VertexDraw;
    DimensionLayout dims;
    dims.repeat(2, {{D::light_fill, false}, {D::light_point}});
    dims.add({D::bsdf_direction, true, true});
    dims.add({D::bsdf_lobe, false});
    dims.add({D::roulette, false});
    CHECK(dims.stride() == 10);
    std::vector<PlannedDraw> plan;
    dims.plan(1, plan);
    const std::uint32_t v = dims.vertex(1);
    // The unplanned fills, lobe and roulette keep their dimensions but are not in the plan.
    REQUIRE(plan.size() == 3);
    CHECK(plan[0].dim == v + 1);
    CHECK((plan[0].two_d && plan[0].bits && !plan[0].cosine));
    CHECK(plan[1].dim == v + 4);
    CHECK((plan[1].two_d && plan[1].bits && !plan[1].cosine));
    CHECK(plan[2].dim == v + 6);
    CHECK((plan[2].two_d && !plan[2].bits && plan[2].cosine));
}
