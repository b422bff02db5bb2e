#pragma once
// Procedural scenes for tests and benchmarks, built without any file.
#include "candela/scene/scene.h"

#include <cstdint>
#include <string>

namespace candela {

/// Builds a finalized scene from a spec "<kind>:<N>[:<seed>]":
///  - `sphere:N`  closed UV-tessellated unit sphere at the origin with about N triangles
///                (shared vertices, smooth normals);
///  - `cube:N`    closed cube [-1,1]^3, each face a grid, about N triangles, welded vertices;
///  - `soup:N`    N random triangles in [-1,1]^3 (fixed seed unless given);
///  - `spheres:N` N random analytic spheres in [-1,1]^3.
/// Every scene has one diffuse material, a camera on +z looking at the origin (hfov 50) and a
/// point light. `box:<kind>:<N>[:<seed>]` puts the same content inside the five walls of an
/// open box [-2, 2]^3 (open towards the camera) lit by a rectangular ceiling light instead of
/// the point light: a scene where paths bounce, for render benchmarks. Throws Error(Usage) for an
/// unknown kind or a bad count. `nearwall:N[:seed]` and `inpanel:N[:seed]` are the many-light
/// scenes below.
Scene make_procedural_scene(const std::string& spec);

/// A wall lit by one point light of intensity 4.4 standing 0.95 m in front of it, among
/// `count` other lights (points, spots, rectangles, emissive spheres, cycled in that order) of
/// intensity log-uniform over [0.01, 10] (or the power of one) scattered through
/// [-12, 12]^3 at least 3 m from it, on both sides of the wall: the near light is a small share
/// of the power but most of the light on the wall around it, which lies inside the bounds of
/// most groups of lights. The 8 x 8 m wall (albedo 0.7, the plane z = 0, facing +z) is seen
/// from z = 6. Finalized.
Scene make_near_wall_scene(std::size_t count, std::uint64_t seed);

/// A 6 x 6 m dim rectangle light (radiance 0.05) facing down 2.5 m over a floor, with `count`
/// lights (points, spots, small rectangles facing down, emissive spheres) of intensity
/// log-uniform over [0.01, 3] (or the power of one) beneath it, inside its bounds: every
/// shading point under the panel is inside the panel's bounding sphere. Seen from the side.
/// Finalized.
Scene make_panel_lights_scene(std::size_t count, std::uint64_t seed);

/// Appends a closed UV sphere (`rings` latitude bands, 2*rings segments, 4*rings*(rings-1)
/// triangles) of radius r about c to `scene` as a new mesh with material 0.
void add_uv_sphere_mesh(Scene& scene, const Vec3& c, float r, int rings);
/// Appends a closed icosphere of radius r about c as a new mesh with material 0: the regular
/// icosahedron with every face split `subdivisions` times into four (20 * 4^subdivisions
/// triangles; 1 gives 80), new vertices pushed out onto the sphere, and smooth normals (each
/// vertex's radial direction). A convex mesh whose shading normals differ from its faces' by up
/// to the angle of a face corner.
void add_icosphere_mesh(Scene& scene, const Vec3& c, float r, int subdivisions);
/// Appends a closed cube [lo, hi] with an n x n grid per face (12 n^2 triangles) as a new mesh.
void add_grid_cube_mesh(Scene& scene, const Vec3& lo, const Vec3& hi, int n);
/// Appends a one-sided rectangular luminaire (CGL <area> semantics: centre, edge vectors dx and
/// dy, emitting side cross(dx, dy), radiance L) as an Area light plus the emissive two-triangle
/// mesh that makes it visible to rays, with its own emission material. Returns the light index.
std::uint32_t add_rect_light(Scene& scene, const Vec3& center, const Vec3& dx, const Vec3& dy,
                             const Rgb& L);
/// Appends `count` random triangles in [-1,1]^3 as a new mesh (seeded).
void add_triangle_soup(Scene& scene, std::size_t count, std::uint64_t seed);
/// Appends the square of side 2*half in the plane y = height, normal +y, as a two-triangle
/// mesh named "floor" with material `mat` (a light record too if `mat` emits).
void add_floor(Scene& scene, float half, float height, std::uint32_t mat);

/// The furnace: a camera inside a closed unit sphere at the origin of diffuse albedo `albedo`
/// that also glows with radiance Le (a Sphere light). Every point sees radiance
/// Le / (1 - albedo). Finalized.
Scene make_furnace_scene(float albedo, float Le);

/// A closed 4 x 3 x 4 room ([-2, 2] x [0, 3] x [-2, 2]: flat walls, floor and ceiling of
/// diffuse albedo 0.7 without vertex normals, seen from inside) lit by a point light of
/// intensity 10 at (0.3, 2.6, -0.4), under its ceiling. With `sun`, a sun of irradiance 1
/// shines on a ground square `ground_width` wide under the room: no light of it reaches inside,
/// so the room renders the same either way, however wide the ground. Finalized.
Scene make_sunlit_room_scene(float ground_width, bool sun);

} // namespace candela
