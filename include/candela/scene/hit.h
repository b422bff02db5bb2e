#pragma once
#include <cstdint>

namespace candela {

/// The result of a closest-hit query, identical for every accelerator. Barycentrics follow
/// Embree's convention: the hit point is (1-u-v) p0 + u p1 + v p2 of triangle prim_id in mesh
/// geom_id. For spheres (geom_id == Scene::sphere_geom_id()) u and v are 0 and prim_id is the
/// sphere's index. Turn a Hit into shading data with make_interaction() (scene/interaction.h).
struct Hit {
    float t = 0.f;
    float u = 0.f, v = 0.f;
    std::uint32_t geom_id = 0;
    std::uint32_t prim_id = 0;
};

} // namespace candela
