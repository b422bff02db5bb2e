// libcandela_image.so: candela's image reads and writes through OpenImageIO (see
// include/candela/io/image_module.h). The only file that includes OpenImageIO.
#include "candela/io/image_module.h"

#include <OpenImageIO/imageio.h>

#include <array>
#include <cstring>

namespace {

using candela::Attribute;
using candela::ImageData;
using candela::ImageHeader;
namespace im = candela::image_module;

void add_attribute(OIIO::ImageSpec& spec, const Attribute& a) {
    switch (a.type) {
    case Attribute::Type::String:
        spec.attribute(a.name, a.text);
        break;
    case Attribute::Type::Int:
        spec.attribute(a.name, a.i);
        break;
    case Attribute::Type::Float:
        spec.attribute(a.name, a.f);
        break;
    case Attribute::Type::Double:
        spec.attribute(a.name, OIIO::TypeDesc(OIIO::TypeDesc::DOUBLE), &a.d);
        break;
    case Attribute::Type::Matrix44:
        spec.attribute(a.name, OIIO::TypeMatrix44, a.m.data());
        break;
    case Attribute::Type::Floats:
        spec.attribute(a.name, OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, int(a.floats.size())),
                       a.floats.data());
        break;
    }
}

bool write(const std::string& path, const im::WriteRequest& req, std::string& why) {
    const OIIO::TypeDesc format =
        req.type == im::PixelType::UInt8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT;
    OIIO::ImageSpec spec(req.width, req.height, req.channels, format);
    spec.x = req.x;
    spec.y = req.y;
    spec.full_x = 0;
    spec.full_y = 0;
    spec.full_width = req.full_width > 0 ? req.full_width : req.width;
    spec.full_height = req.full_height > 0 ? req.full_height : req.height;
    if (req.channel_names && !req.channel_names->empty()) spec.channelnames = *req.channel_names;
    spec.alpha_channel = req.alpha_channel;
    spec.z_channel = req.z_channel;
    if (req.compression) spec.attribute("compression", req.compression);
    if (req.half_channels && std::size_t(req.channels) == req.half_channels->size()) {
        spec.channelformats.assign(std::size_t(req.channels), format);
        for (std::size_t c = 0; c < spec.channelformats.size(); ++c)
            if ((*req.half_channels)[c]) spec.channelformats[c] = OIIO::TypeDesc::HALF;
    }
    if (req.attributes)
        for (const Attribute& a : *req.attributes)
            add_attribute(spec, a);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
        why = OIIO::geterror();
        return false;
    }
    if (!out->open(path, spec) || !out->write_image(format, req.pixels) || !out->close()) {
        why = out->geterror();
        if (why.empty()) why = "write failed";
        return false;
    }
    return true;
}

bool read(const std::string& path, ImageData& img, std::string& why) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        why = OIIO::geterror();
        return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    img.width = spec.width;
    img.height = spec.height;
    img.x = spec.x - spec.full_x;
    img.y = spec.y - spec.full_y;
    img.full_width = spec.full_width;
    img.full_height = spec.full_height;
    img.channel_names = spec.channelnames;
    img.pixels.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data())) {
        why = in->geterror();
        return false;
    }
    for (const auto& p : spec.extra_attribs) {
        const std::string name = p.name().string();
        const OIIO::TypeDesc t = p.type();
        if (t == OIIO::TypeString)
            img.attributes.emplace_back(name, p.get_string());
        else if (t == OIIO::TypeInt)
            img.attributes.emplace_back(name, p.get_int());
        else if (t == OIIO::TypeFloat)
            img.attributes.emplace_back(name, p.get_float());
        else if (t == OIIO::TypeDesc(OIIO::TypeDesc::DOUBLE))
            img.attributes.emplace_back(name, *static_cast<const double*>(p.data()));
        else if (t == OIIO::TypeMatrix44) {
            std::array<float, 16> m{};
            std::memcpy(m.data(), p.data(), sizeof(float) * 16);
            img.attributes.emplace_back(name, m);
        } else if (t.basetype == OIIO::TypeDesc::FLOAT && t.aggregate == OIIO::TypeDesc::SCALAR &&
                   t.arraylen > 0) {
            const float* v = static_cast<const float*>(p.data());
            img.attributes.emplace_back(name, std::vector<float>(v, v + t.arraylen));
        }
    }
    in->close();
    return true;
}

bool read_header(const std::string& path, ImageHeader& h, std::string& why) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        why = OIIO::geterror();
        return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    h.width = spec.width;
    h.height = spec.height;
    h.channels = spec.nchannels;
    h.channel_names = spec.channelnames;
    in->close();
    return true;
}

std::string extension_list() {
    return std::string(OIIO::get_string_attribute("extension_list"));
}

std::string output_format_list() {
    return std::string(OIIO::get_string_attribute("output_format_list"));
}

const im::Api kApi = {im::kAbiVersion, OIIO_VERSION_STRING, &write, &read, &read_header,
                      &extension_list, &output_format_list};

} // namespace

extern "C" __attribute__((visibility("default"))) const im::Api* candela_image_module_api() {
    return &kApi;
}
