#include "candela/render/film.h"
#include "candela/render/output.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

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
}
