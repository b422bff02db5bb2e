// Image files through the OpenImageIO module: loading it, reading, writing atomically, format
// checks.
#include "candela/io/image_io.h"

#include "candela/io/image_module.h"
#include "candela/util/error.h"
#include "candela/util/strings.h"
#include "candela/version.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <unistd.h>
#include <vector>

namespace candela {

std::string Attribute::str() const {
    switch (type) {
    case Type::String:
        return text;
    case Type::Int:
        return std::to_string(i);
    case Type::Float:
        // 9 significant digits read back as the same float.
        return fmt::format("{:.9g}", double(f));
    case Type::Double:
        // 17 significant digits read back as the same double.
        return fmt::format("{:.17g}", d);
    case Type::Matrix44: {
        std::string s;
        for (int k = 0; k < 16; ++k) {
            s += (k ? ", " : "") + fmt::format("{:.9g}", double(m[std::size_t(k)]));
        }
        return s;
    }
    case Type::Floats: {
        std::string s;
        for (std::size_t k = 0; k < floats.size(); ++k) {
            s += (k ? ", " : "") + fmt::format("{:.9g}", double(floats[k]));
        }
        return s;
    }
    }
    return text;
}

const char* Attribute::type_name() const {
    switch (type) {
    case Type::String:
        return "string";
    case Type::Int:
        return "int";
    case Type::Float:
        return "float";
    case Type::Double:
        return "double";
    case Type::Matrix44:
        return "matrix";
    case Type::Floats:
        return "float[]";
    }
    return "string";
}

int ImageData::channel_index(const std::string& name) const {
    for (std::size_t i = 0; i < channel_names.size(); ++i)
        if (channel_names[i] == name) return static_cast<int>(i);
    return -1;
}

const Attribute* ImageData::attribute(const std::string& key) const {
    for (const Attribute& a : attributes)
        if (a.name == key) return &a;
    return nullptr;
}

std::string ImageData::meta(const std::string& key) const {
    const Attribute* a = attribute(key);
    return a ? a->str() : std::string();
}

void ImageData::set(const Attribute& a) {
    for (Attribute& b : attributes)
        if (b.name == a.name) {
            b = a;
            return;
        }
    attributes.push_back(a);
}

std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    std::size_t slash = path.find_last_of('/');
    std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    std::size_t dot = base.find_last_of('.');
    std::string ext = dot == std::string::npos ? "" : base.substr(dot);
    return dir + ".candela-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
           "-" + base + ext;
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
        throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write image: " + why);
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        int e = errno;
        std::remove(tmp.c_str());
        throw Error(ErrorKind::Io, SourceLoc{path},
                    std::string("cannot write image: ") + std::strerror(e));
    }
}

/// Where libcandela_image.so (image_module.h) is looked for, in order: $CANDELA_IMAGE_MODULE
/// when set, else beside the executable (the build tree), in the install tree's library
/// directory relative to it, and, for test and tool binaries inside the build tree only, at the
/// build tree's absolute path. An installed candela never falls back to a build tree's module:
/// that one may be of another build, or vanish with the build directory.
std::vector<std::string> image_module_candidates() {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("CANDELA_IMAGE_MODULE"); env && *env) {
        candidates.push_back(env);
        return candidates;
    }
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const std::filesystem::path dir = exe.parent_path();
        candidates.push_back((dir / CANDELA_IMAGE_MODULE_NAME).string());
        candidates.push_back(
            (dir / CANDELA_IMAGE_MODULE_INSTALL_RELDIR / CANDELA_IMAGE_MODULE_NAME).string());
        const std::filesystem::path build_dir =
            std::filesystem::path(CANDELA_IMAGE_MODULE_BUILD_PATH).parent_path();
        const std::filesystem::path rel = exe.lexically_relative(build_dir);
        if (!rel.empty() && *rel.begin() != "..")
            candidates.push_back(CANDELA_IMAGE_MODULE_BUILD_PATH);
    }
    return candidates;
}

Error module_load_error(const std::string& reasons) {
    return Error(ErrorKind::Io, "cannot load the image module (image files are read and "
                                "written through it): " +
                                    reasons);
}

/// Loads the module from the first candidate that is one.
const image_module::Api* load_image_module() {
    std::string reasons;
    for (const std::string& path : image_module_candidates()) {
        void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* e = ::dlerror();
            reasons += std::string(reasons.empty() ? "" : "; ") + (e ? e : path);
            continue;
        }
        auto entry =
            reinterpret_cast<image_module::EntryPoint>(::dlsym(handle, image_module::kEntryPoint));
        const image_module::Api* api = entry ? entry() : nullptr;
        if (!api || api->abi_version != image_module::kAbiVersion) {
            reasons += std::string(reasons.empty() ? "" : "; ") + path +
                       ": not a candela image module of this version";
            ::dlclose(handle);
            continue;
        }
        return api; // kept loaded for the life of the process
    }
    throw module_load_error(reasons);
}

/// The module, loaded by the first caller; a caller on another thread waits for that load
/// (a function-local static). A failed load throws, and the next caller tries again.
const image_module::Api& image_api() {
    static const image_module::Api* api = load_image_module();
    return *api;
}

bool write_with_module(const std::string& tmp, const image_module::WriteRequest& req,
                       std::string& why) {
    return image_api().write(tmp, req, why);
}

/// A request for an interleaved image without windows, names or attributes.
image_module::WriteRequest plain_request(int width, int height, int channels,
                                         image_module::PixelType type, const void* pixels) {
    image_module::WriteRequest req;
    req.width = width;
    req.height = height;
    req.channels = channels;
    req.type = type;
    req.pixels = pixels;
    return req;
}

/// OpenImageIO's format name for an extension (without the dot), "" when none reads it.
std::string format_for_extension(const std::string& ext) {
    // "format:ext,ext;format:ext,..."
    const std::string list = image_api().extension_list();
    std::size_t pos = 0;
    while (pos < list.size()) {
        std::size_t end = list.find(';', pos);
        if (end == std::string::npos) end = list.size();
        const std::string entry = list.substr(pos, end - pos);
        const std::size_t colon = entry.find(':');
        if (colon != std::string::npos) {
            const std::string exts = "," + entry.substr(colon + 1) + ",";
            if (exts.find("," + ext + ",") != std::string::npos) return entry.substr(0, colon);
        }
        pos = end + 1;
    }
    return "";
}

bool format_writable(const std::string& format) {
    if (format.empty()) return false;
    // Writers that produce no image file.
    if (format == "null" || format == "term") return false;
    const std::string list = "," + image_api().output_format_list() + ",";
    return list.find("," + format + ",") != std::string::npos;
}

/// The standard attribute naming the RGB primaries and white point.
constexpr const char* kChromaticities = "chromaticities";

/// The operating system's reason an existing-or-not file cannot be opened for reading.
std::string open_reason(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return std::strerror(errno);
    std::fclose(f);
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return "is a directory";
    return "";
}

} // namespace

const std::vector<std::string>& exr_compressions() {
    // OpenEXR's names: none, rle, zips, zip, piz lossless; pxr24 rounds floats to 24 bits;
    // b44, b44a, dwaa, dwab are lossy on half channels.
    static const std::vector<std::string> names = {"zip",   "zips", "piz",  "rle",  "none",
                                                   "pxr24", "b44",  "b44a", "dwaa", "dwab"};
    return names;
}

void write_exr(const std::string& path, const ImageData& image, const ExrOptions& opt) {
    // A finite background depth is written into a copy: the caller's image keeps the film's +inf.
    ImageData with_background;
    const int z = image.channel_index("Z");
    if (z >= 0 && !std::isinf(opt.background_depth)) {
        with_background = image;
        const std::size_t nc = std::size_t(image.channels());
        for (std::size_t i = std::size_t(z); i < with_background.pixels.size(); i += nc)
            if (std::isinf(with_background.pixels[i]))
                with_background.pixels[i] = opt.background_depth;
    }
    const ImageData& img = with_background.pixels.empty() ? image : with_background;
    std::vector<Attribute> attributes = img.attributes;
    if (!img.attribute(kChromaticities))
        attributes.emplace_back(kChromaticities, kRec709Chromaticities);
    std::vector<unsigned char> half(img.channel_names.size(), 0);
    for (std::size_t c = 0; c < half.size(); ++c)
        half[c] = std::count(opt.half_channels.begin(), opt.half_channels.end(),
                             img.channel_names[c]) > 0;
    image_module::WriteRequest req;
    req.width = img.width;
    req.height = img.height;
    req.channels = img.channels();
    req.x = img.x;
    req.y = img.y;
    req.full_width = img.display_width();
    req.full_height = img.display_height();
    req.type = image_module::PixelType::Float;
    req.pixels = img.pixels.data();
    req.channel_names = &img.channel_names;
    req.attributes = &attributes;
    req.alpha_channel = img.channel_index("A");
    req.z_channel = z;
    req.compression = opt.compression.c_str();
    req.half_channels = &half;
    write_atomically(path, [&](const std::string& tmp, std::string& why) {
        return write_with_module(tmp, req, why);
    });
}

void write_image8(const std::string& path, int width, int height,
                  const std::vector<unsigned char>& rgb8,
                  const std::vector<Attribute>& attributes) {
    auto req = plain_request(width, height, 3, image_module::PixelType::UInt8, rgb8.data());
    req.attributes = &attributes;
    write_atomically(path, [&](const std::string& tmp, std::string& why) {
        return write_with_module(tmp, req, why);
    });
}

void write_png(const std::string& path, int width, int height,
               const std::vector<unsigned char>& rgb8, const std::vector<Attribute>& attributes) {
    write_image8(path, width, height, rgb8, attributes);
}

void write_image_float(const std::string& path, int width, int height,
                       const std::vector<float>& rgb, const std::vector<Attribute>& attributes) {
    auto req = plain_request(width, height, 3, image_module::PixelType::Float, rgb.data());
    req.attributes = &attributes;
    write_atomically(path, [&](const std::string& tmp, std::string& why) {
        return write_with_module(tmp, req, why);
    });
}

ImageData read_image(const std::string& path) {
    const image_module::Api& api = image_api();
    ImageData img;
    std::string why;
    if (!api.read(path, img, why)) {
        const std::string os_reason = open_reason(path);
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot read image: " + (os_reason.empty() ? why : os_reason));
    }
    return img;
}

OutputKind output_kind(const std::string& path) {
    // Without its dot: the names OpenImageIO's format catalogue lists.
    const std::string dotted = path_extension(path);
    if (dotted.size() < 2) return OutputKind::Unsupported;
    const std::string ext = dotted.substr(1);
    // The usual ones without asking OpenImageIO (whose format catalogue costs a start-up).
    if (ext == "exr") return OutputKind::Exr;
    if (ext == "hdr" || ext == "pfm") return OutputKind::Hdr;
    if (ext == "png" || ext == "jpg" || ext == "jpeg" || ext == "tif" || ext == "tiff")
        return OutputKind::Ldr;
    const std::string format = format_for_extension(ext);
    if (format == "openexr") return OutputKind::Exr;
    if (!format_writable(format)) return OutputKind::Unsupported;
    // Formats that store float pixels: written as linear radiance, like the EXR.
    if (format == "hdr" || ext == "pfm") return OutputKind::Hdr;
    return OutputKind::Ldr;
}

std::string writable_extensions() {
    // The usual ones first, then every other format OpenImageIO can write here.
    std::vector<std::string> exts = {".exr", ".png", ".jpg", ".tif", ".hdr"};
    const std::string list = image_api().extension_list();
    std::size_t pos = 0;
    while (pos < list.size()) {
        std::size_t end = list.find(';', pos);
        if (end == std::string::npos) end = list.size();
        const std::string entry = list.substr(pos, end - pos);
        const std::size_t colon = entry.find(':');
        if (colon != std::string::npos && format_writable(entry.substr(0, colon))) {
            std::string first = entry.substr(colon + 1);
            first = first.substr(0, first.find(','));
            if (std::find(exts.begin(), exts.end(), "." + first) == exts.end())
                exts.push_back("." + first);
        }
        pos = end + 1;
    }
    std::string out;
    for (const std::string& e : exts)
        out += (out.empty() ? "" : ", ") + e;
    return out;
}

void check_image_writable(const std::string& path, OutputKind kind) {
    check_image_location(path);
    check_image_format(path, kind);
}

void check_image_location(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write: it is a directory");
    const fs::path parent = fs::path(path).parent_path();
    const std::string dir = parent.empty() ? std::string(".") : parent.string();
    if (!fs::exists(dir, ec))
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write: directory '" + dir + "' does not exist");
    if (!fs::is_directory(dir, ec))
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write: '" + dir + "' is not a directory");
    const std::string tmp = temp_path_for(path);
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f)
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "cannot write to directory '" + dir + "': " + std::strerror(errno));
    std::fclose(f);
    std::remove(tmp.c_str());
}

void check_image_format(const std::string& path, OutputKind kind) {
    if (kind == OutputKind::Unsupported) return;
    // The module first: when it cannot be loaded there is nothing to clean up.
    image_api();
    // One pixel through the format's writer: a format that cannot write here fails now.
    const std::string tmp = temp_path_for(path);
    std::string why;
    bool ok = false;
    const float px[4] = {0.f, 0.f, 0.f, 0.f};
    const unsigned char px8[3] = {0, 0, 0};
    if (kind == OutputKind::Ldr)
        ok = write_with_module(tmp, plain_request(1, 1, 3, image_module::PixelType::UInt8, px8),
                               why);
    else
        ok = write_with_module(tmp,
                               plain_request(1, 1, kind == OutputKind::Exr ? 4 : 3,
                                             image_module::PixelType::Float, px),
                               why);
    std::remove(tmp.c_str());
    if (!ok) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write this format: " + why);
}

void check_image_module_found() {
    std::string reasons;
    for (const std::string& path : image_module_candidates()) {
        std::error_code ec;
        if (std::filesystem::exists(path, ec)) return;
        reasons += std::string(reasons.empty() ? "" : "; ") + path + ": no such file";
    }
    throw module_load_error(reasons);
}

ImageHeader read_image_header(const std::string& path) {
    const std::string why = open_reason(path);
    if (!why.empty()) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot open image: " + why);
    ImageHeader h;
    std::string reason;
    if (!image_api().read_header(path, h, reason))
        throw Error(ErrorKind::Io, SourceLoc{path}, "not an image OpenImageIO can read: " + reason);
    return h;
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
