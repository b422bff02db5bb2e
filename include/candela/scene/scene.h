#pragma once
// The immutable, flattened, world-space scene that accelerators and integrators read.
// Built once by scene/builder.h from a SceneDesc; passed around as `const Scene&`.
#include "candela/math/bbox.h"
#include "candela/math/mat3.h"
#include "candela/scene/camera.h"
#include "candela/scene/light.h"
#include "candela/scene/material.h"

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace candela {

class EnvMap; // candela/scene/envmap.h

/// Vertex positions of a mesh, followed in memory by one spare Vec3 that is part of the storage's
/// *size*, not only of its capacity. Embree (shared vertex buffers) and the BVH's SSE kernels
/// load 16 bytes at a vertex, 4 bytes past the last one's end; the spare makes those loads read
/// owned memory. Because the spare is an element of the underlying vector, every copy, move and
/// assignment keeps it (a capacity reserved by hand is lost by a copy), and there is no way to
/// make positions without it: size(), operator[], begin()/end() see the real vertices only,
/// while data() points at size() + 1 Vec3s. Readers index it like a std::vector<Vec3> (zero
/// copy: Embree shares data()); the spare is always Vec3(0).
class PaddedPositions {
  public:
    using value_type = Vec3;
    using iterator = Vec3*;
    using const_iterator = const Vec3*;

    PaddedPositions() : v_(1, Vec3(0.f)) {}
    PaddedPositions(std::initializer_list<Vec3> init) { assign(init.begin(), init.end()); }
    explicit PaddedPositions(const std::vector<Vec3>& p) { assign(p.begin(), p.end()); }
    PaddedPositions& operator=(std::initializer_list<Vec3> init) {
        assign(init.begin(), init.end());
        return *this;
    }

    template <class It> void assign(It first, It last) {
        v_.assign(first, last);
        v_.push_back(Vec3(0.f));
    }

    std::size_t size() const { return v_.size() - 1; }
    bool empty() const { return v_.size() == 1; }
    /// size() + 1: the Vec3s that data() may be read at (the last is the spare).
    std::size_t padded_size() const { return v_.size(); }
    void reserve(std::size_t n) { v_.reserve(n + 1); }
    void resize(std::size_t n) {
        v_.back() = Vec3(0.f);
        v_.resize(n + 1, Vec3(0.f));
    }
    void clear() { v_.assign(1, Vec3(0.f)); }
    void push_back(const Vec3& p) {
        v_.back() = p; // the spare becomes the new vertex (p is copied before any reallocation)
        v_.push_back(Vec3(0.f));
    }

    Vec3& operator[](std::size_t i) { return v_[i]; }
    const Vec3& operator[](std::size_t i) const { return v_[i]; }
    Vec3& back() { return v_[v_.size() - 2]; }
    const Vec3& back() const { return v_[v_.size() - 2]; }
    Vec3* data() { return v_.data(); }
    const Vec3* data() const { return v_.data(); }
    iterator begin() { return v_.data(); }
    iterator end() { return v_.data() + size(); }
    const_iterator begin() const { return v_.data(); }
    const_iterator end() const { return v_.data() + size(); }

    bool operator==(const PaddedPositions& o) const { return v_ == o.v_; }
    bool operator!=(const PaddedPositions& o) const { return !(*this == o); }

  private:
    std::vector<Vec3> v_; ///< the positions, then the spare; never empty
};

/// A triangle mesh in world space. Vertex `i` has position positions[i] and unit shading normal
/// normals[i] (or no normals: then the geometric normal shades); triangle `j` is (indices[3j],
/// indices[3j+1], indices[3j+2]), counter-clockwise about its geometric normal. `positions`
/// always carries the spare Vec3 Embree needs after the last vertex (PaddedPositions).
struct Mesh {
    std::string name;
    PaddedPositions positions;
    std::vector<Vec3> normals;
    std::vector<std::uint32_t> indices;
    std::uint32_t material = 0;
    std::int32_t light = -1; ///< index into Scene::lights when the material is emissive

    std::size_t triangle_count() const { return indices.size() / 3; }
};

/// A sphere |p - center| = radius, or an ellipsoid: the image of the unit sphere under
/// p = center + to_world * x (a sphere under a node transform that is not a similarity). Scenes
/// and tests build true spheres as `Sphere{center, radius}`; ellipsoids come from
/// make_ellipsoid(), which fills every field below consistently.
struct Sphere {
    Vec3 center;
    float radius = 1.f; ///< sphere radius; 1 for an ellipsoid (the size is in to_world)
    std::uint32_t material = 0;
    std::int32_t light = -1;
    bool ellipsoid = false; ///< when false, the fields below are unused (identity)
    /// Ellipsoid: the linear map from the unit sphere to world space (radius folded in) and
    /// its inverse, both rounded to float from a double inversion. The surface every backend
    /// intersects is {p : |to_object (p - center)| = 1}.
    Mat3 to_world{}, to_object{};
    /// Ellipsoid: max of the 1- and inf-norms of |to_object| |to_world| (>= its 2-norm, >= 1),
    /// the amplification of relative rounding
    /// errors by the map and its inverse (1 for an axis-aligned ellipsoid, at most 3 under a
    /// rotation, about the condition number of to_world under shear); scales the rounding-error
    /// bounds of points computed through them.
    float map_error = 1.f;

    bool is_ellipsoid() const { return ellipsoid; }
    /// Exact axis-aligned bounds (before rounding): centre +- radius, or for an ellipsoid
    /// centre +- |row i of to_world| on axis i.
    Bounds3 bounds() const;
};

/// Relative tolerance below which a linear map counts as a similarity (orthogonal columns of
/// equal length): a shape error of 1e-5 of the radius is below a pixel of any image candela
/// renders, and matrices written with 7 significant digits (COLLADA <matrix>) stay spheres.
constexpr double kSimilarityRelTol = 1e-5;

/// True when the linear map L is a similarity within kSimilarityRelTol (|c_i . c_j| <=
/// tol |c_i| |c_j| for i != j and column lengths within tol of their mean); then *scale is the
/// mean column length. False for singular or non-finite maps.
bool is_similarity(const Mat3d& L, double* scale);

/// The ellipsoid center + L * (unit sphere). L must be invertible and finite (the builder
/// checks); the inverse is computed in double and both maps are rounded to float.
Sphere make_ellipsoid(const Vec3& center, const Mat3d& L, std::uint32_t material = 0);

/// Surface area of a sphere or ellipsoid, in double: 4 pi r^2, or for an ellipsoid the
/// integral over the unit sphere of |det A| |A^-T n| (Nanson's formula), by a product
/// Gauss-Legendre x trapezoid rule accurate to ~1e-9 relative for axis ratios up to 1e3.
double sphere_area(const Sphere& s);

/// What a scene holds, so that a render pays only for what is used (`candela info`).
struct SceneFeatures {
    std::uint32_t bsdf_mask = 0;  ///< bit k set when BsdfKind(k) is used by some primitive
    std::uint32_t light_mask = 0; ///< bit k set when LightKind(k) occurs in Scene::lights
    bool has(BsdfKind k) const { return bsdf_mask & (1u << static_cast<int>(k)); }
    bool has(LightKind k) const { return light_mask & (1u << static_cast<int>(k)); }
};

class Scene {
  public:
    std::string source; ///< the scene file it was built from
    std::vector<Mesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::shared_ptr<const EnvMap> env; ///< set when an Environment light exists
    Camera camera;
    /// Where the scene file's own camera stands when the framed camera (--camera framed)
    /// replaced it: a camera enclosed by geometry there means the framed one is outside a
    /// closed room (enclosed_point()).
    std::optional<Vec3> file_camera_pos;
    Bounds3 bounds; ///< all meshes and spheres (lights excluded)
    SceneFeatures features;

    /// Geometry ids in hits: meshes are 0 .. meshes.size()-1; all spheres together form the one
    /// geometry sphere_geom_id(), with primitive id = index into `spheres`.
    std::uint32_t sphere_geom_id() const { return static_cast<std::uint32_t>(meshes.size()); }
    std::size_t triangle_count() const {
        std::size_t n = 0;
        for (const auto& m : meshes)
            n += m.triangle_count();
        return n;
    }
    /// Recomputes `bounds` and `features` from the contents. SceneEditor::finalize() calls it
    /// after checking the scene's invariants (scene_editor.h); build scenes through it.
    void finalize();
};

} // namespace candela
