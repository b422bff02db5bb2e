#pragma once
// The geometric cases of the numerical-stability stress suite (docs/numerics.md): watertightness
// of closed meshes near and far from the origin, grazing and degenerate rays and triangles,
// and self-intersection / light leaking across scales, each run with every backend and
// triangle test and judged against the exact geometry or a double-precision ground truth.
#include "candela/numerics/stress.h"

#include <string>
#include <vector>

namespace candela {
class Scene;
struct Mesh;
} // namespace candela

namespace candela::numerics {

/// Where the shared CS184 scenes are, relative to the project root (the report tool's working
/// directory); tests pass their own absolute location.
constexpr const char* kDefaultSharedScenes = "../shared/scenes/cs184";

/// Watertightness (group "watertightness"): rays from outside aimed exactly at shared edges and
/// vertices of closed meshes (UV sphere, grid cube, the same sphere with unwelded vertices, and
/// the closed part of CBbunny when `shared_scenes` holds it), and rays from the inside through
/// the same points, at translations 0, 1e3, 1e5, 1e6. A ray leaks when it misses the closed
/// surface or first hits it beyond the aimed point. Rows per mesh x translation x backend.
std::vector<StressResult>
run_watertight_cases(StressSize size, const std::string& shared_scenes = kDefaultSharedScenes);

/// The procedural meshes of run_watertight_cases (sphere, unwelded sphere, cube, 4
/// translations).
std::vector<StressResult> run_watertight_procedural(StressSize size);
/// The CBbunny part of run_watertight_cases: its open-edge count, then edge/vertex rays at its
/// closed neighbourhoods. One reported row saying so when the scene file is absent.
std::vector<StressResult>
run_watertight_bunny(StressSize size, const std::string& shared_scenes = kDefaultSharedScenes);
/// The same for the largest mesh of any scene file (`label` names it in the rows): its
/// open-edge count, then edge/vertex rays at its closed neighbourhoods.
std::vector<StressResult> run_watertight_scene_mesh(StressSize size, const std::string& path,
                                                    const std::string& label);

/// Grazing and degenerate configurations (group "grazing and degenerate"): rays in a
/// triangle's plane, rays starting exactly on a surface, zero-area and needle triangles, and
/// one scene holding triangles from 1e-6 to 1e6 in size, judged against the exact answer or
/// the double-precision brute force.
std::vector<StressResult> run_degenerate_cases(StressSize size);

/// Self-intersection and leaking at the ray level (group "self-intersection and leaks"): the
/// wall scene of make_wall_scene() scaled 1e-4..1e4 and translated 1e3..1e6; floor points on
/// the lit side whose shadow rays are blocked or whose bounce rays re-hit the floor (acne), and
/// points on the wall's dark face whose shadow rays reach the light (leaks), for the robust
/// offset as the renderer uses it, the robust offset with the light point's error bound, a
/// fixed 1e-4 offset and no offset.
std::vector<StressResult> run_self_intersection_cases(StressSize size);

/// The same scene rendered with the path integrator (group "scale invariance of renders"): the
/// image mean at every scale and translation compared with the unit-scale render near the
/// origin by a z-test, and non-finite samples counted.
std::vector<StressResult> run_scale_render_cases(StressSize size);

/// All of the above, in that order.
std::vector<StressResult>
run_geometry_cases(StressSize size, const std::string& shared_scenes = kDefaultSharedScenes);

// ---- building blocks, exposed for the tests --------------------------------------------------

/// Number of edges of `m` (edges identified by the exact bits of their end positions, so
/// unwelded duplicates count as one) not shared by exactly two triangles: 0 for a closed
/// manifold mesh.
std::size_t count_open_edges(const Mesh& m);

/// A copy of `m` in which every triangle has its own three vertices (positions bit-identical to
/// the shared ones): the same closed surface with duplicated vertices.
Mesh unweld_mesh(const Mesh& m);

/// The test scene of the self-intersection cases, in local units: a 3 x 3 floor (y = 0), a
/// closed wall 0.1 thick and 0.5 high across it at x = 0, a 0.3 x 0.3 rect light facing down
/// at height 0.3 over the +x side, a camera on the -x side that sees the wall's dark face, the
/// dark floor and, over the wall, the lit floor. The world scene is T (1,1,1) + s R p for a
/// fixed rotation R (so that no surface is axis-aligned): scale `s`, translation `t`; camera
/// and light are transformed with it, so the image is the same at every s and t.
Scene make_wall_scene(float s, float t);

} // namespace candela::numerics
