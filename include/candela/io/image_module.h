#pragma once
// The boundary between candela and OpenImageIO. OpenImageIO's dependency tree takes about half a
// second to load and relocate, so the image I/O lives in a module of its own
// (libcandela_image.so, src/image_module/) that io/image_io.cpp loads with dlopen() on the first
// image read or write: commands that touch no image never load it. Both sides are built by the
// same compiler from this header; kAbiVersion changes whenever the table below does.
// Functions return false with a reason in `why` instead of throwing: errors cross the boundary
// as values, and io/image_io.cpp turns them into candela errors with the path.
#include "candela/io/image_io.h"

#include <string>
#include <vector>

namespace candela::image_module {

constexpr int kAbiVersion = 2;

enum class PixelType { UInt8, Float };

/// One image to write: interleaved pixels of `type`, the data window at (x, y) in a display
/// window of full_width x full_height, channel names (empty: OpenImageIO's defaults) and
/// attributes; for EXR the compression and the channels stored as half floats.
struct WriteRequest {
    int width = 0, height = 0, channels = 0;
    int x = 0, y = 0, full_width = 0, full_height = 0;
    PixelType type = PixelType::Float;
    const void* pixels = nullptr;
    const std::vector<std::string>* channel_names = nullptr;
    const std::vector<Attribute>* attributes = nullptr;
    int alpha_channel = -1, z_channel = -1;
    const char* compression = nullptr;                         ///< EXR: OpenEXR's name, e.g. "zip"
    const std::vector<unsigned char>* half_channels = nullptr; ///< per channel: 1 = half float
};

struct Api {
    int abi_version;
    /// OpenImageIO's version string, as the module was built against.
    const char* library_version;
    /// Writes `req` to `path` in the format of its extension.
    bool (*write)(const std::string& path, const WriteRequest& req, std::string& why);
    /// Reads every channel as float with windows and typed attributes into `out`.
    bool (*read)(const std::string& path, ImageData& out, std::string& why);
    /// Reads size and channel names only.
    bool (*read_header)(const std::string& path, ImageHeader& out, std::string& why);
    /// OpenImageIO's "extension_list" ("format:ext,ext;...") and "output_format_list".
    std::string (*extension_list)();
    std::string (*output_format_list)();
};

/// The module's one exported symbol.
constexpr const char* kEntryPoint = "candela_image_module_api";
using EntryPoint = const Api* (*)();

} // namespace candela::image_module
