#pragma once
// Where one pixel's light comes from (`candela probe`): the pixel's samples rendered by the
// render's own integrator and sampler (Integrator::render with PathEvents), so the pixel's value
// is the one a render with the same settings and --adaptive none gives, and every contribution
// to a sample's radiance is attributed to its scattering order, its light, the first surface
// the camera ray hit and the last surface that scattered before the light.
//
// Each split is an estimator of its own: class c's value is the mean over the pixel's samples of
// the part of a sample's radiance that belongs to c (0 for samples with none), so the classes
// of one split add up to the pixel's mean, and each has the standard error of a mean of n
// independent values. Non-finite samples are dropped, as the film drops them.
#include "candela/accel/accel.h"
#include "candela/math/vec.h"
#include "candela/render/settings.h"
#include "candela/scene/scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace candela {

/// One class of a split: its share of the pixel's mean and that share's standard error.
struct ProbeShare {
    std::string name;
    Rgb mean{0.f};
    Rgb std_error{0.f};
};

/// One vertex of a heavy sample's path.
struct ProbeVertex {
    int depth = 0;
    std::string material; ///< its name and BSDF kind
    std::string object;   ///< the mesh's name, or "sphere N"
    std::string emits;    ///< the light it emits as, "" for none
    std::string scatter;  ///< how the path left it ("diffuse reflection", ...), "" at its end
};

/// One contribution of a heavy sample.
struct ProbeLight {
    int order = 0;
    std::string light;
    Rgb value{0.f};
};

/// A sample of the pixel with its path, the heaviest first.
struct ProbePath {
    std::uint64_t sample = 0; ///< sample index
    Rgb L{0.f};
    std::vector<ProbeVertex> vertices;
    std::vector<ProbeLight> lights;
};

struct ProbeResult {
    int x = 0, y = 0;                 ///< the pixel, image coordinates (row 0 at the top)
    std::uint64_t samples = 0;        ///< samples taken (finite and dropped)
    std::uint64_t dropped = 0;        ///< non-finite samples dropped
    Rgb pixel{0.f};                   ///< the pixel's value, as the film computes it
    Rgb std_error{0.f};               ///< its standard error per channel
    std::vector<ProbeShare> by_order; ///< index = scattering order (0: emitter seen)
    /// Scene::lights, then the rays that left the scene when they found several infinite lights
    std::vector<ProbeShare> by_light;
    std::vector<ProbeShare> by_first_material; ///< materials, then "nothing hit"
    std::vector<ProbeShare> by_first_object;   ///< meshes, spheres, then "nothing hit"
    std::vector<ProbeShare> by_last_scatter;   ///< materials, then "camera" (order 0)
    /// Fraction of the sum of the samples' luminance carried by the brightest 1 % of them
    /// (at least one sample): near 0.01 for a smooth pixel, near 1 for one made of fireflies.
    double top_percent_share = 0.0;
    std::vector<ProbePath> heaviest;
};

/// The probe of pixel (x, y) of the full frame with `settings` (its -s samples from
/// sample_offset, its seed, depth, light sampling; adaptive sampling and the region are
/// ignored), with the paths of the `heaviest` brightest samples. Throws Error(Usage) for a
/// pixel outside the frame or the normals integrator (it carries no light).
ProbeResult probe_pixel(const Scene& scene, const Accel& accel, const RenderSettings& settings,
                        int x, int y, int heaviest);

/// Names of a scene's lights as probe reports them: "light 2 (rect)", "light 0 (mesh 'Lamp')".
std::string light_display_name(const Scene& scene, std::int32_t light);

} // namespace candela
