// Light selection seen in images: a lamp-lit room must render the same beside a sun over a
// ground of any width, with every estimator (the sun's selection weight does not grow with the
// scene, and no light's probability vanishes).
#include "render_support.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace candela;
using namespace candela::test;

TEST_CASE("a lamp-lit room renders alike beside a sun over a 100 km ground", "[render][stat]") {
    // The room alone (one light: nothing to choose) is the reference; with the sun and ground
    // outside it, no light of which enters, every estimator must find the same mean. Each
    // comparison is a z-test on the two renders' independent standard errors (kZBound).
    RenderSettings s;
    s.width = 16;
    s.height = 12;
    s.spp = 64;
    s.max_depth = 4;
    s.quiet = true;
    s.aovs = AovSet::parse("variance");
    s.seed = 11;
    const Estimate ref = film_estimate(render_film(make_sunlit_room_scene(0.f, false), s));
    INFO("room alone: " << ref.mean << " +- " << ref.std_err);
    REQUIRE(ref.mean > 0.1);
    for (float width : {20.f, 1e3f, 1e5f}) {
        const Scene scene = make_sunlit_room_scene(width, true);
        struct Variant {
            const char* name;
            IntegratorKind integrator;
            bool hemisphere;
        };
        for (const Variant& v : {Variant{"path", IntegratorKind::Path, false},
                                 Variant{"direct", IntegratorKind::Direct, false},
                                 Variant{"path -H", IntegratorKind::Path, true}}) {
            RenderSettings t = s;
            t.integrator = v.integrator;
            t.hemisphere = v.hemisphere;
            t.seed = 12;
            // The direct integrator sums one bounce of light: compare it with the room alone
            // rendered the same way.
            Estimate r = ref;
            if (v.integrator == IntegratorKind::Direct)
                r = film_estimate(render_film(make_sunlit_room_scene(0.f, false), t));
            t.seed = 13;
            const Estimate e = film_estimate(render_film(scene, t));
            const double z = (e.mean - r.mean) / std::hypot(e.std_err, r.std_err);
            INFO("ground " << width << " m, " << v.name << ": " << e.mean << " +- " << e.std_err
                           << " against " << r.mean << " +- " << r.std_err << ", z = " << z);
            CHECK(std::abs(z) < kZBound);
            // The lamp is chosen half the time, not 2^-25 of it: the noise stays that of the
            // room alone within a factor that covers halving the lamp's samples (sqrt 2) and
            // the sun's wasted shadow rays.
            CHECK(e.std_err < 3.0 * r.std_err);
        }
    }
}
