#include "candela/render/film.h"
#include "candela/render/output.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

using namespace candela;

TEST_CASE("film mean and variance of the mean follow from the sums", "[film][quick]") {
    Film film(2, 1, AovSet::all(), true);
    const float values[] = {1.f, 2.f, 3.f, 6.f};
    for (float v : values) {
        FilmSample s;
        s.L = Rgb(v, 2.f * v, 0.f);
        film.add(1, 0, s);
    }
    CHECK(film.count(1, 0) == 4);
    CHECK(film.count(0, 0) == 0);
    CHECK(film.mean(1, 0).x == Approx(3.0));
    CHECK(film.mean(1, 0).y == Approx(6.0));
    // Sample variance of {1,2,3,6} is 14/3; of the mean, (14/3)/4.
    CHECK(film.variance_of_mean(1, 0).x == Approx(14.0 / 12.0));
    CHECK(film.variance_of_mean(1, 0).y == Approx(4.0 * 14.0 / 12.0));
    double mean, var;
    std::uint32_t n;
    film.lum_stats(1, 0, mean, var, n);
    CHECK(n == 4);
    CHECK(mean == Approx(luminance(Rgb(3.f, 6.f, 0.f))));
}

TEST_CASE("films of disjoint sample ranges merge to the film of all samples", "[film][quick]") {
    Film all(3, 2, AovSet::all(), false), a(3, 2, AovSet::all(), false),
        b(3, 2, AovSet::all(), false);
    for (int k = 0; k < 10; ++k) {
        FilmSample s;
        s.L = Rgb(float(k), float(k * k), 1.f);
        s.depth = float(k);
        s.hit = true;
        all.add(2, 1, s);
        (k < 4 ? a : b).add(2, 1, s);
    }
    a.merge(b);
    CHECK(a.count(2, 1) == all.count(2, 1));
    CHECK(a.mean(2, 1) == all.mean(2, 1));
    CHECK(a.variance_of_mean(2, 1) == all.variance_of_mean(2, 1));
    CHECK(a.nearest_depth(2, 1) == all.nearest_depth(2, 1));
    Film other(2, 2, AovSet::all(), false);
    CHECK_THROWS_AS(a.merge(other), Error);
}

TEST_CASE("dropped samples are counted but never enter the sums", "[film][quick]") {
    Film film(1, 1, AovSet{}, false);
    FilmSample s;
    s.L = Rgb(1.f);
    film.add(0, 0, s);
    film.add_dropped(0, 0);
    CHECK(film.count(0, 0) == 1);
    CHECK(film.total_dropped() == 1);
    CHECK(film.mean(0, 0) == Rgb(1.f));
}

TEST_CASE("a pixel's run of samples adds the same bits as one add() per sample", "[film][quick]") {
    // Values of very different sizes, so that the order of the additions shows in the sums; a
    // NaN and an infinite sample in the run are dropped.
    std::vector<FilmSample> run;
    for (int k = 0; k < 40; ++k) {
        FilmSample s;
        const float v = std::ldexp(1.f + 0.37f * float(k), (k * 7) % 31 - 15);
        s.L = Rgb(v, 0.3f * v, 1.f / v);
        s.albedo = Rgb(0.1f * float(k), 0.2f, 0.3f);
        s.normal = Vec3(0.f, std::sin(float(k)), std::cos(float(k)));
        s.depth = 10.f - 0.2f * float(k % 13);
        s.hit = k % 3 != 0;
        run.push_back(s);
    }
    run[7].L.y = std::numeric_limits<float>::quiet_NaN();
    run[23].L.x = std::numeric_limits<float>::infinity();
    for (const bool lum : {false, true})
        for (const AovSet aovs : {AovSet::all(), AovSet{}}) {
            CAPTURE(lum, aovs.str());
            Film one(2, 2, aovs, lum), many(2, 2, aovs, lum);
            // Two runs into the same pixel: the second starts from the first's sums.
            for (int part = 0; part < 2; ++part) {
                const std::size_t first = part == 0 ? 0 : 25;
                const int count = part == 0 ? 25 : 15;
                for (int k = 0; k < count; ++k) {
                    const FilmSample& s = run[first + std::size_t(k)];
                    if (is_finite(s.L))
                        one.add(1, 1, s);
                    else
                        one.add_dropped(1, 1);
                }
                const std::uint32_t dropped = many.add_samples(
                    1, 1, count, [&](int k) -> const FilmSample& { return run[first + k]; });
                CHECK(dropped == (part == 0 ? 2u : 0u));
            }
            std::ostringstream a, b;
            one.write(a);
            many.write(b);
            CHECK(a.str() == b.str());
            CHECK(many.count(1, 1) == 38);
            CHECK(many.dropped(1, 1) == 2);
        }
}

TEST_CASE("unrequested auxiliary channels are neither stored nor written", "[film][quick]") {
    Film film(4, 4, AovSet::parse("depth"), false);
    ImageData img = film_to_image(film, {});
    CHECK(img.channel_names == std::vector<std::string>{"R", "G", "B", "A", "Z", "samples"});
    CHECK_THROWS_AS(AovSet::parse("albedo,bogus"), Error);
    CHECK(AovSet::parse("normal,variance").str() == "normal,variance");
}

TEST_CASE("sample-rate ramp runs blue, green, red", "[film][quick]") {
    CHECK(sample_rate_color(0.f) == Rgb(0, 0, 1));
    CHECK(sample_rate_color(0.5f) == Rgb(0, 1, 0));
    CHECK(sample_rate_color(1.f) == Rgb(1, 0, 0));
    CHECK(rate_image_path("dir/out.png") == "dir/out_rate.png");
    CHECK(rate_image_path("a.b/out") == "a.b/out_rate.png");
    // The legend names the counts at the ramp's three colours.
    CHECK(rate_legend(32) == "blue 0, green 16, red 32 or more samples per pixel (linear between)");
    CHECK_THAT(rate_legend(5), Catch::Contains("green 2.5, red 5 or more"));
}

TEST_CASE("the variance of a huge radiance saturates instead of overflowing", "[film][quick]") {
    // Radiance 1e20 squared is 1e40, beyond the float range; the sums are doubles.
    Film film(1, 1, AovSet::all(), false);
    for (float v : {0.f, 1e20f}) {
        FilmSample s;
        s.L = Rgb(v, 1.f, 0.f);
        film.add(0, 0, s);
    }
    const Rgb var = film.variance_of_mean(0, 0);
    CHECK(std::isfinite(var.x));
    CHECK(var.x == std::numeric_limits<float>::max());
    CHECK(var.y == 0.f);
    // Below the limit the value is the exact one: radiance 1e18, variance of the mean 2.5e35.
    Film small(1, 1, AovSet::all(), false);
    for (float v : {0.f, 1e18f}) {
        FilmSample s;
        s.L = Rgb(v, 0.f, 0.f);
        small.add(0, 0, s);
    }
    CHECK(small.variance_of_mean(0, 0).x == Approx(0.25e36).epsilon(1e-6));
}
