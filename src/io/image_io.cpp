#include "candela/io/image_io.h"
#include "candela/util/error.h"

#include <OpenImageIO/imageio.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unistd.h>

namespace candela {

int ImageData::channel_index(const std::string& name) const {
    for (std::size_t i = 0; i < channel_names.size(); ++i)
        if (channel_names[i] == name) return static_cast<int>(i);
    return -1;
}

std::string ImageData::meta(const std::string& key) const {
    for (const auto& kv : metadata)
        if (kv.first == key) return kv.second;
    return {};
}

std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    std::size_t slash = path.find_last_of('/');
    std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    std::size_t dot = base.find_last_of('.');
    std::string ext = dot == std::string::npos ? "" : base.substr(dot);
    return dir + ".candela-tmp-" + std::to_string(::getpid()) + "-" +
           std::to_string(counter++) + "-" + base + ext;
}

namespace {

// Writes with `write` to a temporary file, then renames over `path`.
template <typename WriteFn> void write_atomically(const std::string& path, WriteFn&& write) {
    std::string tmp = temp_path_for(path);
    std::string why;
    bool ok = false;
    try {
        ok = write(tmp, why);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    if (!ok) {
        std::remove(tmp.c_str());
        throw Error(ErrorKind::Io, path + ": error: cannot write image: " + why);
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        int e = errno;
        std::remove(tmp.c_str());
        throw Error(ErrorKind::Io, path + ": error: cannot write image: " + std::strerror(e));
    }
}

bool write_with_oiio(const std::string& tmp, const OIIO::ImageSpec& spec, const void* data,
                     OIIO::TypeDesc format, std::string& why) {
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) {
        why = OIIO::geterror();
        return false;
    }
    if (!out->open(tmp, spec) || !out->write_image(format, data) || !out->close()) {
        why = out->geterror();
        if (why.empty()) why = "write failed";
        return false;
    }
    return true;
}

} // namespace

void write_exr(const std::string& path, const ImageData& img) {
    OIIO::ImageSpec spec(img.width, img.height, img.channels(), OIIO::TypeDesc::FLOAT);
    spec.channelnames = img.channel_names;
    spec.alpha_channel = img.channel_index("A");
    spec.z_channel = img.channel_index("Z");
    spec.attribute("compression", "zip");
    for (const auto& kv : img.metadata) spec.attribute(kv.first, kv.second);
    write_atomically(path, [&](const std::string& tmp, std::string& why) {
        return write_with_oiio(tmp, spec, img.pixels.data(), OIIO::TypeDesc::FLOAT, why);
    });
}

void write_png(const std::string& path, int width, int height,
               const std::vector<unsigned char>& rgb8) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    write_atomically(path, [&](const std::string& tmp, std::string& why) {
        return write_with_oiio(tmp, spec, rgb8.data(), OIIO::TypeDesc::UINT8, why);
    });
}

ImageData read_image(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string why = OIIO::geterror();
        throw Error(ErrorKind::Io, path + ": error: cannot read image: " + why);
    }
    const OIIO::ImageSpec& spec = in->spec();
    ImageData img;
    img.width = spec.width;
    img.height = spec.height;
    img.channel_names = spec.channelnames;
    img.pixels.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data()))
        throw Error(ErrorKind::Io, path + ": error: cannot read image: " + in->geterror());
    for (const auto& p : spec.extra_attribs)
        if (p.type() == OIIO::TypeDesc::STRING)
            img.metadata.emplace_back(p.name().string(), p.get_string());
    in->close();
    return img;
}

unsigned char to_srgb8(float linear, float exposure_scale) {
    float v = linear * exposure_scale;
    if (!(v > 0.f)) return 0; // negative and NaN map to black
    float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
    s = std::min(1.f, s);
    return static_cast<unsigned char>(std::lround(s * 255.f));
}

Rgb sample_rate_color(float r) {
    const Rgb blue(0, 0, 1), green(0, 1, 0), red(1, 0, 0);
    r = std::min(1.f, std::max(0.f, r));
    if (r <= 0.5f) {
        float t = (0.5f - r) / 0.5f;
        return blue * t + green * (1.f - t);
    }
    float t = (1.f - r) / 0.5f;
    return green * t + red * (1.f - t);
}

} // namespace candela
