#pragma once
// Small scenes built in code and statistics over rendered films, shared by the render tests.
// Floors, rectangle lights and the furnace scene come from candela/scene/procedural.h.
#include "candela/accel/accel.h"
#include "candela/io/collada.h"
#include "candela/io/envmap_file.h"
#include "candela/render/film.h"
#include "candela/render/renderer.h"
#include "candela/scene/builder.h"
#include "candela/scene/procedural.h"
#include "candela/scene/scene.h"
#include "candela/scene/scene_editor.h"

#include <cmath>
#include <memory>

namespace candela::test {

/// |z| bound for tests of a mean against its expected value. With a fixed seed each test is
/// deterministic; 4 standard errors make a false failure of a correct estimator a 6e-5 event
/// per comparison for any seed we might pick.
constexpr double kZBound = 4.0;

struct Estimate {
    double mean = 0.0;    ///< average over pixels of the per-pixel mean luminance
    double std_err = 0.0; ///< its standard error, from the per-pixel variances of the mean
};

/// Mean luminance of the film (equal weight per pixel) and its standard error. Needs the film's
/// variance channel.
inline Estimate film_estimate(const Film& film) {
    double sum = 0.0, var = 0.0;
    const double P = double(film.width()) * film.height();
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            sum += luminance(film.mean(x, y));
            // Var of luminance of the mean, bounded by treating channels as fully correlated.
            Rgb v = film.variance_of_mean(x, y);
            double sd = 0.2126 * std::sqrt(v.x) + 0.7152 * std::sqrt(v.y) + 0.0722 * std::sqrt(v.z);
            var += sd * sd;
        }
    return {sum / P, std::sqrt(var) / P};
}

inline Film render_film(const Scene& scene, const RenderSettings& s,
                        RenderStats* stats_out = nullptr) {
    std::unique_ptr<Accel> accel = make_accel(scene, s.accel);
    Renderer r(scene, *accel, s);
    RenderStats stats;
    Film f = r.render(stats);
    if (stats_out) *stats_out = stats;
    return f;
}

/// candela's own Cornell box with two diffuse spheres and a closed mesh (scenes/README.md),
/// loaded once per test run. It is in every clone, so the tests that render it always run.
inline const Scene& spheres_scene() {
    static Scene scene = [] {
        Diagnostics diag;
        return load_scene(std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae",
                          BuildOptions{}, diag);
    }();
    return scene;
}

/// A camera at `pos` looking straight down (-y).
inline Camera camera_looking_down(const Vec3& pos, float hfov_deg) {
    Camera c;
    c.pos = pos;
    c.x = Vec3(1, 0, 0);
    c.y = Vec3(0, 0, -1);
    c.z = Vec3(0, 1, 0);
    c.hfov_deg = hfov_deg;
    c.znear = 0.f;
    c.zfar = 1e30f;
    c.target = pos - Vec3(0, 1, 0);
    return c;
}

} // namespace candela::test
