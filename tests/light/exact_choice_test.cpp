// The discrete choices inside light sampling realise exactly the probabilities the estimator
// divides by: an environment map's texel (row, then column) and a mesh light's triangle. The
// values of the 32-bit uniform choosing each are counted exactly (support/exact_count.h), so the
// realised probability is known with no sampling error and must equal the reported one to within
// 2^-32. The cases are skewed as the float CDFs these choices replaced could not follow: one
// texel or triangle 1e6 times the others (whose CDF intervals a float rounds to multiples of
// 2^-24) and one near zero (an interval of zero width behind the large one: a texel or triangle
// that weighs but is never chosen).
#include "candela/light/light_sample.h"
#include "candela/scene/envmap.h"
#include "candela/scene/scene_editor.h"

#include "../support/exact_count.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;
using namespace candela::test;

namespace {

/// The realised probabilities below are exact; the comparison allows 2^-32, the probability of
/// one value of the uniform, as the criterion is stated.
constexpr double kExactTol = 0x1p-32;
/// A float density recomputed from its parts in another order of operations: a few roundings.
constexpr double kDensityRelTol = 1e-5;

constexpr int kMapW = 16, kMapH = 8;

/// A sky of radiance 1 over the upper half with a sun 1e6 times brighter, and a black lower
/// half but for one texel of radiance 1e-9: the rows around it weigh about 1e-15 of the whole.
EnvMap sun_map() {
    std::vector<Rgb> tex(std::size_t(kMapW) * kMapH, Rgb(0.f));
    for (int j = 0; j < kMapH / 2; ++j)
        for (int i = 0; i < kMapW; ++i)
            tex[std::size_t(j) * kMapW + i] = Rgb(1.f);
    tex[std::size_t(2) * kMapW + 5] = Rgb(1e6f);
    tex[std::size_t(6) * kMapW + 10] = Rgb(1e-9f);
    return EnvMap(kMapW, kMapH, tex);
}

std::vector<std::uint64_t> counts_of(const UnitCdf& t) {
    return monotone_choice_counts(
        [&t](std::uint32_t u) {
            float remapped = 0.f;
            return t.sample(u, &remapped);
        },
        t.size());
}

/// Six triangles in the plane z = 0: one of area 1e6 times the unit ones, one of 1e-9.
Scene skewed_mesh_scene() {
    Scene s;
    s.source = "skewed-mesh";
    SceneEditor editor(s);
    Material em;
    em.kind = BsdfKind::Emission;
    em.radiance = Rgb(1.f);
    Mesh m;
    m.material = editor.add_material(em);
    m.name = "emitter";
    // Right triangles of legs a, b at x offsets: area a b / 2.
    const float legs[][2] = {{1.f, 2.f}, {2000.f, 1000.f}, {1.f, 2e-9f},
                             {2.f, 1.f}, {1.f, 2.f},       {2.f, 1.f}};
    float x = 0.f;
    for (const auto& l : legs) {
        const auto base = std::uint32_t(m.positions.size());
        m.positions.push_back(Vec3(x, 0.f, 0.f));
        m.positions.push_back(Vec3(x + l[0], 0.f, 0.f));
        m.positions.push_back(Vec3(x, l[1], 0.f));
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
        x += l[0] + 1.f;
    }
    editor.add_mesh(std::move(m));
    editor.finalize();
    return s;
}

} // namespace

TEST_CASE("environment map: every texel is chosen with exactly texel_pmf",
          "[light][envmap][quick]") {
    const EnvMap env = sun_map();
    const std::vector<std::uint64_t> rows = counts_of(env.row_table());
    double total = 0.0;
    for (int j = 0; j < kMapH; ++j) {
        const std::vector<std::uint64_t> cols = counts_of(env.column_table(j));
        for (int i = 0; i < kMapW; ++i) {
            // Row by u.y, column by u.x: texel (i, j) is chosen by rows[j] * cols[i] of the 2^64
            // pairs, exact in a long double (64-bit significand).
            const long double realised = std::ldexp(
                (long double)rows[std::size_t(j)] * (long double)cols[std::size_t(i)], -64);
            const double pmf = env.texel_pmf(i, j);
            INFO("texel (" << i << ", " << j << "): realised " << double(realised) << ", pmf "
                           << pmf);
            CHECK(std::abs(double(realised - (long double)pmf)) <= kExactTol);
            CHECK(realised == (long double)pmf);
            total += pmf;
            // A texel whose neighbourhood has radiance is chosen (the near-zero one too).
            const bool lit = j < kMapH / 2 + 1 || (std::abs(i - 10) <= 1 && j >= 5);
            CHECK((realised > 0) == lit);
            if (realised == 0) continue;
            // A direction drawn inside the texel's values lies in it, with the density
            // texel_pmf w h / (2 pi^2 sin(theta)) that pdf() reports for it.
            const Bits2 u{run_middle(cols, std::size_t(i)), run_middle(rows, std::size_t(j))};
            const std::optional<EnvSample> s = env.sample(u);
            REQUIRE(s);
            const Vec2 xy = env.direction_to_xy(s->wi);
            CHECK(int(xy.x) == i);
            CHECK(int(xy.y) == j);
            const double sin_theta =
                std::sqrt(double(s->wi.x) * s->wi.x + double(s->wi.z) * s->wi.z);
            const double density = pmf * kMapW * kMapH / (2.0 * kPiD * kPiD * sin_theta);
            CHECK(double(s->pdf) == Approx(density).epsilon(kDensityRelTol));
            CHECK(s->pdf == env.pdf(s->wi));
        }
    }
    CHECK(total == 1.0);
    // The sun and the eight texels whose bilinear lookup reaches it take nearly every sample.
    double sun = 0.0;
    for (int j = 1; j <= 3; ++j)
        for (int i = 4; i <= 6; ++i)
            sun += env.texel_pmf(i, j);
    CHECK(sun > 0.999);
}

TEST_CASE("mesh light: every triangle is chosen with exactly the probability pdf_li divides by",
          "[light][quick]") {
    const Scene scene = skewed_mesh_scene();
    const Light& light = scene.lights.at(0);
    const Mesh& mesh = scene.meshes.at(light.geom_id);
    REQUIRE(light.tri_choice.size() == mesh.triangle_count());
    const std::vector<std::uint64_t> count = counts_of(light.tri_choice);
    const Vec3 ref(3.f, 2.f, 5.f);
    for (std::size_t k = 0; k < mesh.triangle_count(); ++k) {
        const double realised = std::ldexp(double(count[k]), -32);
        const double pmf = double(light.tri_choice.pmf(k));
        INFO("triangle " << k << ": realised " << realised << ", pmf " << pmf);
        CHECK(std::abs(realised - pmf) <= kExactTol);
        CHECK(realised == pmf);
        CHECK(count[k] > 0); // the near-zero triangle too
        // The density the estimator divides by on triangle k is pmf(k) / area(k).
        const Vec3& p0 = mesh.positions[mesh.indices[3 * k]];
        const Vec3& p1 = mesh.positions[mesh.indices[3 * k + 1]];
        const Vec3& p2 = mesh.positions[mesh.indices[3 * k + 2]];
        const double area = 0.5 * double(length(cross(p1 - p0, p2 - p0)));
        CHECK(double(light.tri_area_per_pmf[k]) == Approx(area / pmf).epsilon(kDensityRelTol));
        const Bits2 u{run_middle(count, k), 0x40000000u};
        const std::optional<LightSample> s = sample_li(scene, light, ref, u);
        REQUIRE(s);
        CHECK(s->prim == k);
        // Solid-angle density = (pmf / area) dist^2 / |cos|.
        const double dist2 = double(length_squared(s->p_light - ref));
        const double cos = std::abs(double(dot(s->n_light, s->wi)));
        CHECK(double(s->pdf) == Approx(pmf / area * dist2 / cos).epsilon(kDensityRelTol));
        CHECK(pdf_li(scene, light, ref, s->wi, s->p_light, s->n_light, s->prim) == s->pdf);
    }
    CHECK(light.tri_choice.pmf(1) > 0.99f);
}
