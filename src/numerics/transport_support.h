#pragma once
// Scene construction, rendering and formatting shared by the stiff-transport and guard cases
// (src/numerics/transport_*.cpp). Not a public interface.
#include "candela/numerics/stress.h"
#include "candela/render/renderer.h"
#include "candela/render/settings.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene.h"
#include "candela/scene/scene_editor.h"

#include <fmt/printf.h>

#include <cstdint>
#include <string>

namespace candela::numerics::transport {

/// |z| bound of every statistical row: a correct estimator fails with probability 6e-5 per
/// comparison (normal tails), and the seeds are fixed, so each row is deterministic.
constexpr double kZBound = 4.0;

/// A rendered film reduced to the figures the cases report.
struct Measured {
    double mean = 0.0;         ///< mean over pixels of the pixel-mean luminance
    double std_err = 0.0;      ///< its standard error (per-pixel variances of the mean)
    double min_pixel = 0.0;    ///< smallest pixel-mean luminance
    double max_pixel = 0.0;    ///< largest pixel-mean luminance
    double max_rel_dev = 0.0;  ///< max over pixels and channels |pixel - ref| / ref (see below)
    std::uint64_t samples = 0; ///< camera samples taken, finite or not
    std::uint64_t dropped = 0; ///< non-finite samples dropped by the renderer
    std::uint64_t nonfinite_pixels = 0; ///< pixels whose stored mean is not finite (must be 0)
    std::uint64_t rays = 0;             ///< closest-hit queries
    double seconds = 0.0;
};

/// Render settings for the cases: tiny film, variance channel on, fixed seed, quiet.
RenderSettings case_settings(int size, int spp, std::uint64_t seed);

/// Renders `scene` with `s` and reduces the film. `ref` (> 0) is the value max_rel_dev is
/// measured against; pass 0 to skip it.
Measured render_measure(const Scene& scene, const RenderSettings& s, double ref = 0.0);

// --- Scene pieces ------------------------------------------------------------------------------

/// Appends a material and returns its index.
std::uint32_t add_material(Scene& scene, const Material& m);
Material diffuse_material(float albedo, float Le = 0.f);
Material emission_material(float Le);
Material glass_material(float ior);
Material conductor_material(float alpha, const Rgb& eta, const Rgb& k);

/// A sphere; when its material emits, also a Sphere light record.
void add_sphere(Scene& scene, const Vec3& c, float r, std::uint32_t mat);
/// An axis-aligned box [lo, hi] of 12 triangles with outward face normals (per-face vertices);
/// when its material emits, also a two-sided Mesh light record.
void add_box(Scene& scene, const Vec3& lo, const Vec3& hi, std::uint32_t mat);
// Floors, rectangle lights and the furnace scene: candela/scene/procedural.h.
/// Uniform radiance Le from the upper hemisphere (+y).
void add_sky(Scene& scene, float Le);
/// A pinhole camera at pos looking at target, `up` roughly up, horizontal field of view hfov.
Camera look_at(const Vec3& pos, const Vec3& target, const Vec3& up, float hfov_deg);

// --- Formatting ----------------------------------------------------------------------------------

/// "W x H x spp spp, <accel>" for the method column.
std::string method_of(const RenderSettings& s, const char* what);
/// A z-test row: expected value `expected` (with its description), measured mean +- std_err;
/// passes when |z| < kZBound, std_err < informative_rel * expected (the estimate can tell a
/// wrong answer from a right one) and nothing was dropped.
StressResult z_row(const std::string& group, const std::string& name, const std::string& method,
                   const std::string& expected_desc, double expected, const Measured& m,
                   double informative_rel);
/// The same against an interval [lo, hi] known to contain the expected value (a closed form
/// with a bounded, deterministic approximation error): z is the distance from the mean to the
/// interval in standard errors.
StressResult band_row(const std::string& group, const std::string& name, const std::string& method,
                      const std::string& expected_desc, double lo, double hi, const Measured& m,
                      double informative_rel);

} // namespace candela::numerics::transport
