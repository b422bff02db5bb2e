#pragma once
// Reading the environment map of `render -e` from an image file (the map itself, its lookup and
// its sampling table live in scene/envmap.h).
#include "candela/io/image_io.h"
#include "candela/scene/envmap.h"

#include <memory>
#include <string>

namespace candela {

/// Reads a lat-long environment map (an EXR through OpenEXR, io/exr_pixels.h; any other format
/// OpenImageIO reads through the image module). Channels are
/// matched by name (R, G, B; a lone Y channel is used as grey). Throws
/// Error(ErrorKind::Io, SourceLoc{path}, "...") when the file cannot be read, lacks the channels,
/// or holds a negative or non-finite texel (the message names the pixel).
std::shared_ptr<const EnvMap> load_envmap(const std::string& path);

/// The size and channels of an environment map file from its header, read the way load_envmap()
/// reads the file (so checking an EXR map does not load the image module).
ImageHeader read_envmap_header(const std::string& path);

} // namespace candela
