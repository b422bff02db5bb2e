#pragma once
// Image files through OpenImageIO: the one boundary between candela and image files, so no
// other file includes OpenImageIO. Every write goes to a temporary file in the target directory
// and is renamed into place, so a failed or interrupted write never leaves a truncated image.
#include "candela/math/vec.h"

#include <array>
#include <limits>
#include <string>
#include <vector>

namespace candela {

/// One typed header attribute of an image (an EXR header entry). Numbers are written as numbers
/// (EXR int, float, double) and camera matrices as EXR m44f, so a compositor reads them without
/// parsing text.
struct Attribute {
    enum class Type { String, Int, Float, Double, Matrix44, Floats };
    std::string name;
    Type type = Type::String;
    std::string text;          ///< Type::String
    int i = 0;                 ///< Type::Int
    float f = 0.f;             ///< Type::Float
    double d = 0.0;            ///< Type::Double
    std::array<float, 16> m{}; ///< Type::Matrix44, row-major as OpenEXR stores it
    std::vector<float> floats; ///< Type::Floats: any other float array (e.g. chromaticities)

    Attribute() = default;
    Attribute(std::string n, std::string v)
        : name(std::move(n)), type(Type::String), text(std::move(v)) {}
    Attribute(std::string n, const char* v) : Attribute(std::move(n), std::string(v)) {}
    Attribute(std::string n, int v) : name(std::move(n)), type(Type::Int), i(v) {}
    Attribute(std::string n, float v) : name(std::move(n)), type(Type::Float), f(v) {}
    Attribute(std::string n, double v) : name(std::move(n)), type(Type::Double), d(v) {}
    Attribute(std::string n, const std::array<float, 16>& v)
        : name(std::move(n)), type(Type::Matrix44), m(v) {}
    Attribute(std::string n, std::vector<float> v)
        : name(std::move(n)), type(Type::Floats), floats(std::move(v)) {}

    /// The value as text: integers exactly, floats with enough digits to read back the same
    /// value, matrices as 16 comma-separated numbers.
    std::string str() const;
    /// Type name as oiiotool prints it: string, int, float, double, matrix, float[N].
    const char* type_name() const;
};

/// A planar float image: `channels` interleaved values per pixel, row 0 at the top. The pixels
/// are the data window, placed at (x, y) inside a display window of full_width x full_height
/// (both 0: the display window is the data window), as OpenEXR defines the two windows.
struct ImageData {
    int width = 0, height = 0;
    int x = 0, y = 0;                    ///< data window origin in the display window
    int full_width = 0, full_height = 0; ///< display window size; 0 = width x height
    std::vector<std::string> channel_names;
    std::vector<float> pixels; ///< width * height * channel_names.size()
    std::vector<Attribute> attributes;

    int channels() const { return static_cast<int>(channel_names.size()); }
    int channel_index(const std::string& name) const; ///< -1 when absent
    float at(int px, int py, int c) const {
        return pixels[(std::size_t(py) * width + px) * channel_names.size() + c];
    }
    int display_width() const { return full_width > 0 ? full_width : width; }
    int display_height() const { return full_height > 0 ? full_height : height; }
    /// The attribute named `key`, or nullptr.
    const Attribute* attribute(const std::string& key) const;
    /// The attribute's text (Attribute::str()), "" when absent.
    std::string meta(const std::string& key) const;
    /// Adds `a`, replacing an attribute of the same name.
    void set(const Attribute& a);
};

/// How write_exr stores the channels.
struct ExrOptions {
    /// Channels stored as 16-bit half floats; the others are 32-bit floats.
    std::vector<std::string> half_channels;
    /// OpenEXR compression: one of exr_compressions().
    std::string compression = "zip";
    /// Z written where no sample hit a surface (the film's +inf): +inf, or a large finite
    /// distance for compositing tools that turn +inf into NaN.
    float background_depth = std::numeric_limits<float>::infinity();
};

/// The OpenEXR compressions write_exr accepts; the first four are lossless.
const std::vector<std::string>& exr_compressions();

/// The Rec. 709 primaries and D65 white point (x, y of red, green, blue, white): the colour
/// space of candela's linear RGB, written as every EXR's standard `chromaticities` attribute.
inline const std::vector<float> kRec709Chromaticities = {0.64f, 0.33f, 0.30f,   0.60f,
                                                         0.15f, 0.06f, 0.3127f, 0.3290f};

/// Writes an EXR (float, zip-compressed unless `opt` says otherwise) with the image's channels,
/// windows and attributes, and the Rec. 709 `chromaticities`. Throws Error(Io) with the path on
/// failure; nothing is left at `path` then.
void write_exr(const std::string& path, const ImageData& img, const ExrOptions& opt = {});

/// Writes an 8-bit RGB image in the format of the path's extension (PNG, JPEG, TIFF, ...);
/// `rgb8` is width*height*3 bytes, row 0 at the top. The string `attributes` go into the file as
/// its format keeps text (a PNG's tEXt chunks, read back by read_image under the same names);
/// formats without a place for a name keep what they can (e.g. `Software`).
void write_image8(const std::string& path, int width, int height,
                  const std::vector<unsigned char>& rgb8,
                  const std::vector<Attribute>& attributes = {});

/// write_image8 for a PNG (the name says what the caller expects).
void write_png(const std::string& path, int width, int height,
               const std::vector<unsigned char>& rgb8,
               const std::vector<Attribute>& attributes = {});

/// Writes a float RGB image (`rgb` is width*height*3 values) in the format of the extension,
/// for HDR formats such as Radiance .hdr and .pfm, with the `attributes` the format keeps.
void write_image_float(const std::string& path, int width, int height,
                       const std::vector<float>& rgb,
                       const std::vector<Attribute>& attributes = {});

/// Reads any image OpenImageIO understands as float, with its windows and its string, int,
/// float, double and matrix attributes. Throws Error(Io).
ImageData read_image(const std::string& path);

/// What `candela render -f` writes for an extension.
enum class OutputKind {
    Exr,        ///< HDR with auxiliary channels and metadata
    Hdr,        ///< float RGB (.hdr, .pfm): linear radiance, no tone mapping
    Ldr,        ///< 8-bit RGB preview (.png, .jpg, .tif, ...): exposure, tone map, sRGB
    Unsupported ///< no OpenImageIO writer for the extension
};
/// The kind of output for `path`'s extension (case-insensitive), asking OpenImageIO which
/// formats it can write.
OutputKind output_kind(const std::string& path);
/// Extensions of the formats OpenImageIO can write here, e.g. ".png, .jpg, ..." (for messages).
std::string writable_extensions();

/// Checks, before any work, that an image of `kind` can be written at `path`:
/// check_image_location() and check_image_format(). Throws Error(Io) with the operating
/// system's reason.
void check_image_writable(const std::string& path, OutputKind kind);
/// The part of check_image_writable() that needs no image module: the directory exists and is
/// writable (a temporary file is created beside `path` and removed), `path` is not a directory.
void check_image_location(const std::string& path);
/// The part that does: the format's writer works (a 1x1 image of `kind` is written to a
/// temporary file beside `path` and removed). Loads the image module when it is not loaded
/// yet; safe to call on any thread.
void check_image_format(const std::string& path, OutputKind kind);
/// Throws the error of a failed image-module load at once, without loading it, when no module
/// file exists where the loader looks: a caller that loads the module later, on another thread,
/// still refuses the usual failure before any work.
void check_image_module_found();

/// The size and channels of an image file, read from its header only. Throws Error(Io) with
/// the operating system's reason when it cannot be opened, or OpenImageIO's when it is not an
/// image.
struct ImageHeader {
    int width = 0, height = 0, channels = 0;
    std::vector<std::string> channel_names;
};
ImageHeader read_image_header(const std::string& path);

/// sRGB transfer of a linear value after scaling by 2^exposure, clamped and quantised.
unsigned char to_srgb8(float linear, float exposure_scale);

/// The sample-rate colour ramp of spec §7.2: 0 -> blue, 0.5 -> green, 1 -> red.
Rgb sample_rate_color(float rate);

/// Temporary file name beside `path` (same directory and extension), unique per process.
std::string temp_path_for(const std::string& path);

} // namespace candela
