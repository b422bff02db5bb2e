#pragma once
// The float pixels of an OpenEXR file, read in-process through OpenEXR itself. Image files
// otherwise go through the image module (io/image_module.h), whose first use loads and
// relocates about 260 shared libraries (0.25-0.3 processor-seconds); a render with an
// environment map needs the map before its first pass, so the module's load would sit in
// series with the work. OpenEXR's own libraries are five small ones. Pixels only: the header's
// attributes are not read (read_image() reads them).
#include "candela/io/image_io.h"

#include <string>

namespace candela {

/// True when `path`'s extension is .exr (any case): read_exr_pixels() can read it.
bool is_exr_path(const std::string& path);

/// Every channel of the file's first part as float (half and uint channels converted), the
/// data window at (x, y) in the display window, channels in the file's (alphabetical) order;
/// `attributes` stays empty. Throws Error(Io) naming the path: not an OpenEXR file, deep or
/// subsampled channels, a damaged file, or the operating system's reason.
ImageData read_exr_pixels(const std::string& path);

/// The size and channel names of the file's first part, from its header only (channels in the
/// file's order). Throws as read_exr_pixels() does.
ImageHeader read_exr_header(const std::string& path);

} // namespace candela
