// Film to pixels: the EXR's channels and metadata, tone-mapped previews, HDR RGB, camera matrices.
#include "candela/render/output.h"

#include "candela/render/exr_layout.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>

namespace candela {

ImageData film_to_image(const Film& film, const std::vector<Attribute>& attributes,
                        const FrameWindow& window) {
    ImageData img;
    img.width = film.width();
    img.height = film.height();
    img.x = window.x;
    img.y = window.y;
    img.full_width = window.full_width > 0 ? window.full_width : film.width();
    img.full_height = window.full_height > 0 ? window.full_height : film.height();
    img.attributes = attributes;
    const AovSet& a = film.aovs();
    auto& ch = img.channel_names;
    auto add3 = [&ch](const char* const(&names)[3]) { ch.insert(ch.end(), names, names + 3); };
    ch.clear();
    add3(exr::kRgb);
    ch.push_back(exr::kAlpha);
    if (a.albedo) add3(exr::kAlbedo);
    if (a.normal) add3(exr::kNormal);
    if (a.depth) ch.push_back(exr::kDepth);
    if (a.variance) add3(exr::kVariance);
    ch.push_back(exr::kSamples);
    const std::size_t nc = ch.size();
    img.pixels.assign(std::size_t(img.width) * img.height * nc, 0.f);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            float* p = &img.pixels[(std::size_t(y) * img.width + x) * nc];
            std::uint32_t n = film.count(x, y);
            Rgb L = film.mean(x, y);
            *p++ = L.x;
            *p++ = L.y;
            *p++ = L.z;
            *p++ = film.coverage(x, y);
            if (a.albedo) {
                Rgb al = film.mean_albedo(x, y);
                *p++ = al.x;
                *p++ = al.y;
                *p++ = al.z;
            }
            if (a.normal) {
                Vec3 nn = film.mean_normal(x, y);
                *p++ = nn.x;
                *p++ = nn.y;
                *p++ = nn.z;
            }
            if (a.depth) *p++ = film.nearest_depth(x, y);
            if (a.variance) {
                Rgb v = film.variance_of_mean(x, y);
                *p++ = v.x;
                *p++ = v.y;
                *p++ = v.z;
            }
            *p++ = float(n);
        }
    return img;
}

Tonemap parse_tonemap(const std::string& name) {
    return parse_enum(kTonemaps, "--tonemap", name);
}

namespace {

/// The ACES filmic curve as fitted by K. Narkowicz, "ACES Filmic Tone Mapping Curve" (2015):
/// x (a x + b) / (x (c x + d) + e) with the published coefficients, clamped to [0, 1].
float aces_fit(float x) {
    constexpr float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, e = 0.14f;
    if (!(x > 0.f)) return 0.f;
    return std::min(1.f, (x * (a * x + b)) / (x * (c * x + d) + e));
}

} // namespace

Rgb tonemap_color(const Rgb& linear, float exposure_scale, Tonemap t) {
    Rgb v = linear * exposure_scale;
    switch (t) {
    case Tonemap::Clamp:
        return v;
    case Tonemap::Reinhard: {
        // Global operator of Reinhard et al., "Photographic Tone Reproduction for Digital
        // Images" (2002), eq. 3, on luminance; the colour keeps its chromaticity.
        const float lum = luminance(v);
        return lum > 0.f ? v / (1.f + lum) : Rgb(0.f);
    }
    case Tonemap::Filmic:
        return Rgb(aces_fit(v.x), aces_fit(v.y), aces_fit(v.z));
    }
    return v;
}

std::vector<unsigned char> film_preview(const Film& film, float exposure_ev, Tonemap tonemap,
                                        Look look) {
    const float scale = std::exp2(exposure_ev);
    std::vector<unsigned char> out(std::size_t(film.width()) * film.height() * 3);
    std::size_t i = 0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            if (look == Look::Cs184) {
                const Rgb L = film.mean(x, y);
                out[i++] = cs184_encode8(L.x);
                out[i++] = cs184_encode8(L.y);
                out[i++] = cs184_encode8(L.z);
                continue;
            }
            Rgb c = tonemap_color(film.mean(x, y), scale, tonemap);
            out[i++] = to_srgb8(c.x, 1.f);
            out[i++] = to_srgb8(c.y, 1.f);
            out[i++] = to_srgb8(c.z, 1.f);
        }
    return out;
}

unsigned char cs184_encode8(float v) {
    if (!(v > 0.f)) return 0; // NaN and negative values become 0 (spec §7.1)
    const double c = std::min(1.0, std::pow(kCs184Exposure * double(v), 1.0 / kCs184Gamma));
    return static_cast<unsigned char>(std::floor(255.0 * c)); // truncation, not rounding
}

double cs184_decode8(int b) {
    if (b < 0 || b >= 255) throw Error(ErrorKind::Internal, "cs184_decode8: byte out of [0, 254]");
    const double lo = std::pow(double(b) / 255.0, kCs184Gamma);
    const double hi = std::pow(double(b + 1) / 255.0, kCs184Gamma);
    return 0.5 * (lo + hi) / kCs184Exposure;
}

double srgb_decode8(int b) {
    if (b < 0 || b >= 255) throw Error(ErrorKind::Internal, "srgb_decode8: byte out of [0, 254]");
    const double s = double(b) / 255.0;
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

std::vector<float> film_rgb(const Film& film) {
    std::vector<float> out(std::size_t(film.width()) * film.height() * 3);
    std::size_t i = 0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            Rgb L = film.mean(x, y);
            out[i++] = L.x;
            out[i++] = L.y;
            out[i++] = L.z;
        }
    return out;
}

std::vector<unsigned char> film_rate_image(const Film& film, int max_spp) {
    std::vector<unsigned char> out(std::size_t(film.width()) * film.height() * 3);
    std::size_t i = 0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            float r = max_spp > 0 ? float(film.count(x, y)) / float(max_spp) : 0.f;
            Rgb c = sample_rate_color(r);
            // Quantised by truncation as the reference does (spec §7.2).
            out[i++] = static_cast<unsigned char>(std::min(255.f, c.x * 255.f));
            out[i++] = static_cast<unsigned char>(std::min(255.f, c.y * 255.f));
            out[i++] = static_cast<unsigned char>(std::min(255.f, c.z * 255.f));
        }
    return out;
}

std::string rate_legend(int max_spp) {
    // sample_rate_color: blue at 0, green at half the ramp, red at its end and above.
    return fmt::format("blue 0, green {:g}, red {} or more samples per pixel (linear between)",
                       0.5 * double(max_spp), max_spp);
}

std::string rate_image_path(const std::string& path) {
    std::string ext = path_extension(path);
    std::string stem = path.substr(0, path.size() - ext.size());
    return stem + "_rate.png";
}

std::array<float, 16> world_to_camera_matrix(const Camera& c) {
    // Columns: camera x (right), y (up), and the viewing direction -z; the bottom row moves the
    // camera position to the origin.
    const Vec3 fwd = c.z * -1.f;
    std::array<float, 16> m{};
    for (int r = 0; r < 3; ++r) {
        m[std::size_t(4 * r + 0)] = c.x[r];
        m[std::size_t(4 * r + 1)] = c.y[r];
        m[std::size_t(4 * r + 2)] = fwd[r];
        m[std::size_t(4 * r + 3)] = 0.f;
    }
    m[12] = -dot(c.pos, c.x);
    m[13] = -dot(c.pos, c.y);
    m[14] = -dot(c.pos, fwd);
    m[15] = 1.f;
    return m;
}

std::array<float, 16> world_to_ndc_matrix(const Camera& c, int width, int height) {
    // Camera to NDC for row vectors (p_cam P = (X, Y, Z, W)), matching the renderer's camera
    // rays: x_ndc = 0.5 + 0.5 x / (z tan_h), y_ndc = 0.5 - 0.5 y / (z tan_v), with the
    // horizontal field of view spanning the width (integrator.cpp, camera_ray).
    const double tan_h = std::tan(deg_to_rad(0.5 * double(c.hfov_deg)));
    const double tan_v = tan_h * double(height) / double(width);
    const double n = c.znear, f = c.zfar;
    double P[4][4] = {};
    P[0][0] = 0.5 / tan_h;
    P[1][1] = -0.5 / tan_v;
    P[2][0] = 0.5;
    P[2][1] = 0.5;
    P[2][2] = f / (f - n);
    P[2][3] = 1.0;
    P[3][2] = -f * n / (f - n);
    const std::array<float, 16> M = world_to_camera_matrix(c);
    std::array<float, 16> out{};
    for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) {
            double s = 0.0;
            for (int j = 0; j < 4; ++j)
                s += double(M[std::size_t(4 * r + j)]) * P[j][k];
            out[std::size_t(4 * r + k)] = float(s);
        }
    return out;
}

} // namespace candela
