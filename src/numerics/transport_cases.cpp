// Stiff light transport cases of the stress suite (include/candela/numerics/transport_cases.h).
// Every case builds a small scene in code whose answer is known in closed form (or bounded by an
// independent computation), renders it with fixed seeds and reports a z-test against it.
#include "candela/numerics/transport_cases.h"

#include "candela/bsdf/bsdf.h"
#include "candela/sampling/rng.h"
#include "transport_support.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>

namespace candela::numerics {

using namespace transport;

namespace {

/// Relative float rounding a whole path may accumulate: a path multiplies a few dozen float
/// factors (BSDF weights, 1/eta^2 and eta^2, MIS weights), each rounded to 6e-8 relative, so
/// exact-in-theory values (a lossless enclosure, an index-matched slab) may be off by ~1e-6;
/// 1e-5 leaves a margin for long paths.
constexpr double kFloatRel = 1e-5;

/// A rendered estimate must be informative: its standard error at most this fraction of the
/// expected value, so a wrong answer (a few per cent off) cannot hide in the noise.
constexpr double kInformative = 0.03;

/// Quick runs use the spp as given; full runs four times as many samples.
int scaled(int spp, StressSize size) {
    return size == StressSize::Full ? 4 * spp : spp;
}

/// A floor of material `mat` under a uniform sky of radiance 1, seen at angle theta_o (degrees
/// from the normal) by a camera with a tiny field of view aimed at the origin.
Scene floor_under_sky(const Material& mat, float theta_o_deg) {
    Scene scene;
    add_floor(scene, 1000.f, 0.f, add_material(scene, mat));
    add_sky(scene, 1.f);
    const float t = deg_to_rad(theta_o_deg);
    const Vec3 pos(std::sin(t), std::cos(t), 0.f);
    const Vec3 up = theta_o_deg == 0.f ? Vec3(0, 0, -1) : Vec3(0, 1, 0);
    scene.camera = look_at(pos, Vec3(0.f), up, 1e-3f);
    SceneEditor(scene).finalize();
    return scene;
}

/// Luminance of the per-channel smooth-conductor Fresnel term at cos_i.
double conductor_fresnel_lum(float cos_i, const Rgb& eta, const Rgb& k) {
    return luminance(fresnel_conductor(cos_i, eta, k));
}

// -----------------------------------------------------------------------------------------------
// Furnace
// -----------------------------------------------------------------------------------------------

/// Expected closest-hit queries per camera sample in the furnace with roulette from depth 3:
/// three vertices are always traced. Survival is √(throughput): the third vertex has
/// throughput a^3 and survives with a^(3/2), leaving a^(3/2); the next has a^(5/2) and survives
/// with a^(5/4), and so on, so the j-th test survives with a^(1 + 2^-j) and the number Y of
/// further vertices has P(Y >= k) = a^(k + 1 - 2^-k). Returns 3 + E[Y] and writes Var[Y], from
/// E[Y] = sum P(Y >= k) and E[Y^2] = sum (2k - 1) P(Y >= k).
double furnace_rays_mean(double a, double* variance) {
    // The series' terms fall as a^k; stop when one adds less than this share of the sum
    // (far below the z-test's resolution, ~1e-3 relative).
    constexpr double kSeriesTail = 1e-15;
    double ey = 0.0, ey2 = 0.0;
    for (int k = 1;; ++k) {
        const double p = std::pow(a, double(k) + 1.0 - std::ldexp(1.0, -k));
        ey += p;
        ey2 += (2.0 * k - 1.0) * p;
        if (p * (2.0 * k - 1.0) < kSeriesTail * ey2) break;
    }
    *variance = ey2 - ey * ey;
    return 3.0 + ey;
}

} // namespace

std::vector<StressResult> furnace_cases(StressSize size) {
    std::vector<StressResult> out;
    const float Le = 1.f;
    for (float albedo : {0.99f, 0.999f}) {
        const Scene scene = make_furnace_scene(albedo, Le);
        // A path averages 1/(1 - a) vertices: fewer pixels for the stiffer albedo keep both
        // cases near a second. The per-path estimate is Le times a geometric vertex count, so
        // its relative standard deviation is ~1 and 4096 paths give ~1.6 % standard error.
        const int px = albedo > 0.995f ? 8 : 16;
        RenderSettings s = case_settings(px, scaled(64, size), 11);
        s.max_depth = 1000000; // the cap never binds: roulette ends the paths
        const Measured m = render_measure(scene, s);
        const double a = double(albedo);
        const double expected = Le / (1.0 - a);
        out.push_back(z_row(kStiffTransportGroup, fmt::format("furnace, albedo {:g}", a),
                            method_of(s, "path NEE+MIS, roulette from depth 3"),
                            fmt::format("Le/(1-a) = {:g}", expected), expected, m, kInformative));

        // Roulette decides the path length: its mean must match the survival rule.
        double var_rays = 0.0;
        const double rays_expected = furnace_rays_mean(a, &var_rays);
        const double n = double(m.samples);
        const double rays_mean = double(m.rays) / n;
        const double rays_se = std::sqrt(var_rays / n);
        const double z = (rays_mean - rays_expected) / rays_se;
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = fmt::format("furnace, albedo {:g}: path length under roulette", a);
        r.method = method_of(s, "rays per camera sample");
        r.expected =
            fmt::format("3 + sum a^(k+1-2^-k) = {:.5g}, |z| < {:.0f}", rays_expected, kZBound);
        r.measured =
            fmt::format("{:.5g} +- {:.2g} (z = {:.2f}), {:.2f} s", rays_mean, rays_se, z, m.seconds);
        r.pass = std::abs(z) < kZBound;
        out.push_back(r);
    }
    {
        // Roulette off, depth cap D: the estimate is the truncated series, exactly.
        const float albedo = 0.99f;
        const int D = 200;
        const Scene scene = make_furnace_scene(albedo, Le);
        RenderSettings s = case_settings(8, scaled(64, size), 12);
        s.max_depth = D;
        s.rr_min_depth = D + 1;
        const Measured m = render_measure(scene, s);
        const double a = double(albedo);
        const double expected = Le * (1.0 - std::pow(a, D + 1)) / (1.0 - a);
        // Without roulette the estimator is nearly noise-free (inside a sphere, light sampling
        // of the sphere gives f L cos cos' A / d^2 = a Le exactly), so float rounding is what is
        // left: the throughput of a D-bounce path is a product of D float weights, two
        // roundings (2^-24 each) per bounce.
        const double rounding = 2.0 * (D + 1) * std::ldexp(1.0, -24) * expected;
        out.push_back(band_row(kStiffTransportGroup,
                               fmt::format("furnace, albedo {:g}, no roulette", a),
                               method_of(s, fmt::format("path NEE+MIS, depth cap {}", D).c_str()),
                               fmt::format("Le (1-a^{})/(1-a) = {:.6g} +- {:.1g} float rounding",
                                            D + 1, expected, rounding),
                               expected - rounding, expected + rounding, m, 0.005));
    }
    return out;
}

// -----------------------------------------------------------------------------------------------
// Near-delta microfacet
// -----------------------------------------------------------------------------------------------

namespace {

/// A coloured conductor (gold-like indices), so the Fresnel term varies with angle.
const Rgb kConductorEta(0.2f, 0.9f, 1.3f), kConductorK(3.9f, 2.4f, 2.2f);

/// Bound on |albedo(alpha) - F(cos theta_o)| for a near-delta Beckmann conductor. The
/// importance-sampling weight is F(wo.h) G (wo.h) / (cos theta_o cos theta_h); expanding in the
/// microfacet tilt delta (E[tan^2 theta_h] = alpha^2, odd terms vanish by symmetry in phi) the
/// mean departs from F(cos theta_o) by at most alpha^2 (|F''|/4 + |F'| tan theta_o / 2 +
/// tan^2 theta_o) plus 1 - G, with derivatives in the tilt angle. Twice that, plus the mass of
/// tilts the expansion misses, is returned (per channel, the largest).
double near_delta_bias_bound(float alpha, float theta_o) {
    const double h = 1e-3; // finite-difference step in radians; F is smooth at that scale
    double bound = 0.0;
    for (int c = 0; c < 3; ++c) {
        auto F = [&](double t) {
            return double(fresnel_conductor(float(std::cos(t)), kConductorEta[c], kConductorK[c]));
        };
        const double t0 = std::max(double(theta_o), h);
        const double d1 = (F(t0 + h) - F(t0 - h)) / (2 * h);
        const double d2 = (F(t0 + h) - 2 * F(t0) + F(t0 - h)) / (h * h);
        const double tan_o = std::tan(double(theta_o));
        const double a2 = double(alpha) * alpha;
        bound = std::max(bound, a2 * (std::abs(d2) / 4 + std::abs(d1) * tan_o / 2 + tan_o * tan_o));
    }
    const Vec3 wo(std::sin(theta_o), 0.f, std::cos(theta_o));
    const double one_minus_g = 1.0 - double(beckmann_g(wo, wo, alpha));
    return 2.0 * (bound + one_minus_g);
}

} // namespace

std::vector<StressResult> near_delta_microfacet_cases(StressSize size) {
    std::vector<StressResult> out;
    const int n = size == StressSize::Full ? 1000000 : 100000;
    for (float alpha : {1e-4f, 1e-3f}) {
        Material m = conductor_material(alpha, kConductorEta, kConductorK);
        // BSDF level: directional albedo by the BSDF's own sampling at three angles.
        for (float theta_deg : {0.f, 45.f, 80.f}) {
            const float t = deg_to_rad(theta_deg);
            const Vec3 wo(std::sin(t), 0.f, std::cos(t));
            Pcg32 rng(41, std::uint64_t(theta_deg) + 1);
            double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
            std::uint64_t nonfinite = 0;
            for (int i = 0; i < n; ++i) {
                const Vec2 u(rng.next_float(), rng.next_float());
                auto bs = bsdf_sample(m, wo, u, rng.next_float());
                if (!bs) continue;
                const Rgb w = bs->f * (std::abs(bs->wi.z) / bs->pdf);
                if (!is_finite(w) || !std::isfinite(bs->pdf)) {
                    ++nonfinite;
                    continue;
                }
                for (int c = 0; c < 3; ++c) {
                    sum[c] += w[c];
                    sum2[c] += double(w[c]) * w[c];
                }
            }
            const double bias = near_delta_bias_bound(alpha, t);
            double worst_z = 0.0, worst_err = 0.0;
            for (int c = 0; c < 3; ++c) {
                const double mean = sum[c] / n;
                const double se = std::sqrt(std::max(0.0, sum2[c] / n - mean * mean) / n);
                const double F = fresnel_conductor(std::cos(t), kConductorEta[c], kConductorK[c]);
                const double excess = std::max(0.0, std::abs(mean - F) - bias - kFloatRel * F);
                worst_z = std::max(worst_z, se > 0 ? excess / se : (excess > 0 ? INFINITY : 0.0));
                worst_err = std::max(worst_err, std::abs(mean - F));
            }
            StressResult r;
            r.group = kStiffTransportGroup;
            r.name =
                fmt::format("microfacet alpha {:g}, theta_o {:g} deg: albedo -> smooth conductor F",
                             double(alpha), double(theta_deg));
            r.method = fmt::format("BSDF sampling, {} samples, 3 channels", n);
            r.expected =
                fmt::format("|albedo - F(cos theta_o)| <= {:.2g} (O(alpha^2) bound) + {:.0f} se, "
                             "0 non-finite",
                             bias, kZBound);
            r.measured = fmt::format("max |albedo - F| = {:.2g} (excess z = {:.2f}), {} non-finite",
                                      worst_err, worst_z, nonfinite);
            r.pass = worst_z < kZBound && nonfinite == 0;
            out.push_back(r);
        }
        // Render level: a near-mirror floor under a uniform sky reflects F(cos theta_o) L.
        for (float theta_deg : {0.f, 60.f}) {
            const float t = deg_to_rad(theta_deg);
            const Scene scene = floor_under_sky(m, theta_deg);
            RenderSettings s = case_settings(4, scaled(64, size), 13);
            s.max_depth = 4;
            const Measured meas = render_measure(scene, s);
            const double F = conductor_fresnel_lum(std::cos(t), kConductorEta, kConductorK);
            const double bias = near_delta_bias_bound(alpha, t) + kFloatRel * F;
            out.push_back(
                band_row(kStiffTransportGroup,
                         fmt::format("microfacet floor alpha {:g} under sky, theta_o {:g} deg",
                                      double(alpha), double(theta_deg)),
                         method_of(s, "path NEE+MIS"),
                         fmt::format("F(cos theta_o) L = {:.6g} +- {:.2g}", F, bias), F - bias,
                         F + bias, meas, kInformative));
        }
    }
    return out;
}

// -----------------------------------------------------------------------------------------------
// Dielectrics
// -----------------------------------------------------------------------------------------------

namespace {

/// Cosine-weighted hemispherical average of the Fresnel reflectance of one interface,
/// integral of F(mu) 2 mu dmu (midpoint rule; F is smooth except within ~sqrt(eta - 1) of
/// grazing, which 2^20 intervals resolve).
double mean_fresnel(float ior) {
    const int N = 1 << 20;
    double sum = 0.0;
    for (int i = 0; i < N; ++i) {
        const double mu = (i + 0.5) / N;
        sum += double(fresnel_dielectric(float(mu), ior)) * 2.0 * mu;
    }
    return sum / N;
}

} // namespace

std::vector<StressResult> dielectric_cases(StressSize size) {
    std::vector<StressResult> out;
    const float Le = 1.f;
    // Lossless glass in a uniformly glowing enclosure: every path that escapes the glass carries
    // exactly Le (reflection weight 1, transmission weights 1/eta^2 and eta^2 cancel), so the
    // glass is invisible and every pixel is Le.
    for (float ior : {1.0001f, 3.5f})
        for (bool cube : {false, true}) {
            Scene scene;
            add_sphere(scene, Vec3(0.f), 10.f, add_material(scene, emission_material(Le)));
            const std::uint32_t glass = add_material(scene, glass_material(ior));
            if (cube)
                add_box(scene, Vec3(-1.f), Vec3(1.f), glass);
            else
                add_sphere(scene, Vec3(0.f), 1.f, glass);
            scene.camera = look_at(Vec3(2.5f, 2.f, 3.f), Vec3(0.f), Vec3(0, 1, 0), 50.f);
            SceneEditor(scene).finalize();
            RenderSettings s = case_settings(16, scaled(16, size), 14);
            s.max_depth = 100000; // paths end by escaping the glass, never by the cap
            const Measured m = render_measure(scene, s, Le);
            StressResult r;
            r.group = kStiffTransportGroup;
            r.name = fmt::format("lossless glass {} IOR {:g} in a glowing enclosure",
                                  cube ? "cube" : "sphere", double(ior));
            r.method = method_of(s, "path");
            r.expected =
                fmt::format("every pixel = Le (max rel. dev. <= {:.0e}), 0 non-finite", kFloatRel);
            r.measured = fmt::format("mean {:.7g}, max rel. dev. {:.2g}, {:.1f} rays/sample, {} non-finite", m.mean,
                m.max_rel_dev, double(m.rays) / double(m.samples), m.dropped);
            r.pass = m.max_rel_dev <= kFloatRel && m.dropped == 0 && m.nonfinite_pixels == 0;
            out.push_back(r);
        }

    // A nearly index-matched slab over a diffuse floor under a uniform sky: shadow rays are
    // blocked by the slab, so the floor is lit only through specular chains; the answer must
    // still be albedo * L, less at most the slab's Fresnel loss.
    {
        const float ior = 1.0001f, albedo = 0.5f;
        const double rbar = mean_fresnel(ior);
        const double F0 = fresnel_dielectric(1.f, ior);
        for (bool slab : {false, true}) {
            Scene scene;
            add_floor(scene, 100.f, 0.f, add_material(scene, diffuse_material(albedo)));
            if (slab)
                add_box(scene, Vec3(-100.f, 0.2f, -100.f), Vec3(100.f, 0.4f, 100.f),
                        add_material(scene, glass_material(ior)));
            add_sky(scene, 1.f);
            scene.camera = look_at(Vec3(0, 1, 0), Vec3(0.f), Vec3(0, 0, -1), 1e-3f);
            SceneEditor(scene).finalize();
            RenderSettings s = case_settings(4, scaled(256, size), 15);
            s.max_depth = 64;
            const Measured m = render_measure(scene, s);
            const double full = albedo * 1.0;
            // Floor: each slab crossing transmits at least 1 - 2F of the cosine-weighted
            // light; the camera sees the floor through the slab (1 - 2 F0) plus the sky
            // reflected by it (at most 2 F0 L).
            const double lo = slab ? full * (1.0 - 2.0 * rbar) * (1.0 - 2.0 * F0) : full;
            const double hi = slab ? full + 2.0 * F0 : full;
            const double pad = kFloatRel * full;
            out.push_back(band_row(
                kStiffTransportGroup,
                slab ? fmt::format("diffuse floor under a glass slab IOR {:g}, sky", double(ior))
                     : std::string("diffuse floor, no slab, sky (reference)"),
                method_of(s, "path NEE+MIS"),
                slab ? fmt::format("albedo L = {:g}, less <= {:.2g} Fresnel loss", full, full - lo)
                     : fmt::format("albedo L = {:g}", full),
                lo - pad, hi + pad, m, kInformative));
        }
    }

    // Total internal reflection trap: an emitting sphere inside a glass cube of IOR 3.5 (critical
    // angle 16.6 deg): light leaving the emitter outside the six escape cones would circulate
    // forever, but camera paths enter inside an escape cone and, by reciprocity, can always
    // leave. Expected: the pixel straight on at a face sees (1 - F(0)) Le / n^2; no pixel
    // exceeds Le / n^2 (lossless glass cannot raise radiance L / n^2); nothing non-finite.
    {
        const float ior = 3.5f;
        Scene scene;
        add_box(scene, Vec3(-1.f), Vec3(1.f), add_material(scene, glass_material(ior)));
        add_sphere(scene, Vec3(0.f), 0.5f, add_material(scene, emission_material(Le)));
        const double n2 = double(ior) * ior;
        const double F0 = fresnel_dielectric(1.f, ior);
        {
            scene.camera = look_at(Vec3(0, 0, 5), Vec3(0.f), Vec3(0, 1, 0), 1e-3f);
            SceneEditor(scene).finalize();
            RenderSettings s = case_settings(4, scaled(256, size), 16);
            s.max_depth = 100000;
            const Measured m = render_measure(scene, s);
            const double expected = (1.0 - F0) * Le / n2;
            out.push_back(z_row(
                kStiffTransportGroup, "TIR trap: light in a glass cube IOR 3.5, face-on pixel",
                method_of(s, "path"), fmt::format("(1 - F(0)) Le / n^2 = {:.6g}", expected),
                expected, m, kInformative));
        }
        {
            scene.camera = look_at(Vec3(3.f, 2.5f, 4.f), Vec3(0.f), Vec3(0, 1, 0), 45.f);
            SceneEditor(scene).finalize();
            RenderSettings s = case_settings(16, scaled(16, size), 17);
            s.max_depth = 100000;
            const Measured m = render_measure(scene, s);
            const double bound = Le / n2 * (1.0 + kFloatRel);
            StressResult r;
            r.group = kStiffTransportGroup;
            r.name = "TIR trap: light in a glass cube IOR 3.5, whole image";
            r.method = method_of(s, "path");
            r.expected = fmt::format("every pixel <= Le/n^2 = {:.5g}, 0 non-finite", Le / n2);
            r.measured =
                fmt::format("max pixel {:.5g}, mean {:.4g}, {:.1f} rays/sample, {} non-finite, {:.2f} s",
                             m.max_pixel, m.mean, double(m.rays) / double(m.samples),
                             m.dropped, m.seconds);
            r.pass = m.max_pixel <= bound && m.dropped == 0 && m.nonfinite_pixels == 0;
            out.push_back(r);
        }
    }
    return out;
}

// -----------------------------------------------------------------------------------------------
// Conductor with k = 0
// -----------------------------------------------------------------------------------------------

namespace {

/// Directional albedo integral of f(wo, wi) cos(theta_i) over the hemisphere by the midpoint
/// rule on N x 4N cells of (cos theta_i, phi), in double.
double albedo_quadrature(const Material& m, const Vec3& wo, int N) {
    double sum = 0.0;
    const int M = 4 * N;
    for (int i = 0; i < N; ++i) {
        const double mu = (i + 0.5) / N;
        const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
        for (int j = 0; j < M; ++j) {
            const double phi = 2.0 * kPi * (j + 0.5) / M;
            const Vec3 wi(float(s * std::cos(phi)), float(s * std::sin(phi)), float(mu));
            sum += luminance(bsdf_f(m, wo, wi)) * mu;
        }
    }
    return sum * (2.0 * kPi) / (double(N) * M);
}

} // namespace

std::vector<StressResult> conductor_k0_cases(StressSize size) {
    std::vector<StressResult> out;
    // Fresnel level: with k = 0 the conductor formula must reduce to the dielectric one,
    // including eta < 1 (total reflection beyond the critical angle) and eta = 1 (F = 0).
    {
        // Agreement of two different float evaluations of the same function: each has a few
        // ulps of error amplified by cancellation near grazing, where dF/dcos is largest.
        constexpr double kFresnelAgree = 1e-4;
        double worst = 0.0;
        std::uint64_t nonfinite = 0, calls = 0;
        for (float eta : {0.5f, 0.9999f, 1.f, 1.0001f, 1.5f, 3.5f})
            for (int i = 0; i <= 4096; ++i) {
                const float c = i == 1 ? 1e-7f : float(i) / 4096.f;
                const float fc = fresnel_conductor(c, eta, 0.f);
                const float fd = fresnel_dielectric(c, eta);
                ++calls;
                if (!std::isfinite(fc) || !std::isfinite(fd)) {
                    ++nonfinite;
                    continue;
                }
                worst = std::max(worst, double(std::abs(fc - fd)));
            }
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = "conductor k = 0: Fresnel equals the dielectric term";
        r.method = "eta in {0.5, 0.9999, 1, 1.0001, 1.5, 3.5}, 4097 cosines in [0, 1]";
        r.expected = fmt::format("max |F_cond - F_diel| <= {:.0e}, 0 non-finite", kFresnelAgree);
        r.measured = fmt::format("max diff {:.2g}, {} non-finite of {}", worst,
                                  nonfinite, calls);
        r.pass = worst <= kFresnelAgree && nonfinite == 0;
        out.push_back(r);
    }
    // Render level: a rough k = 0 conductor floor (eta 1.5) under a uniform sky reflects its
    // directional albedo, computed independently by quadrature of f cos.
    {
        const float theta_deg = 45.f, t = deg_to_rad(theta_deg);
        const Material m = conductor_material(0.3f, Rgb(1.5f), Rgb(0.f));
        const Vec3 wo(std::sin(t), 0.f, std::cos(t));
        const double q = albedo_quadrature(m, wo, 512);
        const double q_half = albedo_quadrature(m, wo, 256);
        const double qerr = 2.0 * std::abs(q - q_half) + kFloatRel * q;
        const Scene scene = floor_under_sky(m, theta_deg);
        RenderSettings s = case_settings(4, scaled(256, size), 18);
        s.max_depth = 4;
        const Measured meas = render_measure(scene, s);
        out.push_back(band_row(kStiffTransportGroup,
                               "conductor k = 0, eta 1.5, alpha 0.3 floor under sky, 45 deg",
                               method_of(s, "path NEE+MIS"),
                               fmt::format("quadrature albedo L = {:.6g} +- {:.1g}", q, qerr),
                               q - qerr, q + qerr, meas, kInformative));
    }
    // eta = 1, k = 0: index-matched to vacuum, reflects nothing.
    {
        // The exact formula leaves rounding residue of a few ulps of 1 (relative to a perfect
        // conductor's response of ~1).
        constexpr double kMatchedResidual = 1e-5;
        const Material m = conductor_material(0.3f, Rgb(1.f), Rgb(0.f));
        const Scene scene = floor_under_sky(m, 45.f);
        RenderSettings s = case_settings(4, scaled(64, size), 19);
        s.max_depth = 4;
        const Measured meas = render_measure(scene, s);
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = "conductor k = 0, eta 1 (index-matched) floor under sky";
        r.method = method_of(s, "path NEE+MIS");
        r.expected = fmt::format("black: every pixel <= {:.0e} L, 0 non-finite", kMatchedResidual);
        r.measured = fmt::format("max pixel {:.2g}, {} non-finite", meas.max_pixel,
                                  meas.dropped);
        r.pass =
            meas.max_pixel <= kMatchedResidual && meas.dropped == 0 && meas.nonfinite_pixels == 0;
        out.push_back(r);
    }
    return out;
}

// -----------------------------------------------------------------------------------------------
// A tiny, very bright light beside a dim large one
// -----------------------------------------------------------------------------------------------

namespace {

/// Irradiance at the origin (normal +y) from a uniform polygonal luminaire of radiance L
/// (Lambert's formula): E = L/2 sum_i angle(v_i, v_i+1) dot(n, unit(v_i x v_i+1)), in double.
double polygon_irradiance(const std::vector<Vec3d>& v, double L) {
    double sum = 0.0;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const Vec3d a = normalize(v[i]), b = normalize(v[(i + 1) % v.size()]);
        const Vec3d c = cross(a, b);
        // atan2 of |a x b| and a.b keeps precision for the tiny angles of a tiny light.
        const double angle = std::atan2(length(c), dot(a, b));
        sum += angle * c.y / length(c);
    }
    return 0.5 * L * std::abs(sum);
}

std::vector<Vec3d> rect_corners(const Vec3& c, const Vec3& dx, const Vec3& dy) {
    const Vec3d C(c), X(dx * 0.5f), Y(dy * 0.5f);
    return {C - X - Y, C + X - Y, C + X + Y, C - X + Y};
}

} // namespace

std::vector<StressResult> tiny_light_cases(StressSize size) {
    std::vector<StressResult> out;
    const float albedo = 0.5f;
    const float tiny_L = 1e8f, large_L = 1.f;
    const Vec3 tiny_c(0.3f, 1.f, 0.1f), tiny_dx(1e-3f, 0.f, 0.f), tiny_dy(0.f, 0.f, 1e-3f);
    const Vec3 large_c(-0.5f, 1.5f, 0.2f), large_dx(2.f, 0.f, 0.f), large_dy(0.f, 0.f, 2.f);
    Scene scene;
    add_floor(scene, 10.f, 0.f, add_material(scene, diffuse_material(albedo)));
    add_rect_light(scene, tiny_c, tiny_dx, tiny_dy, Rgb(tiny_L));
    add_rect_light(scene, large_c, large_dx, large_dy, Rgb(large_L));
    scene.camera = look_at(Vec3(0, 0.5f, 0), Vec3(0.f), Vec3(0, 0, -1), 1e-3f);
    SceneEditor(scene).finalize();
    const double E_tiny = polygon_irradiance(rect_corners(tiny_c, tiny_dx, tiny_dy), tiny_L);
    const double E_large = polygon_irradiance(rect_corners(large_c, large_dx, large_dy), large_L);
    const double expected = albedo / double(kPi) * (E_tiny + E_large);
    const std::string desc = fmt::format("albedo/pi (E_tiny + E_large) = {:.6g} (E {:.4g} + {:.4g})",
                                          expected, E_tiny, E_large);
    const char* name = "1e-6-area light of radiance 1e8 beside a 4-area light of radiance 1";
    {
        RenderSettings s = case_settings(4, scaled(256, size), 20);
        s.integrator = IntegratorKind::Direct;
        s.max_depth = 1;
        const Measured m = render_measure(scene, s);
        out.push_back(z_row(kStiffTransportGroup, name,
                            method_of(s, "direct, light sampling of every light"), desc, expected,
                            m, kInformative));
    }
    {
        RenderSettings s = case_settings(4, scaled(256, size), 21);
        s.max_depth = 2;
        const Measured m = render_measure(scene, s);
        out.push_back(z_row(kStiffTransportGroup, name,
                            method_of(s, "path, one light by power, MIS"), desc, expected, m,
                            kInformative));
    }
    {
        // Uniform hemisphere sampling hits the tiny light with probability ~ its solid angle /
        // 2 pi ~ 1e-7 per sample: it misses it, and the estimate is that of the large light
        // alone. A limit, not a requirement.
        RenderSettings s = case_settings(4, scaled(256, size), 22);
        s.integrator = IntegratorKind::Direct;
        s.hemisphere = true;
        s.max_depth = 1;
        const Measured m = render_measure(scene, s);
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = name;
        r.method = method_of(s, "direct, uniform hemisphere sampling (-H)");
        r.expected = desc;
        r.measured =
            fmt::format("{:.4g} +- {:.2g} (rel. err {:+.1f}%), {} non-finite", m.mean, m.std_err,
                         100.0 * (m.mean - expected) / expected, m.dropped);
        r.pass = m.dropped == 0;
        r.reported_only = true;
        out.push_back(r);
    }
    return out;
}

// -----------------------------------------------------------------------------------------------
// Camera inside closed objects
// -----------------------------------------------------------------------------------------------

std::vector<StressResult> camera_inside_cases(StressSize size) {
    std::vector<StressResult> out;
    // Diffuse enclosures with every light outside: nothing can reach the camera. Two-sided
    // diffuse surfaces must not pass light from the outside to the inside, and no ray may leak
    // through the geometry.
    struct Variant {
        bool cube;
        AccelKind accel;
        TriangleTest test;
        /// Rows that only report. None now: the watertight test used to reject hits closer
        /// than its float bound on t (pbrt-v4 6.8.7), so a ray spawned a few 1e-6 from a
        /// concave edge escaped through the neighbouring face (1 in 200,000); it now decides
        /// such hits in double (accel/triangle.h).
        bool reported_only;
    };
    const Variant variants[] = {{false, AccelKind::Embree, TriangleTest::MollerTrumbore, false},
                                {true, AccelKind::Embree, TriangleTest::MollerTrumbore, false},
                                {true, AccelKind::Builtin, TriangleTest::MollerTrumbore, false},
                                {true, AccelKind::Builtin, TriangleTest::Watertight, false}};
    for (const Variant& v : variants) {
        Scene scene;
        const std::uint32_t mat = add_material(scene, diffuse_material(0.8f));
        if (v.cube)
            add_box(scene, Vec3(-1.f), Vec3(1.f), mat);
        else
            add_sphere(scene, Vec3(0.f), 1.f, mat);
        add_sky(scene, 1.f);
        add_rect_light(scene, Vec3(0, 3, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), Rgb(10.f));
        Light point;
        point.kind = LightKind::Point;
        point.L = Rgb(10.f);
        point.p = Vec3(2.f, 2.f, 2.f);
        SceneEditor(scene).add_light(point);
        scene.camera.pos = Vec3(0.1f, -0.2f, 0.3f);
        scene.camera.hfov_deg = 90.f;
        scene.camera.znear = 0.f;
        SceneEditor(scene).finalize();
        RenderSettings s = case_settings(16, scaled(16, size), 23);
        s.accel.kind = v.accel;
        s.accel.triangle = v.test;
        s.max_depth = 64;
        const Measured m = render_measure(scene, s);
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = fmt::format("camera inside a closed diffuse {}, lights outside",
                              v.cube ? "cube (12 triangles)" : "sphere");
        r.method = method_of(s, v.accel == AccelKind::Embree
                                    ? "path NEE+MIS"
                                    : (v.test == TriangleTest::Watertight
                                           ? "path NEE+MIS, watertight triangle test"
                                           : "path NEE+MIS, Moller-Trumbore triangle test"));
        r.expected = "exactly black, 0 non-finite";
        r.measured = fmt::format("max pixel {:.3g}, mean {:.3g}, {} non-finite", m.max_pixel, m.mean,
                                  m.dropped);
        r.pass = m.max_pixel == 0.0 && m.dropped == 0 && m.nonfinite_pixels == 0;
        r.reported_only = v.reported_only;
        out.push_back(r);
    }
    // Emitting enclosures: a closed emitter that does not reflect is seen as exactly its Le.
    const float Le = 2.f;
    for (bool cube : {false, true}) {
        Scene scene;
        const std::uint32_t mat = add_material(scene, emission_material(Le));
        if (cube)
            add_box(scene, Vec3(-1.f), Vec3(1.f), mat);
        else
            add_sphere(scene, Vec3(0.f), 1.f, mat);
        scene.camera.pos = Vec3(0.1f, -0.2f, 0.3f);
        scene.camera.hfov_deg = 90.f;
        scene.camera.znear = 0.f;
        SceneEditor(scene).finalize();
        RenderSettings s = case_settings(16, scaled(16, size), 24);
        const Measured m = render_measure(scene, s, Le);
        StressResult r;
        r.group = kStiffTransportGroup;
        r.name = fmt::format("camera inside an emitting {} (Le = {:g})", cube ? "cube" : "sphere",
                              double(Le));
        r.method = method_of(s, "path NEE+MIS");
        r.expected =
            fmt::format("every pixel = Le (max rel. dev. <= {:.0e}), 0 non-finite", kFloatRel);
        r.measured = fmt::format("mean {:.7g}, max rel. dev. {:.2g}, {} non-finite", m.mean,
                                  m.max_rel_dev, m.dropped);
        r.pass = m.max_rel_dev <= kFloatRel && m.dropped == 0 && m.nonfinite_pixels == 0;
        out.push_back(r);
    }
    return out;
}

std::vector<StressResult> run_transport_cases(StressSize size) {
    std::vector<StressResult> all;
    auto append = [&all](std::vector<StressResult> v) {
        for (StressResult& r : v)
            all.push_back(std::move(r));
    };
    append(furnace_cases(size));
    append(near_delta_microfacet_cases(size));
    append(dielectric_cases(size));
    append(conductor_k0_cases(size));
    append(tiny_light_cases(size));
    append(camera_inside_cases(size));
    append(guard_cases());
    return all;
}

} // namespace candela::numerics
