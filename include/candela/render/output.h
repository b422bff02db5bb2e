#pragma once
// Film -> files: the EXR with its auxiliary channels and metadata, previews in any 8-bit format
// OpenImageIO writes, float RGB for HDR formats, and the sample-rate image (spec §7.2).
#include "candela/io/image_io.h"
#include "candela/render/film.h"
#include "candela/scene/camera.h"
#include "candela/util/enum_table.h"

#include <array>
#include <string>
#include <vector>

namespace candela {

/// Where a film sits in its frame: the data window (x, y, film size) inside the display window
/// (full_width x full_height). The default is a full-frame film.
struct FrameWindow {
    int x = 0, y = 0;
    int full_width = 0, full_height = 0; ///< 0 = the film's own size
};

/// The EXR image of a film: R, G, B (the mean radiance, premultiplied by coverage like every
/// mean channel), A (coverage: the fraction of samples whose camera ray hit a surface), then
/// the requested auxiliary channels albedo.{R,G,B} and N.{X,Y,Z} (means over all samples, world
/// space), Z (nearest hit distance along the camera rays, +inf where none hit), variance.{R,G,B}
/// (variance of the pixel mean), and always `samples` (the per-pixel count of finite samples).
ImageData film_to_image(const Film& film, const std::vector<Attribute>& attributes,
                        const FrameWindow& window = {});

/// Tone mapping of previews, after the exposure scale and before the sRGB curve.
enum class Tonemap {
    Clamp,    ///< none: values above 1 clip to white
    Reinhard, ///< Reinhard et al. 2002, global operator on luminance: c / (1 + L)
    Filmic    ///< Narkowicz 2015 fit of the ACES filmic curve, per channel
};
/// --tonemap (util/enum_table.h).
inline constexpr EnumTable<Tonemap, 3> kTonemaps = {{
    {Tonemap::Clamp, "clamp", ""},
    {Tonemap::Reinhard, "reinhard", "L/(1+L) on luminance"},
    {Tonemap::Filmic, "filmic", "ACES fit"},
}};
/// A name of kTonemaps; throws Error(Usage) naming --tonemap, the choices and the nearest one.
Tonemap parse_tonemap(const std::string& name);
constexpr const char* tonemap_name(Tonemap t) {
    return enum_name(kTonemaps, t);
}
/// One linear colour, scaled by 2^exposure_ev, tone mapped, to display-linear [0, 1].
Rgb tonemap_color(const Rgb& linear, float exposure_scale, Tonemap t);

/// The look of 8-bit images (--look): candela's own (--exposure, --tonemap, the sRGB curve) or
/// the CS184 reference's transfer curve (spec §7.1, docs/cs184-differences.md "Output looks").
enum class Look { Candela, Cs184 };
/// --look.
inline constexpr EnumTable<Look, 2> kLooks = {{
    {Look::Candela, "candela", "--exposure, --tonemap, sRGB curve"},
    {Look::Cs184, "cs184", "the course's exposure sqrt(2) and gamma 2.2, truncated to 8 bits"},
}};

/// The CS184 reference's exposure: sqrt(2^level) with level 1 (spec §7.1).
constexpr double kCs184Exposure = 1.4142135623730951;
/// The CS184 reference's display gamma (spec §7.1).
constexpr double kCs184Gamma = 2.2;
/// The CS184 reference's 8-bit value of a linear value v (spec §7.1):
/// floor(255 * clamp((sqrt(2) v)^(1/2.2), 0, 1)); NaN and v <= 0 give 0, +inf gives 255.
unsigned char cs184_encode8(float v);
/// The linear value that stands for the CS184 byte b < 255: the middle of the interval of
/// values that encode to b, [(b/255)^2.2, ((b+1)/255)^2.2) / sqrt(2). 255 is clipped (every
/// v >= 1/sqrt(2)) and has no value; throws Error(Internal) for it.
double cs184_decode8(int b);
/// The linear value that stands for byte b < 255 of candela's own 8-bit look at 0 EV without
/// a tone map (to_srgb8 rounds): the inverse sRGB curve at b/255. 255 is clipped.
double srgb_decode8(int b);

/// 8-bit preview of the film's mean radiance: in candela's look scaled by 2^exposure_ev, tone
/// mapped and sRGB encoded; in the CS184 look cs184_encode8 per channel (exposure and tone map
/// unused).
std::vector<unsigned char> film_preview(const Film& film, float exposure_ev,
                                        Tonemap tonemap = Tonemap::Clamp,
                                        Look look = Look::Candela);

/// The film's mean radiance as float RGB (HDR formats: no exposure, no tone mapping).
std::vector<float> film_rgb(const Film& film);

/// The sample-rate image: per-pixel count / max_spp through the blue-green-red ramp.
std::vector<unsigned char> film_rate_image(const Film& film, int max_spp);

/// What the sample-rate image's colours mean for a ramp whose red end is `max_spp` samples per
/// pixel: "blue 0, green 16, red 32 or more samples per pixel (linear between)". The image
/// itself stays the course's (spec §7.2: compared pixel for pixel with its reference), so the
/// legend is text: on stderr and in the EXR's metadata.
std::string rate_legend(int max_spp);

/// `out.png` -> `out_rate.png` (spec §7.2, by extension rather than by 4 characters).
std::string rate_image_path(const std::string& path);

/// OpenEXR's worldToCamera: row-major, for row vectors (p' = p M); camera space is left-handed
/// with x right, y up and +z the viewing direction.
std::array<float, 16> world_to_camera_matrix(const Camera& camera);
/// OpenEXR's worldToNDC for a width x height frame: p M = (X, Y, Z, W); X/W and Y/W run from
/// (0, 0) at the top-left to (1, 1) at the bottom-right corner of the display window; Z/W maps
/// the clip range [znear, zfar] to [0, 1].
std::array<float, 16> world_to_ndc_matrix(const Camera& camera, int width, int height);

} // namespace candela
