// SceneDesc -> Scene: world-space meshes and spheres, materials, lights (spec §2 with the §11
// decisions), the luminaire rule (§11.3) and camera framing (§3.1, §11.1-2).
#include "candela/scene/builder.h"

#include "candela/math/constants.h"

#include "candela/scene/scene_desc.h"
#include "candela/scene/scene_editor.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <unordered_map>

namespace candela {

namespace {

/// An emissive mesh is a stand-in for a CGL area light when all its vertices lie within this
/// distance of the light's plane, relative to the rectangle's size (|dx| + |dy|). Course files
/// place both at the same height to within float rounding (~1e-7 relative); 1e-3 also absorbs
/// exporters that write the panel a hair away from the light.
constexpr double kStandInPlaneRelTol = 1e-3;
/// The course framing rule nudges φ off the pole when sin φ = 0 (spec §3.1, EPS_F).
constexpr double kPoleNudge = 1e-5;
/// A group's vertices are renumbered through a dense table over the mesh's positions unless the
/// mesh has more than this many positions per corner of the group; then a hash map is used, so
/// that the cost follows the group's size (either way the vertex order is first use).
constexpr std::size_t kDenseRemapFactor = 8;
/// Below this relative length, cross(world up, view) is treated as zero (camera looking straight
/// up or down); the camera's x axis then falls back to world +X.
constexpr double kParallelRelTol = 1e-9;
/// Largest Sphere::map_error accepted for an ellipsoid. Rounding errors through its maps grow
/// with it (interaction.cpp derives the bound); at 1e4 they reach ~1e-3 of the size, beyond
/// which a float ellipsoid cannot be rendered faithfully (a rotated axis ratio or a shear of
/// ~1e4; axis-aligned ellipsoids have map_error 1 at any axis ratio).
constexpr float kMaxEllipsoidMapError = 1e4f;

Vec3 to_f(const Vec3d& v) {
    return Vec3(v);
}
Vec3d to_d(const Vec3& v) {
    return Vec3d(v);
}

/// xyz(W·(x,y,z,1)) without the division by w (the spec's W(x,y,z)).
Vec3d affine_point(const Mat4& W, const Vec3d& p) {
    return Vec3d(W.m[0][0] * p.x + W.m[0][1] * p.y + W.m[0][2] * p.z + W.m[0][3],
                 W.m[1][0] * p.x + W.m[1][1] * p.y + W.m[1][2] * p.z + W.m[1][3],
                 W.m[2][0] * p.x + W.m[2][1] * p.y + W.m[2][2] * p.z + W.m[2][3]);
}

/// A camera's axes: x right, y up, z back toward the viewer.
struct Basis {
    Vec3d x, y, z;
};

/// The axes of a camera looking along -view with zero roll about world +Y (spec §3.1 step 5);
/// nullopt when view is (nearly) parallel to +Y and no roll is defined.
std::optional<Basis> level_basis(const Vec3d& view) {
    const Vec3d x = cross(Vec3d(0, 1, 0), view);
    if (!(length(x) > kParallelRelTol * length(view))) return std::nullopt;
    const Vec3d unit_x = normalize(x);
    return Basis{unit_x, normalize(cross(view, unit_x)), normalize(view)};
}

class Builder {
  public:
    Builder(const SceneDesc& desc, const BuildOptions& opt, Diagnostics& diag)
        : d_(desc), opt_(opt), diag_(diag), mat_map_(desc.materials.size(), -1) {}

    Scene run() {
        s_.source = d_.source;
        check_triangle_budget();
        const DescInstance* cam = nullptr;
        for (const DescInstance& inst : d_.instances) {
            switch (inst.kind) {
            case DescInstanceKind::Geometry:
                add_geometry(inst);
                break;
            case DescInstanceKind::Light:
                add_light(inst);
                break;
            case DescInstanceKind::Camera:
                cam = &inst;
                break; // the last camera wins
            }
        }
        // Framing bounds: every file mesh (stand-ins included, as in the course) and sphere.
        Bounds3 geometry_bounds = bounds_of_geometry();
        drop_stand_ins();
        add_primitives();
        add_environment();
        place_camera(cam, geometry_bounds);
        editor_.finalize();
        return std::move(s_);
    }

  private:
    const SceneDesc& d_;
    const BuildOptions& opt_;
    Diagnostics& diag_;
    /// The result, appended to only through editor_; the file's lights go in as they come, its
    /// meshes, spheres and materials once the stand-ins are gone (add_primitives).
    Scene s_;
    SceneEditor editor_{s_};
    std::vector<Material> materials_; ///< every material referenced, in order of first reference
    std::vector<Mesh> meshes_;        ///< world-space meshes, material indices into materials_
    std::vector<Sphere> spheres_;     ///< likewise
    std::vector<int> mat_map_;
    int default_mat_ = -1;
    bool attenuation_noted_ = false;
    struct RectInfo {
        std::size_t light;
        std::string name;
        int line;
    };
    std::vector<RectInfo> rects_;
    std::vector<int> mesh_lines_;

    [[noreturn]] void fail(int line, const std::string& what) const {
        throw Error(ErrorKind::Scene, SourceLoc{d_.source, line}, what);
    }
    SourceLoc where(int line) const { return SourceLoc{d_.source, line}; }

    std::uint32_t material(int desc_index) {
        if (desc_index < 0) {
            if (default_mat_ < 0) {
                default_mat_ = static_cast<int>(materials_.size());
                Material m;
                m.name = "default";
                materials_.push_back(m); // Diffuse 0.5 (spec §1.7.5)
            }
            return static_cast<std::uint32_t>(default_mat_);
        }
        int& mapped = mat_map_[static_cast<std::size_t>(desc_index)];
        if (mapped < 0) {
            mapped = static_cast<int>(materials_.size());
            materials_.push_back(d_.materials[static_cast<std::size_t>(desc_index)].material);
        }
        return static_cast<std::uint32_t>(mapped);
    }

    // ---- geometry ----------------------------------------------------------------------------

    /// Every instance copies its mesh into world space: refuses a scene whose instanced
    /// triangle total exceeds loader_limits::kMaxTriangles before anything is built.
    void check_triangle_budget() const {
        std::vector<std::uint64_t> per_geometry(d_.geometries.size());
        for (std::size_t i = 0; i < d_.geometries.size(); ++i)
            per_geometry[i] = d_.geometries[i].triangle_count();
        std::uint64_t total = 0;
        for (const DescInstance& inst : d_.instances) {
            if (inst.kind != DescInstanceKind::Geometry) continue;
            total += per_geometry[static_cast<std::size_t>(inst.index)];
            if (total > loader_limits::kMaxTriangles)
                fail(inst.line,
                     "instancing makes more than " + std::to_string(loader_limits::kMaxTriangles) +
                         " triangles (the loader's limit); this instance of '" +
                         d_.geometries[static_cast<std::size_t>(inst.index)].name + "' crosses it");
        }
    }

    void add_geometry(const DescInstance& inst) {
        const DescGeometry& g = d_.geometries[static_cast<std::size_t>(inst.index)];
        const Mat4& W = inst.world;
        if (g.kind == DescGeometryKind::Sphere) {
            // The world surface is centre + L (unit sphere), L = radius x the linear part of W.
            // A similarity keeps it a sphere (the fast path every backend has); anything else
            // (non-uniform scale, shear) is an ellipsoid.
            const Vec3 center = to_f(W.point(Vec3d(0.0)));
            const Mat3d L = Mat3d::from_columns(W.column(0) * g.radius, W.column(1) * g.radius,
                                                W.column(2) * g.radius);
            const std::string what = "sphere of node '" + inst.node_name + "'";
            if (!is_finite(center)) fail(inst.line, what + " has a non-finite world centre");
            double scale = 0.0;
            Sphere sp;
            if (is_similarity(L, &scale)) {
                sp.center = center;
                sp.radius = static_cast<float>(scale);
                if (!(sp.radius > 0.f) || !std::isfinite(sp.radius))
                    fail(inst.line, what + " has a zero or non-finite world radius");
            } else {
                const double det = L.det();
                // A map that flattens the sphere to float resolution has no usable inverse.
                if (!(std::abs(det) > 0.0) || !std::isfinite(det) || !L.is_finite())
                    fail(inst.line, what + " has a singular or non-finite transform");
                sp = make_ellipsoid(center, L);
                if (!sp.to_world.is_finite() || !sp.to_object.is_finite() ||
                    !(std::abs(sp.to_world.det()) > 0.f) || !std::isfinite(sp.map_error) ||
                    sp.map_error > kMaxEllipsoidMapError)
                    fail(inst.line, what + " is too thin or sheared for float precision (its "
                                           "transform is nearly singular)");
            }
            sp.material = material(inst.material);
            spheres_.push_back(sp);
            return;
        }
        const double det = W.det3();
        if (det == 0.0 || !std::isfinite(det))
            fail(inst.line, "node '" + inst.node_name + "' has a singular transform");
        for (std::size_t gi = 0; gi < g.groups.size(); ++gi) {
            const DescPrimGroup& grp = g.groups[gi];
            if (grp.triangle_count() == 0) continue;
            Mesh m;
            m.name =
                g.groups.size() > 1 ? inst.node_name + "#" + std::to_string(gi) : inst.node_name;
            m.material =
                material(inst.group_materials.empty() ? inst.material : inst.group_materials[gi]);
            build_mesh(g, grp, W, det < 0.0, m);
            meshes_.push_back(std::move(m));
            mesh_lines_.push_back(inst.line);
        }
    }

    /// World-space vertices of one group. With file normals, a vertex is a unique
    /// (position, normal) pair; without, one vertex per referenced position.
    void build_mesh(const DescGeometry& g, const DescPrimGroup& grp, const Mat4& W, bool mirror,
                    Mesh& m) {
        const std::size_t nc = grp.position_index.size();
        m.indices.resize(nc);
        const bool file_normals = !grp.normal_index.empty();
        bool need_smooth = !file_normals;
        if (!file_normals && g.positions.size() > kDenseRemapFactor * nc) {
            // A small group of a large mesh: a table over every position would make the
            // build cost groups x positions (quadratic for a mesh split into many groups).
            std::unordered_map<std::uint32_t, std::uint32_t> remap;
            remap.reserve(nc);
            for (std::size_t c = 0; c < nc; ++c) {
                std::uint32_t pi = grp.position_index[c];
                auto [it, fresh] =
                    remap.emplace(pi, static_cast<std::uint32_t>(m.positions.size()));
                if (fresh) m.positions.push_back(to_f(W.point(to_d(g.positions[pi]))));
                m.indices[c] = it->second;
            }
        } else if (!file_normals) {
            std::vector<std::uint32_t> remap(g.positions.size(),
                                             std::numeric_limits<std::uint32_t>::max());
            for (std::size_t c = 0; c < nc; ++c) {
                std::uint32_t pi = grp.position_index[c];
                if (remap[pi] == std::numeric_limits<std::uint32_t>::max()) {
                    remap[pi] = static_cast<std::uint32_t>(m.positions.size());
                    m.positions.push_back(to_f(W.point(to_d(g.positions[pi]))));
                }
                m.indices[c] = remap[pi];
            }
        } else {
            std::unordered_map<std::uint64_t, std::uint32_t> remap;
            remap.reserve(nc);
            for (std::size_t c = 0; c < nc; ++c) {
                std::uint32_t pi = grp.position_index[c], ni = grp.normal_index[c];
                std::uint64_t key = (std::uint64_t(pi) << 32) | ni;
                auto [it, fresh] =
                    remap.emplace(key, static_cast<std::uint32_t>(m.positions.size()));
                if (fresh) {
                    m.positions.push_back(to_f(W.point(to_d(g.positions[pi]))));
                    Vec3d n = W.normal(to_d(g.normals[ni]));
                    double ln = length(n);
                    if (ln > 0.0 && std::isfinite(ln)) {
                        m.normals.push_back(to_f(n / ln));
                    } else {
                        m.normals.push_back(Vec3(0.f)); // replaced by the smooth normal below
                        need_smooth = true;
                    }
                }
                m.indices[c] = it->second;
            }
        }
        // A mirroring W reverses the winding; swap two corners so that the geometric normal
        // stays the transformed local one.
        if (mirror)
            for (std::size_t c = 0; c < nc; c += 3)
                std::swap(m.indices[c + 1], m.indices[c + 2]);
        for (const Vec3& p : m.positions)
            if (!is_finite(p))
                fail(grp.line, "mesh '" + m.name + "' has non-finite world positions");
        if (need_smooth) smooth_normals(m, file_normals);
    }

    /// Area-weighted vertex normals (sum of unnormalised face normals). When `only_missing`,
    /// only zero normals are replaced.
    static void smooth_normals(Mesh& m, bool only_missing) {
        std::vector<Vec3d> acc(m.positions.size(), Vec3d(0.0));
        std::vector<Vec3d> any_face(m.positions.size(), Vec3d(0.0));
        for (std::size_t t = 0; t < m.indices.size(); t += 3) {
            const std::uint32_t* v = &m.indices[t];
            Vec3d p0 = to_d(m.positions[v[0]]);
            Vec3d fn = cross(to_d(m.positions[v[1]]) - p0, to_d(m.positions[v[2]]) - p0);
            for (int k = 0; k < 3; ++k) {
                acc[v[k]] += fn;
                if (length_squared(fn) > 0.0) any_face[v[k]] = fn;
            }
        }
        m.normals.resize(m.positions.size(), Vec3(0.f));
        for (std::size_t i = 0; i < acc.size(); ++i) {
            if (only_missing && m.normals[i] != Vec3(0.f)) continue;
            Vec3d n = length_squared(acc[i]) > 0.0 ? acc[i] : any_face[i];
            // Every vertex belongs to a non-degenerate triangle (the loader dropped the rest);
            // +Y is a last resort for faces that became degenerate in float.
            m.normals[i] = length_squared(n) > 0.0 ? to_f(normalize(n)) : Vec3(0.f, 1.f, 0.f);
        }
    }

    // ---- lights ------------------------------------------------------------------------------

    Vec3 unit(const Vec3d& v, int line, const std::string& what) const {
        double l = length(v);
        if (!(l > 0.0) || !std::isfinite(l)) fail(line, what + " has a degenerate transform");
        return to_f(v / l);
    }

    void add_light(const DescInstance& inst) {
        const DescLight& dl = d_.lights[static_cast<std::size_t>(inst.index)];
        const Mat4& W = inst.world;
        const std::string what = "light '" + dl.name + "' (node '" + inst.node_name + "')";
        if (is_black(dl.color)) {
            // A light that emits nothing would cost sampling work (and, for an ambient light,
            // an escape lookup per ray) for no contribution.
            diag_.note(where(inst.line), what + " emits nothing and is left out");
            return;
        }
        Light l;
        l.L = dl.color;
        switch (dl.kind) {
        case DescLightKind::Area: {
            l.kind = LightKind::Area;
            l.p = to_f(W.point(Vec3d(0.0)));
            // The emitting side is the image of the local half-space z < 0: its normal
            // transforms as a normal (inverse transpose), which stays perpendicular to the
            // rectangle under shears and non-uniform scales, and on the right side under mirrors.
            l.n = unit(W.normal(Vec3d(0, 0, -1)), inst.line, what);
            Vec3d dx = W.vector(Vec3d(1, 0, 0)), dy = W.vector(Vec3d(0, 1, 0));
            l.dx = to_f(dx);
            l.dy = to_f(dy);
            l.area = static_cast<float>(length(cross(dx, dy)));
            if (!(l.area > 0.f)) fail(inst.line, what + " has zero area");
            rects_.push_back({s_.lights.size(), dl.name, inst.line}); // its index, added below
            break;
        }
        case DescLightKind::Point:
            l.kind = LightKind::Point;
            l.p = to_f(W.point(Vec3d(0.0)));
            break;
        case DescLightKind::Spot:
            l.kind = LightKind::Spot;
            l.p = to_f(W.point(Vec3d(0.0)));
            l.n = unit(W.vector(Vec3d(0, 0, -1)), inst.line, what);
            l.cos_total = static_cast<float>(std::cos(deg_to_rad(0.5 * dl.falloff_angle_deg)));
            l.falloff_exp = dl.falloff_exponent;
            break;
        case DescLightKind::Directional:
            l.kind = LightKind::Directional;
            l.n = unit(W.vector(Vec3d(0, 0, 1)), inst.line, what); // toward the light
            break;
        case DescLightKind::Ambient:
            l.kind = LightKind::Ambient;
            break;
        }
        if (!is_finite(l.p)) fail(inst.line, what + " has a non-finite position");
        if (dl.has_attenuation && !attenuation_noted_ &&
            (l.kind == LightKind::Point || l.kind == LightKind::Spot)) {
            attenuation_noted_ = true;
            diag_.note(where(inst.line), "COLLADA attenuation of " + what +
                                             " is ignored: point and spot lights fall off "
                                             "with the inverse square of distance");
        }
        editor_.add_light(std::move(l));
    }

    /// Spec §11.3: does emissive mesh `m` lie in the plane of rect light `r` and overlap it?
    static bool is_stand_in(const Mesh& m, const Light& r) {
        Vec3d p = to_d(r.p), n = to_d(r.n), dx = to_d(r.dx), dy = to_d(r.dy);
        double tol = kStandInPlaneRelTol * (length(dx) + length(dy));
        double a = dot(dx, dx), b = dot(dx, dy), c = dot(dy, dy), det = a * c - b * b;
        double smin = std::numeric_limits<double>::infinity(), smax = -smin, tmin = smin,
               tmax = -smin;
        for (const Vec3& q : m.positions) {
            Vec3d v = to_d(q) - p;
            if (std::abs(dot(v, n)) > tol) return false;
            double vx = dot(v, dx), vy = dot(v, dy);
            double s = (c * vx - b * vy) / det, t = (a * vy - b * vx) / det; // v = s dx + t dy
            smin = std::min(smin, s);
            smax = std::max(smax, s);
            tmin = std::min(tmin, t);
            tmax = std::max(tmax, t);
        }
        // The mesh's extent in rectangle coordinates overlaps [-1/2, 1/2]² with positive area.
        return smin < 0.5 && smax > -0.5 && tmin < 0.5 && tmax > -0.5;
    }

    void drop_stand_ins() {
        if (rects_.empty()) return;
        std::vector<Mesh> kept;
        std::vector<int> kept_lines;
        for (std::size_t i = 0; i < meshes_.size(); ++i) {
            Mesh& m = meshes_[i];
            const RectInfo* standin_of = nullptr;
            if (materials_[m.material].is_emissive())
                for (const RectInfo& r : rects_)
                    if (is_stand_in(m, s_.lights[r.light])) {
                        standin_of = &r;
                        break;
                    }
            if (standin_of) {
                diag_.note(where(mesh_lines_[i]),
                           "emissive mesh '" + m.name +
                               "' is the visible stand-in of area light '" + standin_of->name +
                               "' and is dropped; the area light is visible itself");
                continue;
            }
            kept.push_back(std::move(m));
            kept_lines.push_back(mesh_lines_[i]);
        }
        meshes_ = std::move(kept);
        mesh_lines_ = std::move(kept_lines);
    }

    Bounds3 bounds_of_geometry() const {
        Bounds3 b;
        for (const Mesh& m : meshes_)
            for (const Vec3& p : m.positions)
                b.grow(p);
        for (const Sphere& sp : spheres_)
            b.grow(sp.bounds());
        return b;
    }

    /// Moves the file's meshes and spheres into the scene, each emissive one with its light
    /// record (after the file's lights), and makes each CGL area light visible to rays as a
    /// two-triangle emissive panel after the file's meshes. Only the materials some primitive uses
    /// go in (stand-ins may have been dropped), in order of first use by meshes, panels, spheres.
    void add_primitives() {
        std::vector<int> remap(materials_.size(), -1);
        auto map = [&](std::uint32_t& idx) {
            if (remap[idx] < 0)
                remap[idx] = static_cast<int>(editor_.add_material(materials_[idx]));
            idx = static_cast<std::uint32_t>(remap[idx]);
        };
        for (Mesh& m : meshes_) {
            map(m.material);
            editor_.add_mesh(std::move(m));
        }
        for (const RectInfo& r : rects_)
            editor_.add_rect_panel(static_cast<std::uint32_t>(r.light), r.name);
        for (Sphere& sp : spheres_) {
            map(sp.material);
            editor_.add_sphere(sp);
        }
        meshes_.clear();
        spheres_.clear();
    }

    void add_environment() {
        if (!opt_.env_map) return;
        s_.env = opt_.env_map;
        Light l;
        l.kind = LightKind::Environment;
        l.L = Rgb(1.f);
        editor_.add_light(std::move(l));
    }

    // ---- camera ------------------------------------------------------------------------------

    void place_camera(const DescInstance* inst, const Bounds3& B) {
        Camera& c = s_.camera;
        const DescCamera* dc = inst ? &d_.cameras[static_cast<std::size_t>(inst->index)] : nullptr;
        const double window_aspect = double(kCs184WindowWidth) / double(kCs184WindowHeight);
        c.hfov_deg = !dc                              ? 50.f
                     : opt_.framing == Framing::Cs184 ? dc->course_hfov_deg(window_aspect)
                                                      : dc->hfov_deg();
        c.znear = dc ? dc->znear : 0.01f; // no camera: spec §3.1 clip planes
        c.zfar = dc ? dc->zfar : 100.f;

        Vec3d target(0.0);
        double D = 1.0;
        if (B.empty()) {
            diag_.warn(SourceLoc{d_.source}, "scene has no geometry");
        } else {
            target = to_d(B.center());
            D = 1.5 * length(to_d(B.extent()));
            if (!(D > 0.0)) D = 1.0;
        }

        if (opt_.camera_mode == CameraMode::File && inst) {
            const Mat4& W = inst->world;
            Vec3d pos = W.point(Vec3d(0.0));
            Vec3d z = W.column(2), x = W.column(0);
            const std::string what = "camera node '" + inst->node_name + "'";
            double lz = length(z);
            if (!(lz > 0.0)) fail(inst->line, what + " has a degenerate orientation");
            z /= lz;
            x -= z * dot(x, z);
            double lx = length(x);
            if (!(lx > 0.0)) fail(inst->line, what + " has a degenerate orientation");
            x /= lx;
            Vec3d y = cross(z, x);
            if (dot(y, W.column(1)) < 0.0) y = -y; // keep the file's handedness of up
            double dist = B.empty() ? 1.0 : length(target - pos);
            set_pose(pos, x, y, z, pos - z * (dist > 0.0 ? dist : 1.0));
            return;
        }

        // Course framing rule (spec §3.1): orbit the bounds' centre from the file camera's
        // direction c_dir = normalize(W(0,0,-1)) (a point, without the division by w).
        Vec3d c_dir(0.0);
        if (inst) {
            s_.file_camera_pos = to_f(inst->world.point(Vec3d(0.0)));
            Vec3d q = affine_point(inst->world, Vec3d(0, 0, -1));
            double lq = length(q);
            if (lq > 0.0 && std::isfinite(lq)) c_dir = q / lq;
        }
        double phi = std::acos(std::clamp(c_dir.y, -1.0, 1.0));
        double theta = std::atan2(c_dir.x, c_dir.z);
        if (std::sin(phi) == 0.0) phi += kPoleNudge;
        Vec3d pos = target + Vec3d(std::sin(phi) * std::sin(theta), std::cos(phi),
                                   std::sin(phi) * std::cos(theta)) *
                                 D;
        const Vec3d view = pos - target;
        // Straight down or up: any horizontal x keeps the basis valid.
        const Basis b = level_basis(view).value_or(
            Basis{Vec3d(1, 0, 0), normalize(cross(view, Vec3d(1, 0, 0))), normalize(view)});
        set_pose(pos, b.x, b.y, b.z, target);
    }

    void set_pose(const Vec3d& pos, const Vec3d& x, const Vec3d& y, const Vec3d& z,
                  const Vec3d& target) {
        Camera& c = s_.camera;
        c.pos = to_f(pos);
        c.x = to_f(x);
        c.y = to_f(y);
        c.z = to_f(z);
        c.target = to_f(target);
    }
};

} // namespace

Scene build_scene(const SceneDesc& desc, const BuildOptions& opt, Diagnostics& diag) {
    return Builder(desc, opt, diag).run();
}

void apply_camera_overrides(Camera& camera, const CameraOverrides& o) {
    if (o.hfov_deg) {
        if (!(*o.hfov_deg > 0.f && *o.hfov_deg < 180.f)) {
            throw Error(ErrorKind::Usage,
                        fmt::format("--fov: {:g} is not a horizontal field of view in (0, 180) "
                                    "degrees",
                                    double(*o.hfov_deg)));
        }
        camera.hfov_deg = *o.hfov_deg;
    }
    if (!o.from && !o.at) return;
    const Vec3d from = to_d(o.from.value_or(camera.pos));
    const Vec3d at = to_d(o.at.value_or(camera.target));
    const Vec3d view = from - at;
    const char* flags = o.from && o.at ? "--look-from and --look-at"
                        : o.from       ? "--look-from (with the camera's target)"
                                       : "--look-at (with the camera's position)";
    if (!(length(view) > 0.0))
        throw Error(ErrorKind::Usage, std::string(flags) +
                                          ": the eye is at the point it looks at; give two "
                                          "different points");
    const std::optional<Basis> b = level_basis(view);
    if (!b)
        throw Error(ErrorKind::Usage,
                    std::string(flags) +
                        ": the camera would look straight up or down, along world +Y, which is "
                        "its up direction; move one point sideways");
    camera.pos = to_f(from);
    camera.x = to_f(b->x);
    camera.y = to_f(b->y);
    camera.z = to_f(b->z);
    camera.target = to_f(at);
}

void frame_camera(Camera& camera, Framing framing, int width) {
    // At the window's own width the field of view is the window's, exactly.
    if (framing == Framing::Candela || width == kCs184WindowWidth) return;
    // screenDist = 800 / (2 tan(hFov_800 / 2)) pixels, kept at every width.
    const double tan_half = std::tan(deg_to_rad(0.5 * double(camera.hfov_deg))) * double(width) /
                            double(kCs184WindowWidth);
    camera.hfov_deg = static_cast<float>(rad_to_deg(2.0 * std::atan(tan_half)));
}

} // namespace candela
