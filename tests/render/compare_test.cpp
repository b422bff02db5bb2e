// `candela compare`: its measures against `candela converge`'s, the 8-bit decoding of the
// course's look, the layer fit that names the light-path order an image has wrong, the error
// map, and the command end to end.
#include "../app/app_support.h"
#include "../support/cs184.h"
#include "render_support.h"

#include "candela/diagnostics/compare.h"
#include "candela/diagnostics/converge.h"
#include "candela/io/image_io.h"
#include "candela/render/output.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

using namespace candela;
using namespace candela::test;

namespace {

/// candela's own Cornell box (scenes/cornell-box.dae), loaded once.
const Scene& cornell_box() {
    static Scene scene = [] {
        Diagnostics diag;
        return load_scene(project_scene("cornell-box.dae"), BuildOptions{}, diag);
    }();
    return scene;
}

RenderSettings small(int spp, std::uint64_t seed, int width = 32, int height = 24) {
    RenderSettings s;
    s.width = width;
    s.height = height;
    s.spp = spp;
    s.seed = seed;
    s.max_depth = 2;
    s.aovs = AovSet::parse("none");
    s.quiet = true;
    return s;
}

/// The 8-bit course-look PNG of `rgb` (a width x height film's means, or any linear RGB).
void write_course_png(const std::string& path, const Film& film) {
    write_png(path, film.width(), film.height(),
              film_preview(film, 0.f, Tonemap::Clamp, Look::Cs184));
}

/// Two small renders of the Cornell box with seeds 1 and 2, and their EXRs in a temporary
/// directory (a.exr, b.exr).
struct TwoRenders {
    Film a = render_film(cornell_box(), small(4, 1));
    Film b = render_film(cornell_box(), small(4, 2));
    TempDir dir;
    explicit TwoRenders(const std::string& name) : dir(name) {
        write_exr(dir / "a.exr", film_to_image(a, {}));
        write_exr(dir / "b.exr", film_to_image(b, {}));
    }
};

} // namespace

TEST_CASE("compare: two renders' EXRs give converge's relMSE exactly", "[compare]") {
    const TwoRenders two("compare-exact");
    const Film &a = two.a, &b = two.b;
    const TempDir& dir = two.dir;
    const CompareResult r = compare_images(read_linear_image(dir / "a.exr", Look::Cs184),
                                           read_linear_image(dir / "b.exr", Look::Cs184), 5);
    const ImageError e = image_error(a, b);
    CHECK(r.whole.rel_mse == e.rel_mse);
    CHECK(r.whole.mse == e.mse);
    CHECK(r.compared == 32u * 24u);
    CHECK(r.left_out == 0u);
    // The cells partition the image: their squared-error shares add up to 1.
    double share = 0.0;
    for (double s : r.cell_share)
        share += s;
    constexpr double kRoundoff = 1e-12; // a sum of a few dozen doubles
    CHECK(std::abs(share - 1.0) < kRoundoff);
    REQUIRE(r.top.size() == 5);
    CHECK(r.top[0].se >= r.top[4].se);
    CHECK(r.grid.cols == kRegionColumns);
}

TEST_CASE("compare: a course-look PNG of a render has only its quantisation error", "[compare]") {
    const Film f = render_film(cornell_box(), small(16, 3));
    TempDir dir("compare-png");
    write_exr(dir / "f.exr", film_to_image(f, {}));
    write_course_png(dir / "f.png", f);
    const LinearImage png = read_linear_image(dir / "f.png", Look::Cs184);
    const CompareResult r = compare_images(png, read_linear_image(dir / "f.exr", Look::Cs184), 3);
    // The light panel is clipped (white) in the course's look and left out.
    CHECK(r.left_out > 0u);
    CHECK(png.decoding.find("CS184") != std::string::npos);
    // The bound: a decoded byte is the middle of its interval, so each channel is off by at
    // most half the interval's width w_b; relMSE <= max_b (w_b / 2)^2 / (lo_b^2 + eps).
    double bound = 0.0;
    for (int b = 0; b < 255; ++b) {
        const double lo = std::pow(b / 255.0, 2.2) / std::sqrt(2.0);
        const double hi = std::pow((b + 1) / 255.0, 2.2) / std::sqrt(2.0);
        bound = std::max(bound, (hi - lo) * (hi - lo) / 4.0 / (lo * lo + kRelMseEps));
    }
    INFO("relMSE " << r.whole.rel_mse << " bound " << bound);
    CHECK(r.whole.rel_mse > 0.0);
    CHECK(r.whole.rel_mse <= bound);
    CHECK(bound < 1e-4); // small: a relative RMS error of 1 % at most
}

TEST_CASE("compare: the layer fit names the one-bounce indirect light darkened by 12 %",
          "[compare][stat]") {
    // The image: direct light plus 0.88 x the one-bounce indirect light (-m 2), in the course's
    // 8-bit look; rendered with seeds the layers do not use.
    constexpr int kW = 48, kH = 36;
    RenderSettings d = small(512, 11, kW, kH), i = small(512, 12, kW, kH);
    d.light_paths = LightPaths::Direct;
    i.light_paths = LightPaths::Indirect;
    const Film direct = render_film(cornell_box(), d), indirect = render_film(cornell_box(), i);
    constexpr double kDarkened = 0.88;
    Film image(kW, kH, AovSet::parse("none"), false);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            FilmSample s;
            s.L = direct.mean(x, y) + indirect.mean(x, y) * float(kDarkened);
            image.add(x, y, s);
        }
    TempDir dir("compare-layers");
    write_course_png(dir / "dark.png", image);
    const LinearImage png = read_linear_image(dir / "dark.png", Look::Cs184);

    RenderSettings settings = small(256, 0, kW, kH);
    const std::vector<Layer> layers =
        render_layers(cornell_box(), layer_specs(settings, LayerSplit::Orders));
    REQUIRE(layers.size() == 3);
    const RegionGrid grid = region_grid(kW, kH);
    const std::vector<int> materials = first_hit_materials(cornell_box(), settings);
    const std::vector<LayerFit> fits = fit_layers(png, layers, grid, materials);
    REQUIRE(fits.size() == 3);
    const LayerFit& one_bounce = fits[2];
    REQUIRE(one_bounce.determined);
    INFO(describe_layer_fit(fits, grid, {}));
    CHECK(one_bounce.significant);
    CHECK(std::abs(one_bounce.scale - kDarkened) <= kZBound * one_bounce.std_err);
    // Precise enough to tell 12 % from noise by a wide margin.
    CHECK(one_bounce.std_err < 0.02);
    const LayerFit& direct_fit = fits[1];
    REQUIRE(direct_fit.determined);
    CHECK_FALSE(direct_fit.significant);
    CHECK(std::abs(direct_fit.scale - 1.0) <= kZBound * direct_fit.std_err);
    // Where: a material of the scene holds the largest part of the deviation.
    REQUIRE(one_bounce.main_material >= 0);
    CHECK(std::size_t(one_bounce.main_material) < cornell_box().materials.size());
    CHECK(one_bounce.main_material_share > 0.0);
    CHECK(one_bounce.main_material_share <= 1.0);
    std::vector<std::string> names;
    for (const Material& m : cornell_box().materials)
        names.push_back(m.name);
    const std::string text = describe_layer_fit(fits, grid, names);
    CHECK(text.find("on material '" + names[std::size_t(one_bounce.main_material)] + "'") !=
          std::string::npos);
    CHECK(text.find("verdict: order 2 (one-bounce indirect) is 1") != std::string::npos);
    CHECK(text.find("% dark") != std::string::npos);
}

TEST_CASE("compare: the error map's scale, legend and size", "[compare][quick]") {
    // The documented scale: 1e-4 blue, 1e-2 green, 1 red; below and above clamp.
    const Rgb blue = error_map_color(1e-4), green = error_map_color(1e-2),
              red = error_map_color(1.0);
    CHECK(blue.z == 1.f);
    CHECK(blue.x == 0.f);
    CHECK(green.y == 1.f);
    CHECK(red.x == 1.f);
    CHECK(red.y == 0.f);
    CHECK(error_map_color(0.0).z == 1.f);
    CHECK(error_map_color(1e3).x == 1.f);
    LinearImage a, b;
    a.width = b.width = 10;
    a.height = b.height = 5;
    a.rgb.assign(150, 0.5f);
    b.rgb.assign(150, 0.5f);
    a.usable.assign(50, 1);
    b.usable.assign(50, 1);
    a.rgb[0] = 1.5f;  // pixel (0, 0): error
    a.usable[49] = 0; // pixel (9, 4): left out
    const Image8 map = error_map(a, b);
    const int k = (kErrorMapMinWidth + 9) / 10;
    CHECK(map.width == 10 * k);
    CHECK(map.height == 5 * k + kErrorMapLegendRows);
    auto px = [&](int x, int y, int c) {
        return int(map.rgb[(std::size_t(y) * map.width + x) * 3 + c]);
    };
    CHECK(px(0, 0, 0) == 255);                // relMSE 1/3 / (0.25 + 0.01) > 1: red
    CHECK(px(k, 0, 2) == 255);                // no error: blue
    CHECK(px(10 * k - 1, 5 * k - 1, 0) == 0); // left out: black
    CHECK(px(10 * k - 1, 5 * k - 1, 1) == 0);
    CHECK(px(10 * k - 1, 5 * k - 1, 2) == 0);
}

TEST_CASE("compare: the command end to end", "[compare][app]") {
    const TwoRenders two("compare-cmd");
    const Film &a = two.a, &b = two.b;
    const TempDir& dir = two.dir;
    const Result r = run_candela(
        {"compare", dir / "a.exr", dir / "b.exr", "--error-map", dir / "map.png", "--top", "3"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    char want[64];
    std::snprintf(want, sizeof want, "relMSE %.4g", image_error(a, b).rel_mse);
    CHECK(r.out.find(want) != std::string::npos);
    CHECK(r.out.find("in linear radiance") != std::string::npos);
    CHECK(r.out.find("  3. (") != std::string::npos);
    const ImageHeader h = read_image_header(dir / "map.png");
    CHECK(h.height == h.width * 24 / 32 + kErrorMapLegendRows);
    // Errors: a missing image, images of different sizes; nothing written then.
    const Result missing = run_candela({"compare", dir / "none.exr", dir / "b.exr"});
    CHECK(missing.status == int(ErrorKind::Io));
    CHECK(missing.err.find("none.exr") != std::string::npos);
    write_exr(dir / "c.exr", film_to_image(render_film(cornell_box(),
                                                       [] {
                                                           RenderSettings s = small(1, 1);
                                                           s.width = 16;
                                                           return s;
                                                       }()),
                                           {}));
    const Result sizes =
        run_candela({"compare", dir / "a.exr", dir / "c.exr", "--error-map", dir / "map2.png"});
    CHECK(sizes.status == int(ErrorKind::Usage));
    CHECK_FALSE(std::filesystem::exists(dir / "map2.png"));
    // The layers' settings without --scene would be ignored: refused, each by its own name.
    for (const char* flag : {"-m", "-o", "-l", "-s", "--split"}) {
        const std::string value = std::string(flag) == "--split" ? "orders" : "1";
        const Result lone = run_candela({"compare", dir / "a.exr", dir / "b.exr", flag, value});
        INFO(flag);
        CHECK(lone.status == int(ErrorKind::Usage));
        CHECK(lone.err.find(std::string(flag)) != std::string::npos);
        CHECK(lone.err.find("give --scene") != std::string::npos);
    }
    const Result lone_r = run_candela({"compare", dir / "a.exr", dir / "b.exr", "-r", "32", "24"});
    CHECK(lone_r.status == int(ErrorKind::Usage));
    CHECK(lone_r.err.find("-r/--resolution describes the layers of --scene") != std::string::npos);
}

TEST_CASE("compare: the layers add up to the image's settings", "[compare][quick]") {
    RenderSettings image;
    image.max_depth = 3;
    const std::vector<LayerSpec> orders = layer_specs(image, LayerSplit::Orders);
    REQUIRE(orders.size() == 4);
    std::set<std::uint64_t> seeds;
    for (int k = 0; k < 4; ++k) {
        const RenderSettings& s = orders[std::size_t(k)].settings;
        CHECK(s.max_depth == k);
        CHECK_FALSE(s.accumulate);
        CHECK(s.aovs.variance);
        CHECK(s.adaptive == AdaptiveKind::None);
        CHECK(s.seed != image.seed);
        seeds.insert(s.seed);
    }
    CHECK(seeds.size() == 4); // independent layers
    CHECK(orders[2].name == "order 2 (one-bounce indirect)");
    // -o 0: only order m.
    image.accumulate = false;
    const std::vector<LayerSpec> last = layer_specs(image, LayerSplit::Orders);
    REQUIRE(last.size() == 1);
    CHECK(last[0].settings.max_depth == 3);
    // Direct and indirect: two layers of the whole -m.
    image.accumulate = true;
    const std::vector<LayerSpec> split = layer_specs(image, LayerSplit::DirectIndirect);
    REQUIRE(split.size() == 2);
    CHECK(split[0].settings.light_paths == LightPaths::Direct);
    CHECK(split[1].settings.light_paths == LightPaths::Indirect);
    CHECK(split[1].settings.max_depth == 3);
    CHECK(split[1].settings.accumulate);
}

namespace {

/// The candela-look 8-bit PNG of a film (0 EV, clamp, sRGB).
void write_candela_png(const std::string& path, const Film& film) {
    write_png(path, film.width(), film.height(),
              film_preview(film, 0.f, Tonemap::Clamp, Look::Candela));
}

/// Settings of the self-consistency renders: small, with three orders.
RenderSettings consistency_settings(int spp) {
    RenderSettings s = small(spp, 0, 80, 60);
    s.max_depth = 3;
    s.adaptive = AdaptiveKind::None;
    return s;
}

} // namespace

TEST_CASE("compare: candela's own image matches its layers in every look", "[compare][stat]") {
    // The 8-bit fits once chose pixels by their own layer values (and the course look was
    // told "order 1 is 3.9 % bright"); the scales' errors left out the layers' noise in the
    // normal equations, and then the correlation of a pixel's channels. All are checked here
    // against candela's own image.
    // The scenes: candela's own, and the course's when present. Each image is candela's render
    // at the settings the layers are made with (seed 0; the layers' seeds are their own), as an
    // EXR, a course-look PNG and a candela-look PNG, at 16 and 256 samples per pixel.
    std::vector<std::string> scenes = {project_scene("cornell-box.dae"),
                                       project_scene("cornell-spheres.dae")};
    if (cs184_available())
        for (const char* name : {"CBspheres.dae", "CBspheres_lambertian.dae"})
            scenes.push_back(cs184_scene(name));
    else
        WARN("the CS184 scenes are absent (" << cs184_dir() << "): candela's scenes only");
    TempDir dir("compare-consistency");
    std::vector<double> z_squares; // (scale - 1)^2 / std_err^2 of every fit
    for (const std::string& path : scenes) {
        Diagnostics diag(false);
        const Scene scene = load_scene(path, BuildOptions{}, diag);
        constexpr int kLayerSpp = 64; // compare's default -s
        const std::vector<Layer> layers =
            render_layers(scene, layer_specs(consistency_settings(kLayerSpp), LayerSplit::Orders));
        const RegionGrid grid = region_grid(80, 60);
        for (int spp : {16, 256}) {
            const Film film = render_film(scene, consistency_settings(spp));
            write_exr(dir / "image.exr", film_to_image(film, {}));
            write_course_png(dir / "course.png", film);
            write_candela_png(dir / "candela.png", film);
            const std::pair<const char*, Look> files[] = {{"image.exr", Look::Cs184},
                                                          {"course.png", Look::Cs184},
                                                          {"candela.png", Look::Candela}};
            for (const auto& [file, look] : files) {
                LinearImage image = read_linear_image(dir / file, look);
                image.spp = spp;
                add_clipping_loss(image, layers, scene, consistency_settings(spp));
                const LayerAnalysis a = analyse_layers(image, layers, grid);
                INFO(path << ", " << spp << " spp, " << file << ":\n"
                          << describe_layer_analysis(a, grid));
                // A correct image is told it matches: every determined fit within
                // kLayerSignificanceZ standard errors, said in those words.
                CHECK(describe_layer_analysis(a, grid).find(
                          "verdict: every determined layer matches") != std::string::npos);
                CHECK(a.first_missing < 0);
                for (const LayerFit& f : a.fits)
                    if (f.determined) {
                        const double z = (f.scale - 1.0) / f.std_err;
                        z_squares.push_back(z * z);
                    }
                REQUIRE(a.common.determined);
                z_squares.push_back(std::pow((a.common.scale - 1.0) / a.common.std_err, 2));
                CHECK_FALSE(check_registration(image, sum_of_layers(layers)).misregistered);
            }
        }
    }
    // The standard errors are calibrated: a fit's (scale - 1) / std_err is a standard normal
    // when the image is right, so the mean of its square is 1 with standard deviation
    // sqrt(2 / n) over n independent fits. The three files of one render share its noise, so
    // only a third of the fits are independent. (The channels of a pixel taken as independent
    // terms of the sandwich error gave 2.53 here, and fits at 3.0 and 3.1 standard errors.)
    const double n_independent = double(z_squares.size()) / 3.0;
    const double spread = std::sqrt(2.0 / n_independent);
    constexpr double kCalibrationZ = 3.0; // the bound is the mean's 3 standard deviations
    const double mean_z2 =
        std::accumulate(z_squares.begin(), z_squares.end(), 0.0) / double(z_squares.size());
    INFO(z_squares.size() << " fits, mean z^2 " << mean_z2 << ", bound 1 +- "
                          << kCalibrationZ * spread);
    CHECK(std::abs(mean_z2 - 1.0) <= kCalibrationZ * spread);
}

TEST_CASE("compare: a course-look image with clipped fireflies matches at its sample count",
          "[compare][stat][app]") {
    // At 16 spp the glass caustics of CBspheres push single pixels over the course look's
    // white. Dropping them kept only pixels whose noise stayed low, and candela's own image
    // was told "the whole image is 1.0 % dark (4.1 standard errors)". Fitted at the white with
    // the light the white is expected to clip at 16 spp added back, it matches. The size and
    // depth are those at which the bias was 4 standard errors (-m 5 carries the caustics; at
    // -m 3 or a smaller image it stayed under the 3 the verdict names).
    CANDELA_SKIP_WITHOUT_CS184();
    const std::string scene = cs184_scene("CBspheres.dae");
    TempDir dir("compare-fireflies");
    const Result render =
        run_candela({"-t", "2", "-s", "16", "--adaptive", "none", "-m", "5", "-r", "240", "180",
                     "--look", "cs184", "-f", dir / "course.png", scene});
    INFO(render.err);
    REQUIRE(render.status == 0);
    const std::vector<std::string> compare = {
        "compare", dir / "course.png", "--scene", scene, "-m", "5", "-r", "240", "180", "-t", "2"};
    // candela's PNG records its sample count (and --adaptive none): no flag is needed.
    const Result recorded = run_candela(compare);
    INFO(recorded.out << recorded.err);
    REQUIRE(recorded.status == 0);
    CHECK(recorded.out.find("verdict: every determined layer matches") != std::string::npos);
    CHECK(recorded.out.find("give --image-spp") == std::string::npos);
    // The same bytes without candela's text (a course renderer's PNG): the clipped pixels are
    // fitted without their expected loss, and the verdict says that it may read the image dark.
    const ImageData png = read_image(dir / "course.png");
    std::vector<unsigned char> bytes;
    for (int y = 0; y < png.height; ++y)
        for (int x = 0; x < png.width; ++x)
            for (int c = 0; c < 3; ++c)
                bytes.push_back((unsigned char)std::lround(png.at(x, y, c) * 255.f));
    write_png(dir / "bare.png", png.width, png.height, bytes, {});
    std::vector<std::string> bare = compare;
    bare[1] = dir / "bare.png";
    bare.insert(bare.end(), {"--look", "cs184"});
    const Result unknown = run_candela(bare);
    INFO(unknown.out << unknown.err);
    REQUIRE(unknown.status == 0);
    CHECK(unknown.out.find("give --image-spp") != std::string::npos);
    std::vector<std::string> known = bare;
    known.insert(known.end(), {"--image-spp", "16"});
    const Result r = run_candela(known);
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("verdict: every determined layer matches") != std::string::npos);
    CHECK(r.out.find("give --image-spp") == std::string::npos);
    // 0 is no sample count.
    std::vector<std::string> zero = bare;
    zero.insert(zero.end(), {"--image-spp", "0"});
    const Result refused = run_candela(zero);
    CHECK(refused.status == 2);
    CHECK(refused.err.find("--image-spp must be >= 1") != std::string::npos);
}

TEST_CASE("compare: an image scaled as a whole is told its one common factor", "[compare][stat]") {
    // Direct light only (-m 1): orders 0 and 1, whose paths have no heavy tail, so both are
    // fitted well enough to tell 2 % apart from noise.
    RenderSettings settings = consistency_settings(256);
    settings.max_depth = 1;
    const Film film = render_film(cornell_box(), settings);
    const std::vector<Layer> layers =
        render_layers(cornell_box(), layer_specs(settings, LayerSplit::Orders));
    constexpr double kWhole = 0.98;
    LinearImage image = linear_image(film);
    for (float& v : image.rgb)
        v *= float(kWhole);
    const RegionGrid grid = region_grid(80, 60);
    const LayerAnalysis a = analyse_layers(image, layers, grid);
    const std::string text = describe_layer_analysis(a, grid);
    INFO(text);
    REQUIRE(a.common.determined);
    CHECK(std::abs(a.common.scale - kWhole) <= kZBound * a.common.std_err);
    CHECK(a.common_explains);
    CHECK(text.find("verdict: the whole image is ") != std::string::npos);
    CHECK(text.find("% dark (scale ") != std::string::npos);
    CHECK(text.find("verdict: order") == std::string::npos);
}

TEST_CASE("compare: orders missing from the image are named as missing", "[compare][stat]") {
    // The image has orders 0 and 1 (-m 1); the layers are made for -m 3.
    RenderSettings lower = consistency_settings(256);
    lower.max_depth = 1;
    const LinearImage image = linear_image(render_film(cornell_box(), lower));
    const std::vector<Layer> layers =
        render_layers(cornell_box(), layer_specs(consistency_settings(64), LayerSplit::Orders));
    const RegionGrid grid = region_grid(80, 60);
    const LayerAnalysis a = analyse_layers(image, layers, grid);
    const std::string text = describe_layer_analysis(a, grid);
    INFO(text);
    CHECK(a.first_missing == 2);
    CHECK(std::abs(a.missing.scale) <= kZBound * a.missing.std_err);
    CHECK(text.find("verdict: orders 2 and above are missing (rendered with a lower -m?)") !=
          std::string::npos);
    // The orders present are fitted without the missing ones: they match.
    CHECK(text.find("% dark") == std::string::npos);
    CHECK(text.find("% bright") == std::string::npos);
    REQUIRE(a.fits.size() == 4);
    CHECK(a.fits[2].absent);
    CHECK(a.fits[3].absent);
    CHECK(text.find("order 3 (2-bounce indirect)") != std::string::npos);
}

TEST_CASE("compare: an undetermined layer is told why", "[compare][stat]") {
    // Order 2 from a handful of samples: its light is below its noise's tenfold, and it looks
    // most like order 1 (both are light on the same walls).
    RenderSettings settings = consistency_settings(64);
    settings.max_depth = 2;
    std::vector<LayerSpec> specs = layer_specs(settings, LayerSplit::Orders);
    specs[2].settings.spp = 2;
    const std::vector<Layer> layers = render_layers(cornell_box(), specs);
    RenderSettings image_settings = consistency_settings(64);
    image_settings.max_depth = 2;
    const LinearImage image = linear_image(render_film(cornell_box(), image_settings));
    const RegionGrid grid = region_grid(80, 60);
    const std::vector<LayerFit> fits = fit_layers(image, layers, grid);
    REQUIRE_FALSE(fits[2].determined);
    CHECK(fits[2].signal_to_noise < kMinLayerSignalToNoise);
    CHECK(fits[2].like_name == layers[1].name);
    const std::string text = describe_layer_fit(fits, grid);
    INFO(text);
    CHECK(text.find("undetermined (too noisy: its light in the compared pixels is") !=
          std::string::npos);
    CHECK(text.find("most like order 1 (direct light) here (cosine") != std::string::npos);
}

TEST_CASE("compare: the course's crop of the 800x600 view is named as a framing",
          "[compare][stat]") {
    // The course's -r 160 120: the centre of the 800x600 view at that view's pixel pitch,
    // rendered as a region of the full frame and cut out.
    constexpr int kW = 160, kH = 120;
    RenderSettings full = small(16, 5, kCourseViewWidth, kCourseViewHeight);
    full.region = Region{(kCourseViewWidth - kW) / 2, (kCourseViewHeight - kH) / 2, kW, kH};
    const Film view = render_film(cornell_box(), full); // the region's pixels only
    REQUIRE(view.width() == kW);
    REQUIRE(view.height() == kH);
    LinearImage crop;
    crop.width = kW;
    crop.height = kH;
    crop.usable.assign(std::size_t(kW) * kH, 1);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const Rgb L = view.mean(x, y);
            crop.rgb.insert(crop.rgb.end(), {L.x, L.y, L.z});
        }
    const LinearImage candela = linear_image(render_film(cornell_box(), small(16, 6, kW, kH)));
    const Registration reg = check_registration(crop, candela);
    const std::string text = describe_registration(reg, kW, kH);
    INFO(text << "correlation as is " << reg.identity << ", best " << reg.best);
    CHECK(reg.misregistered);
    CHECK(reg.zoom == double(kCourseViewWidth) / kW);
    CHECK(text.find("the course's framing") != std::string::npos);
    CHECK(text.find("--framing cs184") != std::string::npos);
    // The same image framed alike is not misregistered, nor is a second render of it.
    CHECK_FALSE(
        check_registration(linear_image(render_film(cornell_box(), small(16, 7, kW, kH))), candela)
            .misregistered);
    // The command gives that verdict instead of the layer fit's.
    TempDir dir("compare-crop");
    Film crop_film(kW, kH, AovSet::parse("none"), false);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            FilmSample s;
            s.L = crop.pixel(x, y);
            crop_film.add(x, y, s);
        }
    write_exr(dir / "crop.exr", film_to_image(crop_film, {}));
    const Result r =
        run_candela({"compare", dir / "crop.exr", "--scene", project_scene("cornell-box.dae"), "-m",
                     "2", "-s", "8", "-t", "2"});
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("--framing cs184") != std::string::npos);
    CHECK(r.out.find("verdict: order") == std::string::npos);
    CHECK(r.out.find("by light-path layer") == std::string::npos);
}

TEST_CASE("compare: regions black in both images say so", "[compare]") {
    // The Cornell box's outer columns are black; its course-look PNG holds them as byte 0.
    const Film f = render_film(cornell_box(), small(16, 3, 64, 48));
    TempDir dir("compare-black");
    write_exr(dir / "f.exr", film_to_image(f, {}));
    write_course_png(dir / "f.png", f);
    const CompareResult c = compare_images(read_linear_image(dir / "f.png", Look::Cs184),
                                           read_linear_image(dir / "f.exr", Look::Cs184), 0);
    REQUIRE(c.cell_black.size() == c.cells.size());
    CHECK(c.cell_black.front() == 1);             // the top-left cell: outside the box
    CHECK(c.cell_black[c.cells.size() / 2] == 0); // the middle: lit
    const Result r = run_candela({"compare", dir / "f.png", dir / "f.exr"});
    INFO(r.out << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("     black") != std::string::npos);
    CHECK(r.out.find("black: black in both images") != std::string::npos);
    CHECK(r.out.find("e-10") == std::string::npos);
}
