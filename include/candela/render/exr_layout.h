#pragma once
// The names in a candela EXR: its channels and its metadata keys (docs/exr-metadata.md), and
// the keys of the text an 8-bit image carries. The writer (render/output), the merger
// (render/merge), the render and compare commands all name them from here, except the keys of
// the render settings, which each setting's row in render/setting_table.h declares.
namespace candela::exr {

// --- Channels, in the order film_to_image writes them ----------------------------------------

inline constexpr const char* kRgb[3] = {"R", "G", "B"}; ///< mean radiance (premultiplied)
inline constexpr const char* kAlpha = "A";              ///< coverage
inline constexpr const char* kAlbedo[3] = {"albedo.R", "albedo.G", "albedo.B"};
inline constexpr const char* kNormal[3] = {"N.X", "N.Y", "N.Z"};
inline constexpr const char* kDepth = "Z";
/// variance.R, .G, .B: the variance of the mean of the radiance channel named after the prefix.
inline constexpr const char* kVariancePrefix = "variance.";
inline constexpr const char* kVariance[3] = {"variance.R", "variance.G", "variance.B"};
inline constexpr const char* kSamples = "samples"; ///< finite samples per pixel
/// The channels `render --half` stores as 16-bit half floats: colours, coverage and normals,
/// which a half's 11-bit significand holds to display precision. Z, variance.* and samples stay
/// 32-bit: depths, variances far below 2^-14 and counts above 2048 need the precision.
inline constexpr const char* kHalfChannels[] = {"R",        "G",        "B",   "A",   "albedo.R",
                                                "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z"};

// --- Metadata keys ---------------------------------------------------------------------------

/// What every candela key begins with.
inline constexpr const char* kKeyPrefix = "candela:";

inline constexpr const char* kSoftware = "Software";
/// OpenEXR's standard matrices, as candela writes them and as older files spell them.
inline constexpr const char* kWorldToCamera = "worldtocamera";
inline constexpr const char* kWorldToNdc = "worldtoNDC";
inline constexpr const char* kWorldToCameraStd = "worldToCamera";
inline constexpr const char* kWorldToNdcStd = "worldToNDC";

// The render: the keys of its settings are in the settings' rows (render/setting_table.h).
inline constexpr const char* kVersion = "candela:version";
/// The command that reproduces the file: a render's first session (a resume continues it
/// bit-identically), or the `merge` that made a merged file.
inline constexpr const char* kCommandLine = "candela:command_line";
/// A resumed render: every session's command, one per line, the first being command_line.
inline constexpr const char* kSessionCommands = "candela:session_commands";
inline constexpr const char* kScene = "candela:scene";
/// One past the largest sample index any pixel used (sample_offset + its most samples, finite
/// or dropped): under the relative sampler -s is a budget and a pixel may take more.
inline constexpr const char* kSampleEnd = "candela:sample_end";
inline constexpr const char* kCamera = "candela:camera";
inline constexpr const char* kCameraFile = "candela:camera_file";
inline constexpr const char* kLensRadius = "candela:lens_radius";
inline constexpr const char* kFocalDistance = "candela:focal_distance";
/// The horizontal field of view across this image's width (after --framing and --fov).
inline constexpr const char* kHfovDeg = "candela:hfov_deg";
/// --framing: candela (the field of view spans every -r) or cs184 (the 800x600 view's pitch).
inline constexpr const char* kFraming = "candela:framing";
inline constexpr const char* kEnv = "candela:env";
inline constexpr const char* kRegion = "candela:region";
inline constexpr const char* kMpiRanks = "candela:mpi_ranks";

// How the render went (summed or recomputed by a merge).
inline constexpr const char* kRenderSeconds = "candela:render_seconds";
inline constexpr const char* kSessions = "candela:sessions";
inline constexpr const char* kSamplesTaken = "candela:samples";
inline constexpr const char* kNonfiniteDropped = "candela:nonfinite_dropped";
inline constexpr const char* kInterrupted = "candela:interrupted";
/// What the colours of the sample-rate image written beside this one mean (rate_legend()).
inline constexpr const char* kRateLegend = "candela:rate_legend";

// 8-bit images (PNG text chunks; docs/exr-metadata.md "8-bit images") carry kSoftware,
// kCommandLine and, for an image of the radiance, how its bytes were encoded:
/// --look: candela or cs184 (`candela compare` decodes the bytes by it).
inline constexpr const char* kLook = "candela:look";
/// --exposure in stops and --tonemap, of candela's look only.
inline constexpr const char* kExposure = "candela:exposure";
inline constexpr const char* kTonemap = "candela:tonemap";

// Written by `candela merge`.
inline constexpr const char* kMergedRanges = "candela:merged_ranges";
inline constexpr const char* kMergedInputs = "candela:merged_inputs";
/// The commands that made the merged parts, one per line, in an order that can be run (a part
/// that is itself a merge contributes its parts' commands, then its own).
inline constexpr const char* kPartCommands = "candela:part_commands";

} // namespace candela::exr
