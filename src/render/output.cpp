#include "candela/render/output.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace candela {

ImageData film_to_image(const Film& film,
                        const std::vector<std::pair<std::string, std::string>>& metadata) {
    ImageData img;
    img.width = film.width();
    img.height = film.height();
    img.metadata = metadata;
    const AovSet& a = film.aovs();
    auto& ch = img.channel_names;
    ch = {"R", "G", "B", "A"};
    if (a.albedo) ch.insert(ch.end(), {"albedo.R", "albedo.G", "albedo.B"});
    if (a.normal) ch.insert(ch.end(), {"N.X", "N.Y", "N.Z"});
    if (a.depth) ch.push_back("Z");
    if (a.variance) ch.insert(ch.end(), {"variance.R", "variance.G", "variance.B"});
    ch.push_back("samples");
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
            *p++ = n > 0 ? 1.f : 0.f;
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
            if (a.depth) *p++ = film.mean_depth(x, y);
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

std::vector<unsigned char> film_preview(const Film& film, float exposure_ev) {
    const float scale = std::exp2(exposure_ev);
    std::vector<unsigned char> out(std::size_t(film.width()) * film.height() * 3);
    std::size_t i = 0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            Rgb L = film.mean(x, y);
            out[i++] = to_srgb8(L.x, scale);
            out[i++] = to_srgb8(L.y, scale);
            out[i++] = to_srgb8(L.z, scale);
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

std::string path_extension(const std::string& path) {
    std::size_t slash = path.find_last_of('/');
    std::size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

std::string rate_image_path(const std::string& path) {
    std::string ext = path_extension(path);
    std::string stem = path.substr(0, path.size() - ext.size());
    return stem + "_rate.png";
}

} // namespace candela
