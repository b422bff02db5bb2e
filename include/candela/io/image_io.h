#pragma once
// Image files through OpenImageIO. Every write goes to a temporary file in the target directory
// and is renamed into place, so a failed or interrupted write never leaves a truncated image.
#include "candela/math/vec.h"

#include <string>
#include <utility>
#include <vector>

namespace candela {

/// A planar float image: `channels` interleaved values per pixel, row 0 at the top.
struct ImageData {
    int width = 0, height = 0;
    std::vector<std::string> channel_names;
    std::vector<float> pixels; ///< width * height * channel_names.size()
    std::vector<std::pair<std::string, std::string>> metadata; ///< string attributes

    int channels() const { return static_cast<int>(channel_names.size()); }
    int channel_index(const std::string& name) const; ///< -1 when absent
    float at(int x, int y, int c) const {
        return pixels[(std::size_t(y) * width + x) * channel_names.size() + c];
    }
    std::string meta(const std::string& key) const; ///< "" when absent
};

/// Writes an EXR (float, zip-compressed) with the image's channels and string metadata.
/// Throws Error(Io) with the path on failure; nothing is left at `path` then.
void write_exr(const std::string& path, const ImageData& img);

/// Writes an 8-bit RGB(A) PNG; `rgb8` is width*height*3 bytes, row 0 at the top.
void write_png(const std::string& path, int width, int height,
               const std::vector<unsigned char>& rgb8);

/// Reads any image OpenImageIO understands as float. Throws Error(Io).
ImageData read_image(const std::string& path);

/// sRGB transfer of a linear value after scaling by 2^exposure, clamped and quantised.
unsigned char to_srgb8(float linear, float exposure_scale);

/// The sample-rate colour ramp of spec §7.2: 0 -> blue, 0.5 -> green, 1 -> red.
Rgb sample_rate_color(float rate);

/// Temporary file name beside `path` (same directory and extension), unique per process.
std::string temp_path_for(const std::string& path);

} // namespace candela
