// Tests of the lat-long environment map: mapping conventions, support of the sampling density,
// unbiasedness of importance sampling, and loading EXR maps.
#include "candela/io/envmap_file.h"
#include "candela/io/image_io.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

using namespace candela;

namespace {

/// Float round-off allowed in a direction computed through acos/atan2 and back.
constexpr float kDirTol = 1e-5f;
/// z-score bound for Monte Carlo estimates with fixed seeds (false failure ~6e-5).
constexpr double kZBound = 4.0;
/// Bilinear weights recomputed from a direction (acos/atan2 round trip) are off by ~1e-6.
constexpr float kBilinearTol = 1e-4f;
/// Largest relative standard error accepted from an estimator: guards against a degenerate
/// estimate (e.g. mostly zero samples) whose huge error bar would pass any z-test.
constexpr double kMaxRelStdErr = 0.01;

Vec3 uniform_sphere(Pcg32& rng) {
    const float u0 = rng.next_float();
    const float u1 = rng.next_float();
    return square_to_uniform_sphere(Vec2(u0, u1));
}

std::vector<Rgb> spot_map(int w, int h) {
    std::vector<Rgb> tex(static_cast<std::size_t>(w) * h, Rgb(0.f));
    tex[3 * w + 10] = Rgb(100.f, 80.f, 60.f); // bright spot
    tex[0 * w + 2] = Rgb(1.f, 2.f, 3.f);      // at the zenith row
    tex[7 * w + (w - 1)] = Rgb(0.5f);         // bottom row, last column (wraps to column 0)
    for (int i = 0; i < w; ++i)
        tex[5 * w + i] += Rgb(0.05f); // a faint band
    return tex;
}

} // namespace

TEST_CASE("envmap: direction <-> pixel mapping follows spec 2.6", "[light][quick]") {
    EnvMap env(8, 4, std::vector<Rgb>(32, Rgb(1.f)));
    auto near = [](const Vec3& a, const Vec3& b) { return length(a - b) < kDirTol; };
    // Row 0 is the zenith; across the width u = 0 -> -X, 1/4 -> +Z, 1/2 -> +X, 3/4 -> -Z.
    CHECK(near(env.xy_to_direction(3.f, 0.f), Vec3(0.f, 1.f, 0.f)));
    CHECK(near(env.xy_to_direction(0.f, 2.f), Vec3(-1.f, 0.f, 0.f)));
    CHECK(near(env.xy_to_direction(2.f, 2.f), Vec3(0.f, 0.f, 1.f)));
    CHECK(near(env.xy_to_direction(4.f, 2.f), Vec3(1.f, 0.f, 0.f)));
    CHECK(near(env.xy_to_direction(6.f, 2.f), Vec3(0.f, 0.f, -1.f)));
    Pcg32 rng(1, 2);
    for (int k = 0; k < 1000; ++k) {
        Vec3 d = uniform_sphere(rng);
        Vec2 xy = env.direction_to_xy(d);
        CHECK(near(env.xy_to_direction(xy.x, xy.y), d));
    }
}

TEST_CASE("envmap: bilinear lookup between texel centres, wrap in x, clamp in y",
          "[light][quick]") {
    const int w = 4, h = 2;
    std::vector<Rgb> tex(w * h, Rgb(0.f));
    tex[0] = Rgb(1.f); // (0, 0)
    tex[3] = Rgb(3.f); // (3, 0)
    tex[4] = Rgb(5.f); // (0, 1)
    EnvMap env(w, h, tex);
    // Centre of texel (0, 0).
    CHECK(env.eval(env.xy_to_direction(0.5f, 0.5f)).x == Approx(1.f));
    // Between the centres of (3, 0) and (0, 0) across the seam (x = 0 = w): average, and only
    // row 0 above its centre (vertical clamp).
    CHECK(env.eval(env.xy_to_direction(0.f, 0.25f)).x == Approx(2.f).epsilon(kBilinearTol));
    // Halfway between rows 0 and 1 at column 0's centre.
    CHECK(env.eval(env.xy_to_direction(0.5f, 1.f)).x == Approx(3.f).epsilon(kBilinearTol));
}

TEST_CASE("envmap: density is positive wherever radiance is, and integrates radiance "
          "without bias",
          "[light][stat]") {
    const int w = 32, h = 8;
    EnvMap env(w, h, spot_map(w, h));
    Pcg32 rng(5, 6);
    for (int k = 0; k < 100000; ++k) {
        Vec3 d = uniform_sphere(rng);
        if (!is_black(env.eval(d))) {
            if (!(env.pdf(d) > 0.f)) {
                FAIL("zero density where the radiance is " << env.eval(d).x << " at (" << d.x
                                                           << ", " << d.y << ", " << d.z << ")");
            }
        }
    }

    // Reference: integral of the bilinear radiance over the sphere by the midpoint rule on a
    // fine grid in pixel coordinates (d omega = sin(theta) (2 pi / w)(pi / h) dx dy).
    constexpr int kSub = 64; // subsamples per texel side
    double ref = 0.0;
    for (int y = 0; y < h * kSub; ++y)
        for (int x = 0; x < w * kSub; ++x) {
            float fx = (x + 0.5f) / kSub, fy = (y + 0.5f) / kSub;
            Vec3 d = env.xy_to_direction(fx, fy);
            double sin_theta = std::sin(kPi * fy / h);
            ref += env.eval(d).x * sin_theta;
        }
    ref *= (2.0 * kPi / w) * (kPi / h) / (kSub * kSub);
    // The midpoint rule on a piecewise-bilinear integrand times sin(theta) with 64x64
    // subsamples per texel errs by O(1/64^2) relative; 1e-3 bounds it.
    constexpr double kQuadRelTol = 1e-3;

    constexpr int kSamples = 400000;
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < kSamples; ++k) {
        auto s = env.sample(Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(s);
        CHECK(s->pdf == env.pdf(s->wi));
        double x = s->L.x / s->pdf;
        sum += x;
        sum2 += x * x;
    }
    double mean = sum / kSamples;
    double se = std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples);
    INFO("quadrature " << ref << ", importance-sampled estimate " << mean << " +- " << se);
    CHECK(std::abs(mean - ref) <= kZBound * se + kQuadRelTol * ref);
    CHECK(se < kMaxRelStdErr * ref);
}

TEST_CASE("envmap: all-black map samples uniformly in pixel space without NaNs", "[light][quick]") {
    EnvMap env(8, 4, std::vector<Rgb>(32, Rgb(0.f)));
    CHECK(env.luminance_integral() == 0.f);
    Pcg32 rng(3, 4);
    for (int k = 0; k < 1000; ++k) {
        auto s = env.sample(Vec2(rng.next_float(), rng.next_float()));
        REQUIRE(s);
        CHECK(std::isfinite(s->pdf));
        CHECK(is_black(s->L));
    }
}

TEST_CASE("envmap: rejects negative and non-finite texels", "[light][quick]") {
    std::vector<Rgb> tex(8, Rgb(1.f));
    tex[5] = Rgb(1.f, -1.f, 0.f);
    try {
        EnvMap env(4, 2, tex, "neg.exr");
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Io);
        CHECK_THAT(e.what(), Catch::Contains("neg.exr") && Catch::Contains("(1, 1)"));
    }
    tex[5] = Rgb(std::nanf(""));
    CHECK_THROWS_AS(EnvMap(4, 2, tex), Error);
    CHECK_THROWS_AS(EnvMap(3, 2, std::vector<Rgb>(8, Rgb(1.f))), Error);
}

TEST_CASE("envmap: EXR write/load round trip with channels matched by name", "[light][quick]") {
    namespace fs = std::filesystem;
    // Per-process directory: several test runs may share the machine.
    const fs::path dir =
        fs::temp_directory_path() / ("candela_envmap_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string path = (dir / "tiny.exr").string();
    const int w = 4, h = 3;
    // Written as A, B, G, R so that reading by channel index would swap colours.
    std::vector<float> px(static_cast<std::size_t>(w) * h * 4);
    for (int k = 0; k < w * h; ++k) {
        px[4 * k + 0] = 1.f;              // A
        px[4 * k + 1] = 0.25f * k + 0.5f; // B
        px[4 * k + 2] = 0.5f * k;         // G
        px[4 * k + 3] = float(k);         // R
    }
    ImageData abgr;
    abgr.width = w;
    abgr.height = h;
    abgr.channel_names = {"A", "B", "G", "R"};
    abgr.pixels = px;
    write_exr(path, abgr);
    auto env = load_envmap(path);
    REQUIRE(env);
    REQUIRE(env->width() == w);
    REQUIRE(env->height() == h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            int k = j * w + i;
            CHECK(env->texel(i, j) == Rgb(float(k), 0.5f * k, 0.25f * k + 0.5f));
        }

    // A lone Y channel is grey; a file without R, G, B or Y is an error naming the channels.
    auto write_one_channel = [&](const std::string& file, const char* name) {
        ImageData one;
        one.width = w;
        one.height = h;
        one.channel_names = {name};
        one.pixels.assign(static_cast<std::size_t>(w) * h, 2.f);
        write_exr(file, one);
    };
    const std::string grey = (dir / "grey.exr").string(), odd = (dir / "odd.exr").string();
    write_one_channel(grey, "Y");
    write_one_channel(odd, "Z");
    CHECK(load_envmap(grey)->texel(1, 2) == Rgb(2.f));
    try {
        load_envmap(odd);
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Io);
        CHECK_THAT(error_line(e), Catch::Contains("odd.exr: ") && Catch::Contains("Z"));
        CHECK(e.where());
    }
    fs::remove_all(dir);

    try {
        load_envmap((dir / "missing.exr").string());
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Io);
        CHECK_THAT(error_line(e),
                   Catch::StartsWith("candela: error: ") && Catch::Contains("missing.exr: "));
    }
}
