// `candela compare`'s measures: reading an image as linear radiance, its error against a
// reference per region, the false-colour error map, and the per-order layer fit.
#include "candela/diagnostics/compare.h"

#include "candela/accel/accel.h"
#include "candela/io/image_io.h"
#include "candela/render/adaptive.h"
#include "candela/render/exr_layout.h"
#include "candela/render/renderer.h"
#include "candela/render/setting_table.h"
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
/// A layer's second half: its seed plus this, far from the other layers' (base + index).
constexpr std::uint64_t kHalfSeedOffset = 0x1'0000'0000ull;

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

/// Whether the sampler an image names (its adaptive attribute) gives every pixel the same sample
/// count; false for a name this build does not know.
bool fixed_sample_count(const std::string& sampler) {
    const auto kind = find_enum(kAdaptiveKinds, sampler);
    if (!kind) return false;
    RenderSettings s;
    s.adaptive = *kind;
    return !make_pass_policy(s)->spreads_samples();
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
    if (eight_bit) {
        img.clip = look == Look::Cs184 ? 1.0 / kCs184Exposure : 1.0;
        img.clipped.assign(img.usable.size(), 0);
    }
    // A fixed sample count is what the clipping loss needs; adaptive sampling varies it.
    // An EXR records it as an int, an 8-bit file as text (PNG text chunks hold strings).
    const Attribute* spp = data.attribute(setting_key(Setting::Spp));
    if (spp && fixed_sample_count(data.meta(setting_key(Setting::Adaptive)))) {
        if (spp->type == Attribute::Type::Int) {
            img.spp = spp->i;
        } else if (spp->type == Attribute::Type::String) {
            char* end = nullptr;
            const long n = std::strtol(spp->text.c_str(), &end, 10);
            if (end != spp->text.c_str() && *end == '\0' && n >= 1 &&
                n <= std::numeric_limits<int>::max())
                img.spp = int(n);
        }
    }
    std::size_t& clipped = img.clipped_count;
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
                    if (!img.clipped[p]) ++clipped;
                    img.clipped[p] = 1;
                    img.usable[p] = 0;
                    out = float(img.clip);
                    continue;
                }
                out =
                    float(look == Look::Cs184 ? cs184_decode8(int(byte)) : srgb_decode8(int(byte)));
            }
        }
    if (eight_bit) {
        // Byte 0's interval: [0, 2 x its middle) under truncation; half of byte 1 under
        // candela's rounding.
        img.black = look == Look::Cs184 ? 2.0 * cs184_decode8(0) : 0.5 * srgb_decode8(1);
    }
    if (!eight_bit) {
        img.clipped.clear();
        img.decoding = "linear radiance as stored";
    } else {
        img.decoding = fmt::format(
            "8-bit, decoded to linear radiance through {}; {} clipped pixels (a channel at 255): "
            "left out of the error, fitted at the white",
            look == Look::Cs184 ? "the inverse of the CS184 curve (exposure sqrt(2), gamma 2.2, "
                                  "truncation)"
                                : "the inverse sRGB curve (candela's look at 0 EV, no tone map)",
            clipped);
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
    r.cell_black.assign(r.grid.cells.size(), 1);
    const double black = std::max(image.black, ref.black);
    ErrorSums whole;
    std::vector<PixelError> pixels;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            if (!image.ok(x, y) || !ref.ok(x, y)) {
                ++r.left_out;
                continue;
            }
            ++r.compared;
            const std::size_t cell_index = std::size_t(r.grid.cell_of(x, y));
            ErrorSums& cell = cell_sums[cell_index];
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
                if (!(a <= black && b <= black)) r.cell_black[cell_index] = 0;
            }
            pixels.push_back(p);
        }
    r.whole = whole.error();
    r.psnr = psnr_of(r.whole.mse);
    for (std::size_t i = 0; i < cell_sums.size(); ++i) {
        const ErrorSums& s = cell_sums[i];
        if (s.count == 0) r.cell_black[i] = 0;
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

namespace {

/// A pixel's structure value: its luminance, capped at the 8-bit image's white (what a clipped
/// pixel is known to reach) and compressed by log(1 + L / scale), so that the light and the
/// walls both count.
std::vector<float> structure_of(const LinearImage& img, double cap, double scale) {
    std::vector<float> out(std::size_t(img.width) * std::size_t(img.height), 0.f);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const Rgb p = img.pixel(x, y);
            // Unusable pixels of an 8-bit image are clipped ones: at least its white.
            const double L = img.ok(x, y) ? double(luminance(p)) : cap;
            out[pixel_index(img, x, y)] =
                float(std::log1p(std::max(0.0, std::min(L, cap)) / scale));
        }
    return out;
}

struct Framing {
    double zoom = 1.0, dx = 0.0, dy = 0.0;
};

/// Pearson correlation of the image's structure with the reference's seen through `f`, over
/// the image pixels whose reference position falls inside it; NaN when they are fewer than
/// kMinRegistrationOverlap of the image.
double framed_correlation(const std::vector<float>& img, const std::vector<float>& ref, int W,
                          int H, const Framing& f) {
    double n = 0, si = 0, sr = 0, sii = 0, srr = 0, sir = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            // The reference position of this pixel's centre, in pixel-centre coordinates.
            const double rx = 0.5 * W + (x + 0.5 - 0.5 * W) / f.zoom + f.dx - 0.5;
            const double ry = 0.5 * H + (y + 0.5 - 0.5 * H) / f.zoom + f.dy - 0.5;
            if (rx < 0.0 || ry < 0.0 || rx > W - 1.0 || ry > H - 1.0) continue;
            const int x0 = std::min(int(rx), W - 2 < 0 ? 0 : W - 2);
            const int y0 = std::min(int(ry), H - 2 < 0 ? 0 : H - 2);
            const int x1 = std::min(x0 + 1, W - 1), y1 = std::min(y0 + 1, H - 1);
            const double tx = rx - x0, ty = ry - y0;
            auto at = [&](int px, int py) { return double(ref[std::size_t(py) * W + px]); };
            const double r = (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x1, y0)) +
                             ty * ((1 - tx) * at(x0, y1) + tx * at(x1, y1));
            const double v = double(img[std::size_t(y) * W + x]);
            n += 1;
            si += v;
            sr += r;
            sii += v * v;
            srr += r * r;
            sir += v * r;
        }
    if (n < kMinRegistrationOverlap * double(W) * double(H))
        return std::numeric_limits<double>::quiet_NaN();
    const double cov = sir - si * sr / n, vi = sii - si * si / n, vr = srr - sr * sr / n;
    return vi > 0 && vr > 0 ? cov / std::sqrt(vi * vr) : 0.0;
}

} // namespace

Registration check_registration(const LinearImage& image, const LinearImage& ref) {
    check_same_size(image, ref);
    const int W = image.width, H = image.height;
    Registration out;
    if (W < 2 || H < 2) return out;
    const double cap =
        std::isfinite(image.clip) ? image.clip : std::numeric_limits<double>::infinity();
    double sum = 0.0, count = 0.0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            if (ref.ok(x, y)) {
                sum += std::min(double(luminance(ref.pixel(x, y))), cap);
                count += 1.0;
            }
    const double scale = count > 0 && sum > 0 ? sum / count : 1.0;
    const std::vector<float> a = structure_of(image, cap, scale), b = structure_of(ref, cap, scale);
    out.identity = framed_correlation(a, b, W, H, Framing{});
    if (!std::isfinite(out.identity)) return out;
    std::vector<Framing> tries;
    for (int dy = -kRegistrationMaxShift; dy <= kRegistrationMaxShift; ++dy)
        for (int dx = -kRegistrationMaxShift; dx <= kRegistrationMaxShift; ++dx)
            if (dx != 0 || dy != 0) tries.push_back({1.0, double(dx), double(dy)});
    for (int k = 1; k <= kRegistrationZoomSteps; ++k) {
        const double z = std::pow(kRegistrationZoomStep, k);
        tries.push_back({z, 0.0, 0.0});
        tries.push_back({1.0 / z, 0.0, 0.0});
    }
    const double course = double(kCourseViewWidth) / double(W);
    if (course != 1.0) {
        tries.push_back({course, 0.0, 0.0});
        tries.push_back({1.0 / course, 0.0, 0.0});
    }
    out.best = out.identity;
    for (const Framing& f : tries) {
        const double c = framed_correlation(a, b, W, H, f);
        if (std::isfinite(c) && c > out.best) {
            out.best = c;
            out.zoom = f.zoom;
            out.dx = f.dx;
            out.dy = f.dy;
        }
    }
    const double unexplained_as_is = 1.0 - out.identity * out.identity;
    const double unexplained_best = 1.0 - out.best * out.best;
    out.misregistered = out.best >= kMinRegistrationCorrelation &&
                        unexplained_best <= kRegistrationGain * unexplained_as_is &&
                        (out.zoom != 1.0 || out.dx != 0.0 || out.dy != 0.0);
    return out;
}

std::string describe_registration(const Registration& r, int width, int height) {
    const double course = double(kCourseViewWidth) / double(width);
    std::string what;
    if (std::abs(r.zoom / course - 1.0) <= kCourseZoomTolerance)
        what = fmt::format("the image is the centre {}x{} of the {}x{} view at that view's pixel "
                           "pitch (candela's view zoomed {:.3g}x), the course's framing; compare "
                           "(and render candela's images) with --framing cs184",
                           width, height, kCourseViewWidth, kCourseViewHeight, r.zoom);
    else if (std::abs(r.zoom * course - 1.0) <= kCourseZoomTolerance)
        what = fmt::format("the image shows the whole view (candela's view zoomed {:.3g}x), while "
                           "the reference has the course's framing; compare with --framing "
                           "candela",
                           r.zoom);
    else if (r.zoom != 1.0)
        what = fmt::format("the image is candela's view zoomed {:.3g}x about its centre: a "
                           "different field of view or camera",
                           r.zoom);
    else
        what = fmt::format("the image is candela's view shifted by ({:+g}, {:+g}) pixels: a "
                           "different camera position or pixel-centre convention",
                           r.dx, r.dy);
    return fmt::format("verdict: the image is not framed like the reference (structure "
                       "correlation {:.3f} as it is, {:.3f} reframed): {}; the scale fit needs "
                       "both framed alike, so it is not made\n",
                       r.identity, r.best, what);
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
    use_uniform_sampler(base);
    base.time_budget = 0.0;
    base.region = Region{};
    base.quiet = true;
    std::vector<LayerSpec> out;
    auto add = [&](const std::string& name, RenderSettings s, int order) {
        s.seed = kLayerSeedBase + std::uint64_t(out.size());
        out.push_back({name, s, order});
    };
    if (split == LayerSplit::DirectIndirect) {
        for (LightPaths lp : {LightPaths::Direct, LightPaths::Indirect}) {
            if (image.light_paths != LightPaths::All && image.light_paths != lp) continue;
            RenderSettings s = base;
            s.light_paths = lp;
            add(lp == LightPaths::Direct ? "direct (orders 0-1)" : "indirect (orders 2+)", s, -1);
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
        add("order " + std::to_string(k) + " (" + order_name(k) + ")", s, k);
    }
    return out;
}

std::vector<Layer> render_layers(const Scene& scene, const std::vector<LayerSpec>& specs) {
    std::vector<Layer> out;
    for (const LayerSpec& spec : specs) {
        if (spec.settings.spp < 2)
            throw Error(ErrorKind::Usage, "-s/--spp: the layers need at least 2 samples per "
                                          "pixel (two independent halves each)");
        std::unique_ptr<Accel> accel = make_accel(scene, spec.settings.accel);
        auto render_half = [&](int spp, std::uint64_t seed) {
            RenderSettings s = spec.settings;
            s.spp = spp;
            s.seed = seed;
            Renderer r(scene, *accel, s);
            RenderStats stats;
            return r.render(stats);
        };
        Layer layer;
        layer.name = spec.name;
        layer.order = spec.order;
        layer.half_a = render_half((spec.settings.spp + 1) / 2, spec.settings.seed);
        layer.half_b = render_half(spec.settings.spp / 2, spec.settings.seed + kHalfSeedOffset);
        layer.film = layer.half_a;
        layer.film.merge(layer.half_b);
        out.push_back(std::move(layer));
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

namespace {

/// How a layer enters a grouped fit besides a group of its own: at a fixed scale.
constexpr int kAtOne = -1;  ///< taken as it is (scale 1)
constexpr int kAtZero = -2; ///< taken as absent from the image (scale 0)

/// The pixels a fit uses: usable in `image` and, for an 8-bit image, not near its white
/// (kFitClipMargin). Whether a pixel is near the white is judged from its neighbours' values in
/// candela's layers, never its own: a pixel's own layer noise must not decide whether the
/// pixel is fitted (docs/convergence.md "8-bit images").
std::vector<std::uint8_t> fit_mask(const LinearImage& image, const std::vector<Layer>& layers) {
    const int W = image.width, H = image.height;
    std::vector<std::uint8_t> mask(std::size_t(W) * std::size_t(H), 0);
    std::vector<float> peak(mask.size(), 0.f);
    if (std::isfinite(image.clip))
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                Rgb sum(0.f);
                for (const Layer& l : layers)
                    sum += l.film.mean(x, y);
                peak[pixel_index(image, x, y)] = std::max({sum.x, sum.y, sum.z});
            }
    const float limit = float(kFitClipMargin * image.clip);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            // A clipped pixel away from the white in candela's layers is fitted at the white
            // (with the expected clipping loss added back): leaving it out would keep only the
            // pixels whose own noise stayed low, and bias the fit dark.
            if (!image.fitted(x, y)) continue;
            bool near_white = false;
            for (int dy = -1; dy <= 1 && !near_white; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    if (peak[pixel_index(image, nx, ny)] >= limit) {
                        near_white = true;
                        break;
                    }
                }
            if (!near_white) mask[pixel_index(image, x, y)] = 1;
        }
    return mask;
}

} // namespace

std::size_t fitted_clipped(const LinearImage& image, const std::vector<Layer>& layers) {
    if (image.clipped_count == 0) return 0;
    const std::vector<std::uint8_t> mask = fit_mask(image, layers);
    std::size_t n = 0;
    for (std::size_t p = 0; p < mask.size(); ++p)
        n += mask[p] && image.clipped[p] ? 1 : 0;
    return n;
}

void add_clipping_loss(LinearImage& image, const std::vector<Layer>& layers, const Scene& scene,
                       const RenderSettings& settings) {
    if (fitted_clipped(image, layers) == 0 || image.spp < 1) return;
    CANDELA_CHECK(settings.width == image.width && settings.height == image.height,
                  "add_clipping_loss: settings and image differ in size");
    const int replicas = std::max(kClipLossMinReplicas, kClipLossSamples / image.spp);
    std::unique_ptr<Accel> accel = make_accel(scene, settings.accel);
    std::vector<double> sum(image.rgb.size(), 0.0);
    for (int r = 0; r < replicas; ++r) {
        RenderSettings s = settings;
        s.spp = image.spp;
        s.seed = kClipLossSeedBase + std::uint64_t(r);
        use_uniform_sampler(s);
        s.aovs = AovSet::parse("none");
        s.time_budget = 0.0;
        s.region = Region{};
        s.quiet = true;
        Renderer renderer(scene, *accel, s);
        RenderStats stats;
        const LinearImage replica = linear_image(renderer.render(stats));
        for (std::size_t i = 0; i < sum.size(); ++i)
            sum[i] += std::max(0.0, double(replica.rgb[i]) - image.clip);
    }
    image.clip_loss.resize(sum.size());
    for (std::size_t i = 0; i < sum.size(); ++i)
        image.clip_loss[i] = float(sum[i] / double(replicas));
}

namespace {

/// Fits image ~ sum_g s_g (sum of group g's layers) + the fixed layers, over the entries of
/// `mask`. group_of[k] is layer k's group (0..groups-1), kAtOne or kAtZero. A group whose light
/// is below kMinLayerSignalToNoise of its noise is undetermined and enters at scale 1. Returns
/// one LayerFit per group (named by the caller) and, in `layer_share`, each layer's share of
/// the layers' light in the fitted pixels.
std::vector<LayerFit> fit_groups(const LinearImage& image, const std::vector<Layer>& layers,
                                 const std::vector<int>& group_of, std::size_t groups,
                                 const std::vector<std::uint8_t>& mask, const RegionGrid& grid,
                                 const std::vector<int>& materials,
                                 std::vector<double>* layer_share) {
    const std::size_t K = groups;
    std::vector<LayerFit> fits(K);
    std::vector<double> each_light(layers.size(), 0.0);
    bool first_pass = true;
    // Sums over the fitted pixel channels: A^T A, the halves' product
    // (A_a^T A_b + A_b^T A_a) / 2, A^T b, each group's summed variance and light.
    std::vector<double> ata(K * K, 0.0), cross(K * K, 0.0), atb(K, 0.0), var(K, 0.0), light(K, 0.0);
    std::vector<double> a(K), v(K), ha(K), hb(K);
    // b is the image minus the layers taken at scale 1.
    auto for_each_entry = [&](auto&& f) {
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x) {
                if (!mask[pixel_index(image, x, y)]) continue;
                for (int c = 0; c < 3; ++c) {
                    std::fill(a.begin(), a.end(), 0.0);
                    std::fill(v.begin(), v.end(), 0.0);
                    std::fill(ha.begin(), ha.end(), 0.0);
                    std::fill(hb.begin(), hb.end(), 0.0);
                    // The image's value plus the light its white is expected to clip: the
                    // loss's spread over its replicas is part of each entry's residual, so the
                    // sandwich standard error below carries it.
                    double b = double(image.at(x, y, c)), total = 0.0;
                    if (!image.clip_loss.empty())
                        b += double(image.clip_loss[pixel_index(image, x, y) * 3 + std::size_t(c)]);
                    for (std::size_t k = 0; k < layers.size(); ++k) {
                        const double m = double(layers[k].film.mean(x, y)[c]);
                        total += m;
                        if (first_pass) each_light[k] += m;
                        if (group_of[k] >= 0) {
                            const std::size_t g = std::size_t(group_of[k]);
                            a[g] += m;
                            v[g] += double(layers[k].film.variance_of_mean(x, y)[c]);
                            ha[g] += double(layers[k].half_a.mean(x, y)[c]);
                            hb[g] += double(layers[k].half_b.mean(x, y)[c]);
                        } else if (group_of[k] == kAtOne) {
                            b -= m;
                        }
                    }
                    f(x, y, b);
                }
            }
    };
    for_each_entry([&](int, int, double b) {
        for (std::size_t i = 0; i < K; ++i) {
            for (std::size_t j = 0; j < K; ++j) {
                ata[i * K + j] += a[i] * a[j];
                cross[i * K + j] += 0.5 * (ha[i] * hb[j] + hb[i] * ha[j]);
            }
            atb[i] += a[i] * b;
            var[i] += v[i];
            light[i] += a[i];
        }
    });
    first_pass = false;
    const double all_light = std::accumulate(each_light.begin(), each_light.end(), 0.0);
    if (layer_share)
        for (double l : each_light)
            layer_share->push_back(all_light > 0 ? l / all_light : 0.0);
    // The groups that carry light above their noise take part in the fit; the others keep the
    // scale 1 they are assumed to have and are reported as undetermined.
    std::vector<std::size_t> in;
    for (std::size_t k = 0; k < K; ++k) {
        fits[k].light_share = all_light > 0 ? light[k] / all_light : 0.0;
        // The halves' noise is independent: their product estimates the light's energy alone.
        const double signal = cross[k * K + k];
        fits[k].signal_to_noise = var[k] > 0 ? signal / var[k] : 0.0;
        if (signal > kMinLayerSignalToNoise * var[k] && signal > 0.0) in.push_back(k);
    }
    // An undetermined group's closest look-alike: the group whose light is most nearly
    // proportional to its own over the fitted pixels (cosine of the two images).
    for (std::size_t k = 0; k < K; ++k) {
        if (std::find(in.begin(), in.end(), k) != in.end()) continue;
        for (std::size_t j = 0; j < K; ++j) {
            const double norm = std::sqrt(ata[k * K + k] * ata[j * K + j]);
            if (j == k || !(norm > 0)) continue;
            const double cosine = ata[k * K + j] / norm;
            if (cosine > fits[k].like_cosine) {
                fits[k].like = int(j);
                fits[k].like_cosine = cosine;
            }
        }
    }
    const std::size_t n = in.size();
    if (n == 0) return fits;
    // Normal equations without the layers' noise: E[A^T A] = M^T M + diag(sum Var), but the
    // two halves' noise is independent, so E[(A_a^T A_b + A_b^T A_a) / 2] = M^T M with no
    // variance to estimate (a sample variance of heavy-tailed paths runs low, and at a small
    // S/N its shortfall biased the scale towards 0). The undetermined groups enter b at 1.
    std::vector<double> G(n * n), h(n), s;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < n; ++j)
            G[i * n + j] = cross[in[i] * K + in[j]];
        h[i] = atb[in[i]];
        for (std::size_t k = 0; k < K; ++k)
            if (std::find(in.begin(), in.end(), k) == in.end()) h[i] -= ata[in[i] * K + k];
    }
    if (!solve_spd(G, s, h, n)) return fits;
    // Sandwich covariance G^-1 (sum psi psi^T) G^-1 from each pixel's term of the estimating
    // equation, psi_i = sum over its channels of a_i (b - fixed) - sum_j c_ij s_j (c the halves'
    // product): the pixels' terms are independent with mean 0 at the true scales and carry the
    // image's noise, the layers' (in both A^T b and G) and whatever the model misses. A pixel's
    // three channels come from the same paths and are correlated (a white light's path moves
    // all three), so they are summed into one term before the outer product; taken as three
    // independent terms they understated the standard errors about 1.5-fold.
    std::vector<double> B(n * n, 0.0), psi(n), pixel_psi(n, 0.0);
    long pixel_at = -1; // index of the pixel whose channels pixel_psi holds
    auto add_pixel = [&] {
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = 0; j < n; ++j)
                B[i * n + j] += pixel_psi[i] * pixel_psi[j];
        std::fill(pixel_psi.begin(), pixel_psi.end(), 0.0);
    };
    std::vector<std::vector<double>> cell_dev(n, std::vector<double>(grid.cells.size(), 0.0));
    int material_count = 0;
    for (int m : materials)
        material_count = std::max(material_count, m + 1);
    std::vector<std::vector<double>> material_dev(
        n, std::vector<double>(std::size_t(material_count), 0.0));
    for_each_entry([&](int x, int y, double b) {
        double target = b;
        for (std::size_t k = 0; k < K; ++k)
            if (std::find(in.begin(), in.end(), k) == in.end()) target -= a[k];
        for (std::size_t i = 0; i < n; ++i) {
            psi[i] = a[in[i]] * target;
            for (std::size_t j = 0; j < n; ++j)
                psi[i] -= 0.5 * (ha[in[i]] * hb[in[j]] + hb[in[i]] * ha[in[j]]) * s[j];
        }
        const long pixel = long(pixel_index(image, x, y));
        if (pixel != pixel_at && pixel_at >= 0) add_pixel();
        pixel_at = pixel;
        const int cell = grid.cell_of(x, y);
        for (std::size_t i = 0; i < n; ++i) {
            pixel_psi[i] += psi[i];
            const double dev = (s[i] - 1.0) * a[in[i]];
            cell_dev[i][std::size_t(cell)] += dev * dev;
            if (!materials.empty()) {
                const int m = materials[pixel_index(image, x, y)];
                if (m >= 0) material_dev[i][std::size_t(m)] += dev * dev;
            }
        }
    });
    if (pixel_at >= 0) add_pixel();
    std::vector<double> ginv(n * n), e(n), col;
    for (std::size_t j = 0; j < n; ++j) {
        std::fill(e.begin(), e.end(), 0.0);
        e[j] = 1.0;
        solve_spd(G, col, e, n);
        for (std::size_t i = 0; i < n; ++i)
            ginv[i * n + j] = col[i];
    }
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < n; ++j) {
            double c = 0.0;
            for (std::size_t p = 0; p < n; ++p)
                for (std::size_t q = 0; q < n; ++q)
                    c += ginv[i * n + p] * B[p * n + q] * ginv[q * n + j];
            if (i != j) continue;
            LayerFit& f = fits[in[i]];
            f.determined = true;
            f.scale = s[i];
            f.std_err = std::sqrt(std::max(0.0, c));
            f.significant = std::abs(f.scale - 1.0) > kLayerSignificanceZ * f.std_err;
        }
        LayerFit& f = fits[in[i]];
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

void check_layers(const LinearImage& image, const std::vector<Layer>& layers) {
    for (const Layer& l : layers) {
        if (l.film.width() != image.width || l.film.height() != image.height)
            throw Error(ErrorKind::Usage, "the layers are " + std::to_string(l.film.width()) + "x" +
                                              std::to_string(l.film.height()) + ", the image " +
                                              std::to_string(image.width) + "x" +
                                              std::to_string(image.height));
        CANDELA_CHECK(l.film.aovs().variance, "fit_layers: a layer has no variance channel");
        CANDELA_CHECK(l.half_a.width() == l.film.width() && l.half_b.width() == l.film.width() &&
                          l.half_a.height() == l.film.height() &&
                          l.half_b.height() == l.film.height(),
                      "fit_layers: a layer has no halves");
    }
}

/// One group per layer, with the layers' names; layers from `first_absent` on at scale 0.
std::vector<LayerFit> fit_each(const LinearImage& image, const std::vector<Layer>& layers,
                               std::size_t first_absent, const std::vector<std::uint8_t>& mask,
                               const RegionGrid& grid, const std::vector<int>& materials) {
    std::vector<int> group_of(layers.size());
    for (std::size_t k = 0; k < layers.size(); ++k)
        group_of[k] = k < first_absent ? int(k) : kAtZero;
    std::vector<double> share;
    std::vector<LayerFit> fits =
        fit_groups(image, layers, group_of, std::min(first_absent, layers.size()), mask, grid,
                   materials, &share);
    fits.resize(layers.size());
    for (std::size_t k = 0; k < fits.size(); ++k) {
        fits[k].name = layers[k].name;
        if (fits[k].like >= 0) fits[k].like_name = layers[std::size_t(fits[k].like)].name;
        if (k >= first_absent) {
            fits[k].absent = true;
            fits[k].light_share = share[k];
        }
    }
    return fits;
}

} // namespace

std::vector<LayerFit> fit_layers(const LinearImage& image, const std::vector<Layer>& layers,
                                 const RegionGrid& grid, const std::vector<int>& materials) {
    check_layers(image, layers);
    return fit_each(image, layers, layers.size(), fit_mask(image, layers), grid, materials);
}

LayerAnalysis analyse_layers(const LinearImage& image, const std::vector<Layer>& layers,
                             const RegionGrid& grid, const std::vector<int>& materials) {
    check_layers(image, layers);
    const bool orders =
        std::all_of(layers.begin(), layers.end(), [](const Layer& l) { return l.order >= 0; });
    LayerAnalysis out;
    const std::vector<std::uint8_t> mask = fit_mask(image, layers);
    // Missing orders: the smallest k (past the first layer) such that the layers from k on,
    // fitted as one, are absent from the image (scale 0 within kLayerSignificanceZ standard
    // errors) and not all there (scale 1 outside them).
    if (orders)
        for (std::size_t first = 1; first < layers.size() && out.first_missing < 0; ++first) {
            std::vector<int> group_of(layers.size());
            for (std::size_t k = 0; k < layers.size(); ++k)
                group_of[k] = int(std::min(k, first));
            const std::vector<LayerFit> fits =
                fit_groups(image, layers, group_of, first + 1, mask, grid, materials, nullptr);
            const LayerFit& tail = fits[first];
            if (tail.determined && std::abs(tail.scale) <= kLayerSignificanceZ * tail.std_err &&
                std::abs(tail.scale - 1.0) > kLayerSignificanceZ * tail.std_err) {
                out.first_missing = layers[first].order;
                out.missing = tail;
            }
        }
    std::size_t first_absent = layers.size();
    if (out.first_missing >= 0)
        for (std::size_t k = 0; k < layers.size(); ++k)
            if (layers[k].order == out.first_missing) first_absent = k;
    out.fits = fit_each(image, layers, first_absent, mask, grid, materials);
    // One common factor: the present layers as one.
    std::vector<int> group_of(layers.size());
    for (std::size_t k = 0; k < layers.size(); ++k)
        group_of[k] = k < first_absent ? 0 : kAtZero;
    out.common = fit_groups(image, layers, group_of, 1, mask, grid, materials, nullptr).front();
    out.common.name = "the whole image";
    bool agree = out.common.determined;
    for (const LayerFit& f : out.fits)
        if (f.determined && std::abs(f.scale - out.common.scale) >
                                kLayerSignificanceZ * std::hypot(f.std_err, out.common.std_err))
            agree = false;
    out.common_explains = agree;
    if (image.clip_loss.empty()) out.clipped_unknown_spp = fitted_clipped(image, layers);
    return out;
}

namespace {

std::string describe_analysis_body(const LayerAnalysis& analysis, const RegionGrid& grid,
                                   const std::vector<std::string>& material_names) {
    std::string out;
    std::vector<const LayerFit*> off;
    const bool missing = analysis.first_missing >= 0;
    for (const LayerFit& f : analysis.fits) {
        if (f.absent) {
            out += fmt::format("  {:<34} {:5.1f} % of the light: missing from the image (taken "
                               "as 0)\n",
                               f.name, 100.0 * f.light_share);
            continue;
        }
        if (!f.determined && f.light_share < kNoLightShare) {
            out += fmt::format("  {:<34} {:5.1f} % of the light: undetermined (next to none of "
                               "its light is in the compared pixels: clipped or left out; taken "
                               "as 1)\n",
                               f.name, 100.0 * f.light_share);
            continue;
        }
        if (!f.determined) {
            out += fmt::format("  {:<34} {:5.1f} % of the light: undetermined (", f.name,
                               100.0 * f.light_share);
            out += fmt::format("too noisy: its light in the compared pixels is {:.2g} times "
                               "its noise, under {:.0f}; more -s helps",
                               std::max(0.0, f.signal_to_noise), kMinLayerSignalToNoise);
            if (!f.like_name.empty())
                out += fmt::format(
                    "; most like {} here (cosine {:.2f}){}", f.like_name, f.like_cosine,
                    f.like_cosine >= kLookAlikeCosine ? ", which the fit cannot tell it apart from"
                                                      : "");
            out += "; taken as 1)\n";
            continue;
        }
        out +=
            fmt::format("  {:<34} {:5.1f} % of the light: scale {:.4f} +- {:.4f} ({:+.1f} % "
                        "+- {:.1f} %) S/N {:.3g}{}\n",
                        f.name, 100.0 * f.light_share, f.scale, f.std_err, 100.0 * (f.scale - 1.0),
                        100.0 * f.std_err, f.signal_to_noise, f.significant ? "  <- off" : "");
        if (f.significant) off.push_back(&f);
    }
    if (missing) {
        const LayerFit& m = analysis.missing;
        out += fmt::format("verdict: orders {} and above are missing (rendered with a lower -m?): "
                           "the image has {:.1f} % +- {:.1f} % of their light\n",
                           analysis.first_missing, 100.0 * m.scale, 100.0 * m.std_err);
        if (off.empty()) return out;
    } else if (analysis.common_explains && analysis.common.significant) {
        const LayerFit& c = analysis.common;
        return out + fmt::format("verdict: the whole image is {:.1f} % {} (scale {:.4f} +- {:.4f}, "
                                 "{:.1f} standard errors): every determined order agrees with "
                                 "this one factor, an exposure or scale of the whole image "
                                 "rather than one order's light\n",
                                 100.0 * std::abs(c.scale - 1.0), c.scale < 1.0 ? "dark" : "bright",
                                 c.scale, c.std_err, std::abs(c.scale - 1.0) / c.std_err);
    }
    if (off.empty()) {
        double worst = 0.0;
        for (const LayerFit& f : analysis.fits)
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

} // namespace

std::string describe_layer_analysis(const LayerAnalysis& analysis, const RegionGrid& grid,
                                    const std::vector<std::string>& material_names) {
    std::string out = describe_analysis_body(analysis, grid, material_names);
    if (analysis.clipped_unknown_spp > 0)
        out += fmt::format("verdict: with caution: {} clipped pixels are fitted at the white "
                           "without the light it is expected to clip, which depends on the "
                           "image's samples per pixel: give --image-spp N (an image of few "
                           "samples reads dark)\n",
                           analysis.clipped_unknown_spp);
    return out;
}

std::string describe_layer_fit(const std::vector<LayerFit>& fits, const RegionGrid& grid,
                               const std::vector<std::string>& material_names) {
    LayerAnalysis analysis;
    analysis.fits = fits;
    return describe_layer_analysis(analysis, grid, material_names);
}

} // namespace candela
