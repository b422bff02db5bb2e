// `candela compare`'s measures: reading an image as linear radiance, its error against a
// reference per region, the false-colour error map, and the per-order layer fit.
#include "candela/diagnostics/compare.h"

#include "candela/accel/accel.h"
#include "candela/io/image_io.h"
#include "candela/render/exr_layout.h"
#include "candela/render/renderer.h"
#include "candela/scene/camera.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>

namespace candela {

namespace {

/// How far an 8-bit format's value (read as float, byte / 255) may be from a whole byte: the
/// float rounding of b / 255 is ~1e-5 of a byte; a 16-bit file's values are off by up to half
/// a byte.
constexpr double kByteTolerance = 1e-3;

/// Seed of layer k: far from the seeds renders use by default (0) and from converge's
/// (1..N and its reference's), so a layer's noise is independent of the image it explains.
constexpr std::uint64_t kLayerSeedBase = 0x1a7e'0000'0000ull;

std::size_t pixel_index(const LinearImage& img, int x, int y) {
    return std::size_t(y) * std::size_t(img.width) + std::size_t(x);
}

} // namespace

LinearImage linear_image(const Film& film) {
    LinearImage img;
    img.width = film.width();
    img.height = film.height();
    img.rgb.resize(std::size_t(img.width) * std::size_t(img.height) * 3);
    img.usable.assign(std::size_t(img.width) * std::size_t(img.height), 1);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const Rgb L = film.mean(x, y);
            for (int c = 0; c < 3; ++c)
                img.rgb[pixel_index(img, x, y) * 3 + std::size_t(c)] = L[c];
        }
    img.decoding = "linear radiance (a film)";
    return img;
}

namespace {

/// Chooses the look an 8-bit file is decoded by (read_linear_image) into img.look and
/// img.look_source, with the warnings about it.
void choose_look(const std::string& path, const ImageData& data, std::optional<Look> given,
                 LinearImage& img) {
    const std::string name = data.meta(exr::kLook);
    const std::optional<Look> recorded = find_enum(kLooks, name);
    img.look = given ? *given : recorded.value_or(kAssumedLook);
    img.look_source = given      ? LookSource::Given
                      : recorded ? LookSource::Recorded
                                 : LookSource::Assumed;
    if (given && recorded && *given != *recorded)
        img.warnings.push_back(fmt::format("{} was written in look {}; decoded as --look {}", path,
                                           name, enum_name(kLooks, *given)));
    if (img.look != Look::Candela || !recorded || *recorded != Look::Candela) return;
    // candela's look at another exposure or through a tone map: decoded as 0 EV without one.
    const std::string ev = data.meta(exr::kExposure), tonemap = data.meta(exr::kTonemap);
    if ((!ev.empty() && std::strtod(ev.c_str(), nullptr) != 0.0) ||
        (!tonemap.empty() && tonemap != tonemap_name(Tonemap::Clamp)))
        img.warnings.push_back(fmt::format(
            "{} was written with --exposure {} --tonemap {}; compare decodes candela's look at "
            "0 EV without a tone map, so its radiance is off by those (render at 0 EV with "
            "--tonemap clamp, or compare the EXR)",
            path, ev, tonemap));
}

} // namespace

LinearImage read_linear_image(const std::string& path, std::optional<Look> given) {
    const OutputKind kind = output_kind(path);
    const ImageData data = read_image(path);
    const int ch[3] = {data.channel_index("R"), data.channel_index("G"), data.channel_index("B")};
    if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0)
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "no R, G and B channels (has " + std::to_string(data.channels()) +
                        " channels)");
    LinearImage img;
    img.width = data.width;
    img.height = data.height;
    img.rgb.resize(std::size_t(img.width) * std::size_t(img.height) * 3);
    img.usable.assign(std::size_t(img.width) * std::size_t(img.height), 1);
    const bool eight_bit = kind == OutputKind::Ldr;
    if (eight_bit) choose_look(path, data, given, img);
    const Look look = img.look;
    std::size_t clipped = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const std::size_t p = pixel_index(img, x, y);
            for (int c = 0; c < 3; ++c) {
                const float v = data.at(x, y, ch[c]);
                float& out = img.rgb[p * 3 + std::size_t(c)];
                if (!std::isfinite(v)) {
                    img.usable[p] = 0;
                    out = 0.f;
                    continue;
                }
                if (!eight_bit) {
                    out = v;
                    continue;
                }
                const double b = double(v) * 255.0;
                const long byte = std::lround(b);
                if (std::abs(b - double(byte)) > kByteTolerance || byte < 0 || byte > 255)
                    throw Error(ErrorKind::Io, SourceLoc{path},
                                "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                    ") is not an 8-bit value; compare reads 8-bit and float "
                                    "images (convert 16-bit files to EXR)");
                if (byte == 255) {
                    if (img.usable[p]) ++clipped;
                    img.usable[p] = 0;
                    out = 0.f;
                    continue;
                }
                out =
                    float(look == Look::Cs184 ? cs184_decode8(int(byte)) : srgb_decode8(int(byte)));
            }
        }
    if (eight_bit) img.clip = look == Look::Cs184 ? 1.0 / kCs184Exposure : 1.0;
    if (!eight_bit) {
        img.decoding = "linear radiance as stored";
    } else {
        char buf[320];
        std::snprintf(buf, sizeof buf,
                      look == Look::Cs184
                          ? "8-bit, decoded to linear radiance through the inverse of the CS184 "
                            "curve (exposure sqrt(2), gamma 2.2, truncation); %zu clipped pixels "
                            "(a channel at 255) left out"
                          : "8-bit, decoded to linear radiance through the inverse sRGB curve "
                            "(candela's look at 0 EV, no tone map); %zu clipped pixels (a "
                            "channel at 255) left out",
                      clipped);
        img.decoding = buf;
        img.decoding += img.look_source == LookSource::Recorded ? "; the look the file records"
                        : img.look_source == LookSource::Given  ? "; the look --look names"
                                                                : "; the look assumed";
    }
    return img;
}

double psnr_of(double mse) {
    if (!(mse > 0.0)) return std::numeric_limits<double>::infinity();
    return 10.0 * std::log10(kPsnrPeak * kPsnrPeak / mse);
}

namespace {

void check_same_size(const LinearImage& a, const LinearImage& b) {
    if (a.width != b.width || a.height != b.height)
        throw Error(ErrorKind::Usage, "the images differ in size (" + std::to_string(a.width) +
                                          "x" + std::to_string(a.height) + " and " +
                                          std::to_string(b.width) + "x" + std::to_string(b.height) +
                                          ")");
}

} // namespace

CompareResult compare_images(const LinearImage& image, const LinearImage& ref, int top_n) {
    check_same_size(image, ref);
    CompareResult r;
    r.grid = region_grid(ref.width, ref.height);
    std::vector<ErrorSums> cell_sums(r.grid.cells.size());
    ErrorSums whole;
    std::vector<PixelError> pixels;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            if (!image.ok(x, y) || !ref.ok(x, y)) {
                ++r.left_out;
                continue;
            }
            ++r.compared;
            ErrorSums& cell = cell_sums[std::size_t(r.grid.cell_of(x, y))];
            PixelError p;
            p.x = x;
            p.y = y;
            p.value = image.pixel(x, y);
            p.reference = ref.pixel(x, y);
            for (int c = 0; c < 3; ++c) {
                const double a = double(image.at(x, y, c)), b = double(ref.at(x, y, c));
                whole.add(a, b);
                cell.add(a, b);
                p.se += (a - b) * (a - b);
            }
            pixels.push_back(p);
        }
    r.whole = whole.error();
    r.psnr = psnr_of(r.whole.mse);
    for (const ErrorSums& s : cell_sums) {
        r.cells.push_back(s.error());
        r.cell_share.push_back(whole.se > 0 ? s.se / whole.se : 0.0);
    }
    const std::size_t n = std::min(pixels.size(), std::size_t(std::max(0, top_n)));
    std::partial_sort(pixels.begin(), pixels.begin() + std::ptrdiff_t(n), pixels.end(),
                      [](const PixelError& a, const PixelError& b) {
                          return a.se > b.se ||
                                 (a.se == b.se && (a.y < b.y || (a.y == b.y && a.x < b.x)));
                      });
    pixels.resize(n);
    for (PixelError& p : pixels)
        p.share = whole.se > 0 ? p.se / whole.se : 0.0;
    r.top = std::move(pixels);
    return r;
}

Rgb error_map_color(double rel_mse) {
    double t = 0.0;
    if (rel_mse > 0.0)
        t = (std::log10(rel_mse) - kErrorMapLogMin) / (kErrorMapLogMax - kErrorMapLogMin);
    return sample_rate_color(float(std::clamp(t, 0.0, 1.0)));
}

namespace {

/// A 3x5 pixel font for the legend's labels: five rows of three bits, the high bit leftmost.
struct Glyph {
    char c;
    unsigned char rows[5];
};
constexpr Glyph kGlyphs[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'E', {7, 4, 6, 4, 7}}, {'-', {0, 0, 7, 0, 0}},
};
constexpr int kGlyphWidth = 3, kGlyphHeight = 5, kGlyphAdvance = 4;

void put(Image8& img, int x, int y, const unsigned char (&c)[3]) {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
    unsigned char* p = &img.rgb[(std::size_t(y) * std::size_t(img.width) + std::size_t(x)) * 3];
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
}

/// Draws `text` with its top-left corner at (x, y).
void draw_text(Image8& img, int x, int y, const std::string& text,
               const unsigned char (&colour)[3]) {
    for (char ch : text) {
        for (const Glyph& g : kGlyphs) {
            if (g.c != ch) continue;
            for (int r = 0; r < kGlyphHeight; ++r)
                for (int b = 0; b < kGlyphWidth; ++b)
                    if (g.rows[r] & (1 << (kGlyphWidth - 1 - b))) put(img, x + b, y + r, colour);
        }
        x += kGlyphAdvance;
    }
}

unsigned char to_byte(float v) {
    return static_cast<unsigned char>(std::lround(std::clamp(v, 0.f, 1.f) * 255.f));
}

} // namespace

Image8 error_map(const LinearImage& image, const LinearImage& ref) {
    check_same_size(image, ref);
    const int k = std::max(1, (kErrorMapMinWidth + ref.width - 1) / std::max(1, ref.width));
    Image8 out;
    out.width = ref.width * k;
    const int map_rows = ref.height * k;
    out.height = map_rows + kErrorMapLegendRows;
    const unsigned char background[3] = {40, 40, 40}, white[3] = {255, 255, 255};
    out.rgb.assign(std::size_t(out.width) * std::size_t(out.height) * 3, 0);
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            unsigned char c[3] = {0, 0, 0};
            if (image.ok(x, y) && ref.ok(x, y)) {
                ErrorSums s;
                for (int ch = 0; ch < 3; ++ch)
                    s.add(double(image.at(x, y, ch)), double(ref.at(x, y, ch)));
                const Rgb col = error_map_color(s.error().rel_mse);
                c[0] = to_byte(col.x);
                c[1] = to_byte(col.y);
                c[2] = to_byte(col.z);
            }
            for (int dy = 0; dy < k; ++dy)
                for (int dx = 0; dx < k; ++dx)
                    put(out, x * k + dx, y * k + dy, c);
        }
    // The legend: a dark strip with the colour bar, a tick and a label at every decade.
    for (int y = map_rows; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            put(out, x, y, background);
    const int margin = 10, bar_top = map_rows + 4, bar_rows = 10;
    const int bar_width = out.width - 2 * margin;
    for (int x = 0; x < bar_width; ++x) {
        const double t = (double(x) + 0.5) / double(bar_width);
        const Rgb col = sample_rate_color(float(t));
        const unsigned char c[3] = {to_byte(col.x), to_byte(col.y), to_byte(col.z)};
        for (int y = bar_top; y < bar_top + bar_rows; ++y)
            put(out, margin + x, y, c);
    }
    for (int d = int(kErrorMapLogMin); d <= int(kErrorMapLogMax); ++d) {
        const double t = (double(d) - kErrorMapLogMin) / (kErrorMapLogMax - kErrorMapLogMin);
        const int x = margin + std::min(bar_width - 1, int(std::lround(t * double(bar_width))));
        for (int y = bar_top + bar_rows; y < bar_top + bar_rows + 3; ++y)
            put(out, x, y, white);
        const std::string label = d == 0 ? "1" : "1E" + std::to_string(d);
        const int w = int(label.size()) * kGlyphAdvance - 1;
        const int left = std::clamp(x - w / 2, 1, out.width - w - 1);
        draw_text(out, left, bar_top + bar_rows + 5, label, white);
    }
    return out;
}

std::string order_name(int k) {
    switch (k) {
    case 0:
        return "emitters seen directly";
    case 1:
        return "direct light";
    case 2:
        return "one-bounce indirect";
    default:
        return std::to_string(k - 1) + "-bounce indirect";
    }
}

std::vector<LayerSpec> layer_specs(const RenderSettings& image, LayerSplit split) {
    RenderSettings base = image;
    base.aovs = AovSet::parse("variance");
    base.adaptive = AdaptiveKind::None;
    base.time_budget = 0.0;
    base.region = Region{};
    base.quiet = true;
    std::vector<LayerSpec> out;
    auto add = [&](const std::string& name, RenderSettings s) {
        s.seed = kLayerSeedBase + std::uint64_t(out.size());
        out.push_back({name, s});
    };
    if (split == LayerSplit::DirectIndirect) {
        for (LightPaths lp : {LightPaths::Direct, LightPaths::Indirect}) {
            if (image.light_paths != LightPaths::All && image.light_paths != lp) continue;
            RenderSettings s = base;
            s.light_paths = lp;
            add(lp == LightPaths::Direct ? "direct (orders 0-1)" : "indirect (orders 2+)", s);
        }
        return out;
    }
    for (int k = image.accumulate ? 0 : image.max_depth; k <= image.max_depth; ++k) {
        if (image.light_paths == LightPaths::Direct && k > 1) continue;
        if (image.light_paths == LightPaths::Indirect && k < 2) continue;
        RenderSettings s = base;
        s.accumulate = false;
        s.max_depth = k;
        s.light_paths = LightPaths::All;
        add("order " + std::to_string(k) + " (" + order_name(k) + ")", s);
    }
    return out;
}

std::vector<Layer> render_layers(const Scene& scene, const std::vector<LayerSpec>& specs) {
    std::vector<Layer> out;
    for (const LayerSpec& spec : specs) {
        std::unique_ptr<Accel> accel = make_accel(scene, spec.settings.accel);
        Renderer r(scene, *accel, spec.settings);
        RenderStats stats;
        out.push_back({spec.name, r.render(stats)});
    }
    return out;
}

LinearImage sum_of_layers(const std::vector<Layer>& layers) {
    CANDELA_CHECK(!layers.empty(), "sum_of_layers: no layers");
    LinearImage sum = linear_image(layers.front().film);
    for (std::size_t k = 1; k < layers.size(); ++k) {
        const LinearImage more = linear_image(layers[k].film);
        for (std::size_t i = 0; i < sum.rgb.size(); ++i)
            sum.rgb[i] += more.rgb[i];
    }
    sum.decoding = "candela's render (the sum of its layers below)";
    return sum;
}

namespace {

/// Solves the symmetric positive definite system G x = h by Cholesky; false when G is not
/// positive definite.
bool solve_spd(std::vector<double> G, std::vector<double>& x, const std::vector<double>& h,
               std::size_t n) {
    for (std::size_t j = 0; j < n; ++j) {
        double d = G[j * n + j];
        for (std::size_t k = 0; k < j; ++k)
            d -= G[j * n + k] * G[j * n + k];
        if (!(d > 0.0)) return false;
        G[j * n + j] = std::sqrt(d);
        for (std::size_t i = j + 1; i < n; ++i) {
            double s = G[i * n + j];
            for (std::size_t k = 0; k < j; ++k)
                s -= G[i * n + k] * G[j * n + k];
            G[i * n + j] = s / G[j * n + j];
        }
    }
    x = h;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < i; ++k)
            x[i] -= G[i * n + k] * x[k];
        x[i] /= G[i * n + i];
    }
    for (std::size_t i = n; i-- > 0;) {
        for (std::size_t k = i + 1; k < n; ++k)
            x[i] -= G[k * n + i] * x[k];
        x[i] /= G[i * n + i];
    }
    return true;
}

} // namespace

std::vector<int> first_hit_materials(const Scene& scene, const RenderSettings& settings) {
    std::unique_ptr<Accel> accel = make_accel(scene, settings.accel);
    const CameraProjection camera(scene.camera, settings.width, settings.height);
    std::vector<int> out(std::size_t(settings.width) * std::size_t(settings.height), -1);
    for (int y = 0; y < settings.height; ++y)
        for (int x = 0; x < settings.width; ++x) {
            const std::optional<Hit> hit =
                accel->intersect(camera.ray(float(x) + 0.5f, float(y) + 0.5f, Vec2(0.5f, 0.5f)));
            if (!hit) continue;
            const std::uint32_t m = hit->geom_id == scene.sphere_geom_id()
                                        ? scene.spheres[hit->prim_id].material
                                        : scene.meshes[hit->geom_id].material;
            out[std::size_t(y) * std::size_t(settings.width) + std::size_t(x)] = int(m);
        }
    return out;
}

std::vector<LayerFit> fit_layers(const LinearImage& image, const std::vector<Layer>& layers,
                                 const RegionGrid& grid, const std::vector<int>& materials) {
    for (const Layer& l : layers) {
        if (l.film.width() != image.width || l.film.height() != image.height)
            throw Error(ErrorKind::Usage, "the layers are " + std::to_string(l.film.width()) + "x" +
                                              std::to_string(l.film.height()) + ", the image " +
                                              std::to_string(image.width) + "x" +
                                              std::to_string(image.height));
        CANDELA_CHECK(l.film.aovs().variance, "fit_layers: a layer has no variance channel");
    }
    const std::size_t K = layers.size();
    std::vector<LayerFit> fits(K);
    // Sums over the compared pixel channels: A^T A, A^T b and each layer's summed variance.
    std::vector<double> ata(K * K, 0.0), atb(K, 0.0), var(K, 0.0), light(K, 0.0);
    std::vector<double> a(K), v(K);
    // Pixels whose candela value is near the 8-bit white: left out whatever the image holds.
    std::vector<std::uint8_t> near_white(std::size_t(image.width) * std::size_t(image.height), 0);
    if (std::isfinite(image.clip))
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x) {
                Rgb sum(0.f);
                for (const Layer& l : layers)
                    sum += l.film.mean(x, y);
                if (std::max({sum.x, sum.y, sum.z}) >= kFitClipMargin * image.clip)
                    near_white[pixel_index(image, x, y)] = 1;
            }
    auto for_each_entry = [&](auto&& f) {
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x) {
                if (!image.ok(x, y) || near_white[pixel_index(image, x, y)]) continue;
                for (int c = 0; c < 3; ++c) {
                    for (std::size_t k = 0; k < K; ++k) {
                        a[k] = double(layers[k].film.mean(x, y)[c]);
                        v[k] = double(layers[k].film.variance_of_mean(x, y)[c]);
                    }
                    f(x, y, double(image.at(x, y, c)));
                }
            }
    };
    for_each_entry([&](int, int, double b) {
        for (std::size_t i = 0; i < K; ++i) {
            for (std::size_t j = 0; j < K; ++j)
                ata[i * K + j] += a[i] * a[j];
            atb[i] += a[i] * b;
            var[i] += v[i];
            light[i] += a[i];
        }
    });
    const double total_light = std::accumulate(light.begin(), light.end(), 0.0);
    // The layers that carry light above their noise take part in the fit; the others keep the
    // scale 1 they are assumed to have and are reported as undetermined.
    std::vector<std::size_t> in;
    for (std::size_t k = 0; k < K; ++k) {
        fits[k].name = layers[k].name;
        fits[k].light_share = total_light > 0 ? light[k] / total_light : 0.0;
        const double signal = ata[k * K + k] - var[k];
        fits[k].signal_to_noise = var[k] > 0 ? signal / var[k] : 0.0;
        if (signal > kMinLayerSignalToNoise * var[k] && signal > 0.0) in.push_back(k);
    }
    const std::size_t n = in.size();
    if (n == 0) return fits;
    // Normal equations with the layers' noise removed: E[A^T A] = M^T M + diag(sum Var), the
    // layers being independent renders; the undetermined layers enter b at scale 1.
    std::vector<double> G(n * n), h(n), s;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < n; ++j)
            G[i * n + j] = ata[in[i] * K + in[j]] - (i == j ? var[in[i]] : 0.0);
        h[i] = atb[in[i]];
        for (std::size_t k = 0; k < K; ++k)
            if (std::find(in.begin(), in.end(), k) == in.end()) h[i] -= ata[in[i] * K + k];
    }
    if (!solve_spd(G, s, h, n)) return fits;
    // Sandwich covariance G^-1 (sum a a^T r^2) G^-1 from the residuals r, which carry the
    // image's noise, the layers' noise and whatever the model misses.
    std::vector<double> B(n * n, 0.0);
    std::vector<std::vector<double>> cell_dev(n, std::vector<double>(grid.cells.size(), 0.0));
    int material_count = 0;
    for (int m : materials)
        material_count = std::max(material_count, m + 1);
    std::vector<std::vector<double>> material_dev(
        n, std::vector<double>(std::size_t(material_count), 0.0));
    for_each_entry([&](int x, int y, double b) {
        double model = 0.0;
        for (std::size_t k = 0; k < K; ++k) {
            const auto it = std::find(in.begin(), in.end(), k);
            model += a[k] * (it == in.end() ? 1.0 : s[std::size_t(it - in.begin())]);
        }
        const double r = b - model;
        const int cell = grid.cell_of(x, y);
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t j = 0; j < n; ++j)
                B[i * n + j] += a[in[i]] * a[in[j]] * r * r;
            const double dev = (s[i] - 1.0) * a[in[i]];
            cell_dev[i][std::size_t(cell)] += dev * dev;
            if (!materials.empty()) {
                const int m = materials[pixel_index(image, x, y)];
                if (m >= 0) material_dev[i][std::size_t(m)] += dev * dev;
            }
        }
    });
    // Columns of G^-1 one at a time: cov = G^-1 B G^-1, only its diagonal is needed.
    std::vector<double> ginv(n * n), e(n), col;
    for (std::size_t j = 0; j < n; ++j) {
        std::fill(e.begin(), e.end(), 0.0);
        e[j] = 1.0;
        solve_spd(G, col, e, n);
        for (std::size_t i = 0; i < n; ++i)
            ginv[i * n + j] = col[i];
    }
    for (std::size_t i = 0; i < n; ++i) {
        double c = 0.0;
        for (std::size_t p = 0; p < n; ++p)
            for (std::size_t q = 0; q < n; ++q)
                c += ginv[i * n + p] * B[p * n + q] * ginv[q * n + i];
        LayerFit& f = fits[in[i]];
        f.determined = true;
        f.scale = s[i];
        f.std_err = std::sqrt(std::max(0.0, c));
        f.significant = std::abs(f.scale - 1.0) > kLayerSignificanceZ * f.std_err;
        const double total = std::accumulate(cell_dev[i].begin(), cell_dev[i].end(), 0.0);
        const auto top = std::max_element(cell_dev[i].begin(), cell_dev[i].end());
        if (total > 0 && top != cell_dev[i].end()) {
            f.main_cell = int(top - cell_dev[i].begin());
            f.main_cell_share = *top / total;
        }
        const auto top_material = std::max_element(material_dev[i].begin(), material_dev[i].end());
        if (total > 0 && top_material != material_dev[i].end() && *top_material > 0) {
            f.main_material = int(top_material - material_dev[i].begin());
            f.main_material_share = *top_material / total;
        }
    }
    return fits;
}

std::string describe_layer_fit(const std::vector<LayerFit>& fits, const RegionGrid& grid,
                               const std::vector<std::string>& material_names) {
    std::string out;
    std::vector<const LayerFit*> off;
    for (const LayerFit& f : fits) {
        if (!f.determined) {
            out += fmt::format("  {:<34} {:5.1f} % of the light: undetermined (too little of it "
                               "in the compared pixels; taken as 1)\n",
                               f.name, 100.0 * f.light_share);
            continue;
        }
        out +=
            fmt::format("  {:<34} {:5.1f} % of the light: scale {:.4f} +- {:.4f} ({:+.1f} % "
                        "+- {:.1f} %) S/N {:.3g}{}\n",
                        f.name, 100.0 * f.light_share, f.scale, f.std_err, 100.0 * (f.scale - 1.0),
                        100.0 * f.std_err, f.signal_to_noise, f.significant ? "  <- off" : "");
        if (f.significant) off.push_back(&f);
    }
    if (off.empty()) {
        double worst = 0.0;
        for (const LayerFit& f : fits)
            if (f.determined)
                worst = std::max(worst, std::abs(f.scale - 1.0) + kLayerSignificanceZ * f.std_err);
        return out + fmt::format("verdict: every determined layer matches (each within {:.1f} "
                                 "%, {:.0f} standard errors)\n",
                                 100.0 * worst, kLayerSignificanceZ);
    }
    for (const LayerFit* f : off) {
        std::string where;
        if (f->main_cell >= 0) {
            const GridCell& c = grid.cells[std::size_t(f->main_cell)];
            where = fmt::format(", largest in region row {} column {} (x {}-{}, y {}-{}: {:.0f} % "
                                "of its deviation)",
                                f->main_cell / grid.cols + 1, f->main_cell % grid.cols + 1, c.x0,
                                c.x1 - 1, c.y0, c.y1 - 1, 100.0 * f->main_cell_share);
        }
        if (f->main_material >= 0 && std::size_t(f->main_material) < material_names.size())
            where += fmt::format(", {} on material '{}' ({:.0f} %)",
                                 f->main_material_share > 0.5 ? "mostly" : "most",
                                 material_names[std::size_t(f->main_material)],
                                 100.0 * f->main_material_share);
        out += fmt::format("verdict: {} is {:.1f} % {} ({:.1f} standard errors){}\n", f->name,
                           100.0 * std::abs(f->scale - 1.0), f->scale < 1.0 ? "dark" : "bright",
                           f->std_err > 0 ? std::abs(f->scale - 1.0) / f->std_err
                                          : std::numeric_limits<double>::infinity(),
                           where);
    }
    return out;
}

} // namespace candela
