#pragma once
// Film -> files: the EXR with its auxiliary channels and metadata, the PNG preview and the
// sample-rate image (spec §7.2).
#include "candela/io/image_io.h"
#include "candela/render/film.h"

#include <string>
#include <utility>
#include <vector>

namespace candela {

/// The EXR image of a film: R, G, B, A (1 where sampled), then the requested auxiliary
/// channels albedo.{R,G,B}, N.{X,Y,Z}, Z, variance.{R,G,B}, and always `samples` (the
/// per-pixel count of finite samples).
ImageData film_to_image(const Film& film,
                        const std::vector<std::pair<std::string, std::string>>& metadata);

/// 8-bit sRGB preview of the film's mean radiance, scaled by 2^exposure_ev.
std::vector<unsigned char> film_preview(const Film& film, float exposure_ev);

/// The sample-rate image: per-pixel count / max_spp through the blue-green-red ramp.
std::vector<unsigned char> film_rate_image(const Film& film, int max_spp);

/// `out.png` -> `out_rate.png` (spec §7.2, by extension rather than by 4 characters).
std::string rate_image_path(const std::string& path);

/// Lower-case extension of a path including the dot, "" when none.
std::string path_extension(const std::string& path);

} // namespace candela
