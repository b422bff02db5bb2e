// Reads the environment map of `render -e` from an image file into an EnvMap.
#include "candela/io/envmap_file.h"

#include "candela/io/exr_pixels.h"
#include "candela/io/image_io.h"
#include "candela/util/error.h"

#include <utility>
#include <vector>

namespace candela {

std::shared_ptr<const EnvMap> load_envmap(const std::string& path) {
    // An EXR map is read through OpenEXR in-process: the render needs the map before its first
    // pass, and the image module's load would sit in series with the work.
    const ImageData img = is_exr_path(path) ? read_exr_pixels(path) : read_image(path);
    const int w = img.width, h = img.height, nc = img.channels();
    if (w <= 0 || h <= 0 || nc <= 0) throw Error(ErrorKind::Io, SourceLoc{path}, "not a 2-D image");
    int cr = img.channel_index("R"), cg = img.channel_index("G"), cb = img.channel_index("B");
    if (cr < 0 || cg < 0 || cb < 0) {
        int cy = img.channel_index("Y");
        if (cy < 0) {
            std::string names;
            for (const auto& s : img.channel_names)
                names += (names.empty() ? "" : ",") + s;
            throw Error(ErrorKind::Io, SourceLoc{path},
                        "no R, G, B (or Y) channels, found " + (names.empty() ? "none" : names));
        }
        cr = cg = cb = cy;
    }
    std::vector<Rgb> texels(static_cast<std::size_t>(w) * h);
    for (std::size_t k = 0; k < texels.size(); ++k) {
        const float* px = &img.pixels[k * std::size_t(nc)];
        texels[k] = Rgb(px[cr], px[cg], px[cb]);
    }
    return std::make_shared<const EnvMap>(w, h, std::move(texels), path);
}

ImageHeader read_envmap_header(const std::string& path) {
    return is_exr_path(path) ? read_exr_header(path) : read_image_header(path);
}

} // namespace candela
