// Different estimators of the same integral must agree in the mean; the image must not depend
// on the thread count; backends must give identical pixels wherever their hits agree.
#include "render_support.h"

#include "candela/io/image_io.h"
#include "candela/render/integrator.h"
#include "candela/render/output.h"
#include "candela/scene/builder.h"
#include "candela/scene/interaction.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <unistd.h>

using namespace candela;
using namespace candela::test;

namespace {

RenderSettings cb_settings() {
    RenderSettings s;
    s.width = 32;
    s.height = 24;
    s.spp = 64;
    s.max_depth = 3;
    s.quiet = true;
    s.seed = 11;
    s.aovs = AovSet::parse("variance");
    return s;
}

void check_same_mean(const Estimate& a, const Estimate& b, const char* what) {
    double se = std::sqrt(a.std_err * a.std_err + b.std_err * b.std_err);
    INFO(what << ": " << a.mean << " +- " << a.std_err << " vs " << b.mean << " +- " << b.std_err);
    REQUIRE(se > 0.0);
    CHECK(std::abs(a.mean - b.mean) < kZBound * se);
    CHECK(se < 0.05 * a.mean); // the comparison has power
}

} // namespace

TEST_CASE("light sampling, hemisphere sampling, MIS on/off and samplers agree in the mean",
          "[render][stat]") {
    const Scene& scene = spheres_scene();
    RenderSettings base = cb_settings();
    Estimate reference = film_estimate(render_film(scene, base));

    SECTION("MIS off") {
        RenderSettings s = base;
        s.mis = false;
        s.seed = 12;
        check_same_mean(reference, film_estimate(render_film(scene, s)), "no-mis");
    }
    SECTION("uniform hemisphere direct lighting") {
        RenderSettings s = base;
        s.hemisphere = true;
        s.light_samples = 4;
        s.seed = 13;
        check_same_mean(reference, film_estimate(render_film(scene, s)), "hemisphere");
    }
    SECTION("Owen-scrambled Sobol sampler") {
        RenderSettings s = base;
        s.sampler = SamplerKind::Sobol;
        s.seed = 14;
        check_same_mean(reference, film_estimate(render_film(scene, s)), "sobol");
    }
    SECTION("direct integrator: light sampling vs hemisphere sampling") {
        RenderSettings a = base, b = base;
        a.integrator = b.integrator = IntegratorKind::Direct;
        a.max_depth = b.max_depth = 1;
        a.light_samples = 2;
        b.hemisphere = true;
        b.light_samples = 8;
        b.seed = 15;
        check_same_mean(film_estimate(render_film(scene, a)), film_estimate(render_film(scene, b)),
                        "direct light vs hemisphere");
    }
    SECTION("direct + indirect light paths add up to all") {
        RenderSettings d = base, i = base;
        d.light_paths = LightPaths::Direct;
        i.light_paths = LightPaths::Indirect;
        i.seed = 16;
        Estimate ed = film_estimate(render_film(scene, d));
        Estimate ei = film_estimate(render_film(scene, i));
        CHECK(ei.mean > 0.0);
        check_same_mean(reference,
                        Estimate{ed.mean + ei.mean,
                                 std::sqrt(ed.std_err * ed.std_err + ei.std_err * ei.std_err)},
                        "direct + indirect");
    }
}

TEST_CASE("one thread and many threads give a bit-identical EXR", "[render][quick]") {
    const Scene& scene = spheres_scene();
    RenderSettings s = cb_settings();
    s.spp = 4;
    s.max_depth = 4;
    s.aovs = AovSet::all();
    for (SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol}) {
        s.sampler = sampler;
        s.threads = 1;
        Film one = render_film(scene, s);
        s.threads = 4;
        Film many = render_film(scene, s);
        auto dir =
            std::filesystem::temp_directory_path() / ("candela-det-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
        write_exr((dir / "one.exr").string(), film_to_image(one, {}));
        write_exr((dir / "many.exr").string(), film_to_image(many, {}));
        ImageData a = read_image((dir / "one.exr").string());
        ImageData b = read_image((dir / "many.exr").string());
        std::filesystem::remove_all(dir);
        REQUIRE(a.pixels.size() == b.pixels.size());
        CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
        CHECK(one.raw_sum() == many.raw_sum());
    }
}

TEST_CASE("embree and builtin renders are identical wherever the hits agree", "[render][quick]") {
    const Scene& scene = spheres_scene();
    RenderSettings s = cb_settings();
    s.spp = 1;
    s.integrator = IntegratorKind::Normals;
    s.aovs = AovSet{};
    s.accel.kind = AccelKind::Embree;
    auto embree = make_accel(scene, s.accel);
    Film fe = Renderer(scene, *embree, s).render(*std::make_unique<RenderStats>());
    s.accel.kind = AccelKind::Builtin;
    auto builtin = make_accel(scene, s.accel);
    Film fb = Renderer(scene, *builtin, s).render(*std::make_unique<RenderStats>());

    // Normals from hits on the same triangle differ by a few ulps of (t, u, v) at most.
    constexpr float kRoundoff = 1e-5f;
    Integrator integrator(scene, *embree, s);
    int agreeing = 0, identical = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            // Regenerate the pixel's camera ray exactly as the renderer did.
            Sampler sampler(s.sampler, s.seed);
            sampler.start(std::uint32_t(x), std::uint32_t(y), 0);
            Vec2 u = sampler.get_2d();
            Ray r = integrator.camera_ray(float(x) + u.x, float(y) + u.y, Vec2(0.5f, 0.5f));
            auto he = embree->intersect(r), hb = builtin->intersect(r);
            bool agree = he.has_value() == hb.has_value() &&
                         (!he || (he->geom_id == hb->geom_id && he->prim_id == hb->prim_id));
            if (!agree) continue;
            ++agreeing;
            bool bitwise = !he || (he->t == hb->t && he->u == hb->u && he->v == hb->v);
            Rgb d = vabs(fe.mean(x, y) - fb.mean(x, y));
            // Same primitive: the shading inputs differ only by the backends' last-bit
            // rounding of (t, u, v), so normals agree to float precision; bitwise-equal hits
            // give bitwise-equal pixels (one shared make_interaction).
            if (bitwise ? fe.mean(x, y) == fb.mean(x, y) : max_component(d) < kRoundoff)
                ++identical;
        }
    INFO(agreeing << " pixels with agreeing hits");
    CHECK(agreeing >= s.width * s.height * 99 / 100);
    CHECK(identical == agreeing);
}
