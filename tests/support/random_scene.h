#pragma once
// Random scenes for estimator agreement: a few primitives under random, often non-rigid node
// transforms (shears, non-uniform scales, mirrors), every material kind, every light kind with
// several infinite lights at once. Every fifth scene adds a string of 1 to 200 lights of every
// finite kind with powers over nine decades; every fifth another a sun over a ground 100 km wide
// beside the scene's own lights (the lamp-beside-a-sun case of light selection). Scenes are built
// as a SceneDesc (what a COLLADA file says, with flattened world matrices) and go through the scene
// builder, so that what the builder does with transforms is under test too. Each scene is a pure
// function of its index.
#include "cameras.h"

#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/io/image_io.h"
#include "candela/math/constants.h"
#include "candela/math/mat4.h"
#include "candela/sampling/rng.h"
#include "candela/scene/builder.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace candela::test {

/// What one random scene holds, for messages and for choosing which estimators apply.
struct RandomSceneInfo {
    std::string summary;         ///< one line: primitives, materials, lights
    bool has_env = false;        ///< uses the environment map (BuildOptions::env_map)
    int infinite_lights = 0;     ///< ambient lights + environment
    int delta_lights = 0;        ///< point, spot, directional
    int area_lights = 0;         ///< CGL <area> lights
    int emissive_prims = 0;      ///< emissive meshes and spheres
    bool non_rigid_area = false; ///< an area light under a shear or non-uniform scale
};

class RandomSceneMaker {
  public:
    /// `env_path`: an EXR environment map scenes may use (see write_test_envmap()).
    explicit RandomSceneMaker(std::string env_path) : env_path_(std::move(env_path)) {}

    /// Scene number `index`. The result depends only on the index.
    Scene make(std::uint64_t index, RandomSceneInfo& info) const {
        Rand r(hash_combine(kSceneSalt, index));
        SceneDesc d;
        d.source = "random-scene-" + std::to_string(index);
        info = RandomSceneInfo{};
        summary_.clear();

        // Floor: a large diffuse (or glossy) square at y = 0 (100 km wide under a sun).
        const bool sun_over_ground = index % 5 == 4;
        const double floor_half = sun_over_ground ? 5e4 : 2.5;
        const int floor_mat = add_material(d, r, r.uniform() < 0.75 ? kDiffuseOnly : kGlossy, info);
        add_instance(d, add_quad(d), floor_mat, Mat4::scale(Vec3d(floor_half, 1.0, floor_half)));

        // Objects: boxes, smooth-normal blobs and spheres over the floor.
        const int objects = 1 + int(r.uniform() * 3.0);
        for (int k = 0; k < objects; ++k) {
            const double pick = r.uniform();
            const int mat = add_material(d, r, kAnyMaterial, info);
            const Mat4 w =
                Mat4::translate(Vec3d(r.range(-1.5, 1.5), r.range(0.4, 1.2), r.range(-1.5, 1.5))) *
                random_linear(r, 0.25, 0.6);
            if (pick < 0.4)
                add_instance(d, add_box(d), mat, w);
            else if (pick < 0.7)
                add_instance(d, add_blob(d), mat, w);
            else
                add_instance(d, add_sphere(d), mat, w);
        }

        // Lights: at least one of some kind.
        int lights = 0;
        while (lights == 0) {
            if (r.uniform() < 0.45) lights += add_area_light(d, r, info);
            if (r.uniform() < 0.35) lights += add_point_or_spot(d, r, info);
            if (r.uniform() < 0.25) lights += add_directional(d, r, info);
            // Often two ambient lights, or an ambient light with the environment: infinite
            // lights are weighed light by light.
            const double inf = r.uniform();
            if (inf < 0.25) {
                lights += add_ambient(d, r, info);
            } else if (inf < 0.45) {
                lights += add_ambient(d, r, info);
                lights += add_ambient(d, r, info);
            }
            if (!env_path_.empty() && r.uniform() < 0.25) {
                info.has_env = true;
                ++info.infinite_lights;
                ++lights;
            }
        }

        // Extra lights from their own stream, so the scenes without them stay as they were.
        Rand extra(hash_combine(kExtraSalt, index));
        if (index % 5 == 3) add_light_string(d, extra, info);
        if (sun_over_ground) {
            add_directional(d, extra, info);
            add_point_or_spot(d, extra, info);
        }

        // The camera: framed on the scene's bounds from a random direction above the floor.
        const float xfov = float(r.range(35.0, 60.0));
        const double phi = r.range(0.0, 2.0 * kPiD), height = r.range(0.4, 1.5);
        add_desc_camera(d, xfov,
                        Mat4::translate(Vec3d(std::cos(phi), height, std::sin(phi)) * 5.0));

        BuildOptions opt;
        if (sun_over_ground) {
            // Framing on a 100 km ground would put the camera kilometres away: keep the pose,
            // turned to look at the objects.
            opt.camera_mode = CameraMode::File;
            d.instances.back().world =
                look_at(d.instances.back().world.point(Vec3d(0.0)), Vec3d(0.0, 0.6, 0.0));
        }
        if (info.has_env) opt.env_map = load_envmap(env_path_);
        Diagnostics diag;
        Scene scene = build_scene(d, opt, diag);
        info.summary = d.source + ": " + summary_;
        return scene;
    }

  private:
    static constexpr std::uint64_t kSceneSalt = 0x52414e44534345ULL;
    static constexpr std::uint64_t kExtraSalt = 0x4d414e594c4954ULL;
    /// The string of lights: at most this many, powers spread over this many decades.
    static constexpr int kMaxStringLights = 200;
    static constexpr double kStringPowerDecades = 9.0;
    /// The floor is diffuse or glossy: a mirror floor would turn every light into a caustic
    /// that only BSDF sampling finds, whose rare, bright paths no sample variance estimates
    /// well enough for a z-test. Objects take every material.
    enum MaterialSet { kDiffuseOnly, kGlossy, kAnyMaterial };

    /// Uniform numbers from a PCG32 stream.
    struct Rand {
        explicit Rand(std::uint64_t seed) : rng(seed, hash_combine(seed, 1)) {}
        double uniform() { return rng.next_float(); }
        double range(double a, double b) { return a + (b - a) * uniform(); }
        Pcg32 rng;
    };

    std::string env_path_;
    mutable std::string summary_;

    /// A linear map of overall size about [lo, hi]: rotations, and often a shear, a
    /// non-uniform scale or a mirror, composed as nested nodes would compose them.
    static Mat4 random_linear(Rand& r, double lo, double hi) {
        auto rotation = [&r]() {
            Vec3d axis(r.range(-1, 1), r.range(-1, 1), r.range(-1, 1));
            if (length(axis) < 1e-3) axis = Vec3d(0, 1, 0);
            return Mat4::rotate(normalize(axis), r.range(0.0, 360.0));
        };
        const double s = r.range(lo, hi);
        Mat4 m = rotation() * Mat4::scale(Vec3d(s));
        const double kind = r.uniform();
        if (kind < 0.3) {
            m = m * Mat4::scale(Vec3d(r.range(0.5, 1.6), r.range(0.5, 1.6), r.range(0.5, 1.6)));
        } else if (kind < 0.6) {
            Mat4 shear;
            shear.m[0][1] = r.range(-0.8, 0.8);
            shear.m[1][2] = r.range(-0.8, 0.8);
            m = m * shear * rotation();
        } else if (kind < 0.7) {
            m = m * Mat4::scale(Vec3d(-1.0, 1.0, 1.0)); // a mirror
        }
        return rotation() * m;
    }

    /// The camera pose at `pos` looking at `target` (the camera looks along its -z), +y up.
    static Mat4 look_at(const Vec3d& pos, const Vec3d& target) {
        const Vec3d z = normalize(pos - target);
        const Vec3d x = normalize(cross(Vec3d(0, 1, 0), z));
        const Vec3d y = cross(z, x);
        Mat4 w = Mat4::translate(pos);
        for (int i = 0; i < 3; ++i) {
            w.m[i][0] = x[i];
            w.m[i][1] = y[i];
            w.m[i][2] = z[i];
        }
        return w;
    }

    static bool is_rigid_up_to_scale(const Mat4& w) {
        // Columns orthogonal and of equal length.
        Vec3d c[3] = {w.column(0), w.column(1), w.column(2)};
        const double l = length(c[0]);
        constexpr double kTol = 1e-9;
        for (int i = 0; i < 3; ++i) {
            if (std::abs(length(c[i]) - l) > kTol * l) return false;
            for (int j = i + 1; j < 3; ++j)
                if (std::abs(dot(c[i], c[j])) > kTol * l * l) return false;
        }
        return true;
    }

    int add_material(SceneDesc& d, Rand& r, MaterialSet set, RandomSceneInfo& info) const {
        Material m;
        m.name = "m" + std::to_string(d.materials.size());
        const double pick = r.uniform();
        auto colour = [&r](double lo, double hi) {
            return Rgb(float(r.range(lo, hi)), float(r.range(lo, hi)), float(r.range(lo, hi)));
        };
        if (set == kDiffuseOnly || pick < 0.35) {
            m.kind = BsdfKind::Diffuse;
            m.albedo = colour(0.2, 0.85);
            summary_ += "diffuse ";
        } else if (pick < 0.55 || set == kGlossy) {
            m.kind = BsdfKind::Microfacet;
            m.alpha = float(r.range(0.08, 0.6));
            m.eta = colour(0.2, 1.5);
            m.k = colour(1.0, 4.0);
            summary_ += "microfacet ";
        } else if (pick < 0.65) {
            m.kind = BsdfKind::Mirror;
            m.reflectance = colour(0.5, 0.95);
            summary_ += "mirror ";
        } else if (pick < 0.8) {
            m.kind = BsdfKind::Glass;
            m.ior = float(r.range(1.2, 1.8));
            m.reflectance = colour(0.7, 1.0);
            m.transmittance = colour(0.7, 1.0);
            // Half of the glass is rough (ignored by a build without the rough dielectric).
            m.roughness = r.uniform() < 0.5 ? float(r.range(0.05, 0.5)) : 0.f;
            summary_ += m.roughness > 0.f ? "rough-glass " : "glass ";
        } else if (pick < 0.85) {
            m.kind = BsdfKind::Refraction;
            m.ior = float(r.range(1.2, 1.6));
            m.transmittance = colour(0.7, 1.0);
            summary_ += "refraction ";
        } else {
            m.kind = BsdfKind::Emission;
            m.radiance = colour(0.5, 3.0);
            ++info.emissive_prims;
            summary_ += "emissive ";
        }
        d.materials.push_back(DescMaterial{m, 0});
        return int(d.materials.size()) - 1;
    }

    static void add_instance(SceneDesc& d, int geometry, int material, const Mat4& w) {
        DescInstance inst;
        inst.kind = DescInstanceKind::Geometry;
        inst.index = geometry;
        inst.material = material;
        inst.group_materials.assign(d.geometries[std::size_t(geometry)].groups.size(), material);
        inst.world = w;
        inst.node_name = "node" + std::to_string(d.instances.size());
        d.instances.push_back(inst);
    }

    /// A unit square in the y = 0 plane, normal +y.
    static int add_quad(SceneDesc& d) {
        DescGeometry g;
        g.name = "quad";
        g.positions = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
        DescPrimGroup grp;
        grp.position_index = {0, 1, 2, 0, 2, 3};
        g.groups.push_back(grp);
        d.geometries.push_back(g);
        return int(d.geometries.size()) - 1;
    }

    /// The cube [-1, 1]^3, flat faces wound outward.
    static int add_box(SceneDesc& d) {
        DescGeometry g;
        g.name = "box";
        for (int i = 0; i < 8; ++i)
            g.positions.push_back(Vec3(i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f));
        DescPrimGroup grp;
        // Faces as (a, b, c, d) counter-clockwise seen from outside.
        const std::uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
        for (const auto& f : faces)
            for (std::uint32_t t : {f[0], f[1], f[2], f[0], f[2], f[3]})
                grp.position_index.push_back(t);
        g.groups.push_back(grp);
        d.geometries.push_back(g);
        return int(d.geometries.size()) - 1;
    }

    /// A coarse UV sphere of radius 1 with the sphere's own normals as file normals: the
    /// shading normals differ from the flat faces, most at the silhouettes.
    static int add_blob(SceneDesc& d) {
        constexpr int kRings = 5, kSegments = 8;
        DescGeometry g;
        g.name = "blob";
        g.positions.push_back(Vec3(0, 1, 0));
        for (int i = 1; i < kRings; ++i)
            for (int j = 0; j < kSegments; ++j) {
                const double th = kPiD * i / kRings, ph = 2.0 * kPiD * j / kSegments;
                g.positions.push_back(Vec3(
                    Vec3d(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph))));
            }
        g.positions.push_back(Vec3(0, -1, 0));
        g.normals = g.positions;
        const auto ring = [](int i, int j) {
            return std::uint32_t(1 + (i - 1) * kSegments + (j % kSegments));
        };
        const std::uint32_t south = std::uint32_t(g.positions.size() - 1);
        DescPrimGroup grp;
        auto tri = [&grp](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
            for (std::uint32_t t : {a, b, c}) { // counter-clockwise seen from outside
                grp.position_index.push_back(t);
                grp.normal_index.push_back(t);
            }
        };
        for (int j = 0; j < kSegments; ++j) {
            tri(0, ring(1, j + 1), ring(1, j));
            tri(south, ring(kRings - 1, j), ring(kRings - 1, j + 1));
            for (int i = 1; i + 1 < kRings; ++i) {
                tri(ring(i, j), ring(i, j + 1), ring(i + 1, j + 1));
                tri(ring(i, j), ring(i + 1, j + 1), ring(i + 1, j));
            }
        }
        g.groups.push_back(grp);
        d.geometries.push_back(g);
        return int(d.geometries.size()) - 1;
    }

    static int add_sphere(SceneDesc& d) {
        DescGeometry g;
        g.kind = DescGeometryKind::Sphere;
        g.name = "sphere";
        g.radius = 1.f;
        d.geometries.push_back(g);
        return int(d.geometries.size()) - 1;
    }

    static void add_light_instance(SceneDesc& d, const DescLight& l, const Mat4& w) {
        d.lights.push_back(l);
        DescInstance inst;
        inst.kind = DescInstanceKind::Light;
        inst.index = int(d.lights.size()) - 1;
        inst.world = w;
        inst.node_name = l.name;
        d.instances.push_back(inst);
    }

    int add_area_light(SceneDesc& d, Rand& r, RandomSceneInfo& info) const {
        DescLight l;
        l.kind = DescLightKind::Area;
        l.name = "area" + std::to_string(d.lights.size());
        l.color = Rgb(float(r.range(1.0, 6.0)), float(r.range(1.0, 6.0)), float(r.range(1.0, 6.0)));
        // Any linear map (often sheared, stretched or mirrored), then turned so that the
        // emitting side (the image of local z < 0, whose normal is W^-T (0, 0, -1)) faces down
        // within 35 degrees, and lifted above the scene.
        const Mat4 lin = random_linear(r, 0.8, 1.6);
        const Vec3d n = normalize(lin.normal(Vec3d(0, 0, -1)));
        const Vec3d down(0, -1, 0);
        Mat4 align;
        const Vec3d axis = cross(n, down);
        if (length(axis) > 1e-6)
            align = Mat4::rotate(normalize(axis),
                                 rad_to_deg(std::acos(std::clamp(dot(n, down), -1.0, 1.0))));
        else if (dot(n, down) < 0.0)
            align = Mat4::rotate(Vec3d(1, 0, 0), 180.0);
        const Mat4 tilt = Mat4::rotate(Vec3d(0, 1, 0), r.range(0.0, 360.0)) *
                          Mat4::rotate(Vec3d(1, 0, 0), r.range(-35.0, 35.0));
        const Mat4 w =
            Mat4::translate(Vec3d(r.range(-1.0, 1.0), r.range(2.0, 3.0), r.range(-1.0, 1.0))) *
            tilt * align * lin;
        add_light_instance(d, l, w);
        ++info.area_lights;
        if (!is_rigid_up_to_scale(w)) info.non_rigid_area = true;
        summary_ += is_rigid_up_to_scale(w) ? "area-light " : "sheared-area-light ";
        return 1;
    }

    int add_point_or_spot(SceneDesc& d, Rand& r, RandomSceneInfo& info) const {
        DescLight l;
        const bool spot = r.uniform() < 0.5;
        l.kind = spot ? DescLightKind::Spot : DescLightKind::Point;
        l.name = (spot ? "spot" : "point") + std::to_string(d.lights.size());
        l.color = Rgb(float(r.range(2.0, 12.0)));
        if (spot) {
            l.falloff_angle_deg = float(r.range(40.0, 140.0));
            l.falloff_exponent = r.uniform() < 0.5 ? 0.f : float(r.range(0.5, 4.0));
        }
        const Mat4 w =
            Mat4::translate(Vec3d(r.range(-1.5, 1.5), r.range(1.8, 3.0), r.range(-1.5, 1.5))) *
            Mat4::rotate(Vec3d(1, 0, 0), -90.0 + r.range(-30.0, 30.0));
        add_light_instance(d, l, w);
        ++info.delta_lights;
        summary_ += spot ? "spot " : "point ";
        return 1;
    }

    int add_directional(SceneDesc& d, Rand& r, RandomSceneInfo& info) const {
        DescLight l;
        l.kind = DescLightKind::Directional;
        l.name = "sun" + std::to_string(d.lights.size());
        l.color = Rgb(float(r.range(0.5, 2.0)));
        const Mat4 w = Mat4::rotate(Vec3d(0, 1, 0), r.range(0.0, 360.0)) *
                       Mat4::rotate(Vec3d(1, 0, 0), -r.range(30.0, 80.0));
        add_light_instance(d, l, w);
        ++info.delta_lights;
        summary_ += "directional ";
        return 1;
    }

    /// 1 to 200 point, spot and area lights (more often few than many), each scaled by a power
    /// of ten from 1 down to 1e-9.
    void add_light_string(SceneDesc& d, Rand& r, RandomSceneInfo& info) const {
        const double u = r.uniform();
        const int n = 1 + int(u * u * (kMaxStringLights - 1));
        for (int k = 0; k < n; ++k) {
            if (r.uniform() < 0.3)
                add_area_light(d, r, info);
            else
                add_point_or_spot(d, r, info);
            d.lights.back().color *= float(std::pow(10.0, -kStringPowerDecades * r.uniform()));
        }
        summary_ += "(string of " + std::to_string(n) + ") ";
    }

    int add_ambient(SceneDesc& d, Rand& r, RandomSceneInfo& info) const {
        DescLight l;
        l.kind = DescLightKind::Ambient;
        l.name = "ambient" + std::to_string(d.lights.size());
        l.color = Rgb(float(r.range(0.2, 1.0)), float(r.range(0.2, 1.0)), float(r.range(0.2, 1.0)));
        add_light_instance(d, l, Mat4{});
        ++info.infinite_lights;
        summary_ += "ambient ";
        return 1;
    }
};

/// Writes a small lat-long environment map with a bright, smooth lobe and a dim rest, for
/// RandomSceneMaker. Throws Error(Io) when it cannot be written.
inline void write_test_envmap(const std::string& path) {
    ImageData img;
    img.width = 32;
    img.height = 16;
    img.channel_names = {"R", "G", "B"};
    img.pixels.resize(std::size_t(img.width) * img.height * 3);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double u = (x + 0.5) / img.width, v = (y + 0.5) / img.height;
            const double lobe = std::exp(-30.0 * ((u - 0.3) * (u - 0.3) + (v - 0.3) * (v - 0.3)));
            float* p = &img.pixels[(std::size_t(y) * img.width + x) * 3];
            p[0] = float(0.2 + 4.0 * lobe);
            p[1] = float(0.25 + 3.0 * lobe);
            p[2] = float(0.35 + 1.0 * lobe);
        }
    write_exr(path, img);
}

} // namespace candela::test
