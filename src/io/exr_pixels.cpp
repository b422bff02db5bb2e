// Reading an OpenEXR file's pixels without the image module (see io/exr_pixels.h for why).
#include "candela/io/exr_pixels.h"

#include "candela/util/error.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include <cctype>
#include <cstddef>
#include <exception>

namespace candela {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& why) {
    throw Error(ErrorKind::Io, SourceLoc{path}, "cannot read image: " + why);
}

} // namespace

bool is_exr_path(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return false;
    std::string ext = path.substr(dot + 1);
    for (char& c : ext)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == "exr";
}

ImageData read_exr_pixels(const std::string& path) {
    ImageData img;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        const Imath::Box2i data = header.dataWindow();
        const Imath::Box2i display = header.displayWindow();
        img.width = data.max.x - data.min.x + 1;
        img.height = data.max.y - data.min.y + 1;
        img.x = data.min.x - display.min.x;
        img.y = data.min.y - display.min.y;
        img.full_width = display.max.x - display.min.x + 1;
        img.full_height = display.max.y - display.min.y + 1;
        if (img.width <= 0 || img.height <= 0) fail(path, "empty data window");
        const Imf::ChannelList& channels = header.channels();
        for (auto it = channels.begin(); it != channels.end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                fail(path, std::string("channel ") + it.name() + " is subsampled");
            img.channel_names.emplace_back(it.name());
        }
        const std::size_t nc = img.channel_names.size();
        if (nc == 0) fail(path, "no channels");
        img.pixels.assign(std::size_t(img.width) * std::size_t(img.height) * nc, 0.f);
        // OpenEXR addresses a slice by the pixel (0, 0) of the data window's coordinate system,
        // which may lie outside the buffer: the base pointer is offset back by the window's
        // origin, as its documentation prescribes.
        const std::ptrdiff_t x_stride = std::ptrdiff_t(nc * sizeof(float));
        const std::ptrdiff_t y_stride = x_stride * img.width;
        char* const origin = reinterpret_cast<char*>(img.pixels.data()) -
                             std::ptrdiff_t(data.min.x) * x_stride -
                             std::ptrdiff_t(data.min.y) * y_stride;
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < nc; ++c)
            fb.insert(img.channel_names[c],
                      Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), std::size_t(x_stride),
                                 std::size_t(y_stride), 1, 1, 0.0));
        file.setFrameBuffer(fb);
        file.readPixels(data.min.y, data.max.y);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail(path, e.what());
    }
    return img;
}

ImageHeader read_exr_header(const std::string& path) {
    ImageHeader h;
    try {
        const Imf::InputFile file(path.c_str());
        const Imath::Box2i data = file.header().dataWindow();
        h.width = data.max.x - data.min.x + 1;
        h.height = data.max.y - data.min.y + 1;
        for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
            h.channel_names.emplace_back(it.name());
        h.channels = int(h.channel_names.size());
    } catch (const std::exception& e) {
        fail(path, e.what());
    }
    return h;
}

} // namespace candela
