#pragma once
// Checkpoints of a render in progress: the render's own command line (its settings), a hash of
// the scene file, and the RenderState between two passes. Resuming re-runs the same settings
// from that state, which gives a bit-identical image (see renderer.h).
#include "candela/render/renderer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace candela {

struct Checkpoint {
    /// The render's image-defining arguments (after `render`) in canonical form, with absolute
    /// paths, so a resume works from any directory (app/cli.h, canonical_render_args).
    std::vector<std::string> args;
    std::uint64_t scene_hash = 0; ///< file_hash() of the scene file
    std::uint64_t env_hash = 0;   ///< file_hash() of the environment map, 0 without one
    double render_seconds = 0.0;  ///< rendering time of every session so far
    int sessions = 0;             ///< render sessions so far (1 + resumes)
    /// The command line of every session so far, the first render's first (empty in checkpoints
    /// of version 3, which did not keep them).
    std::vector<std::string> commands;
    RenderState state;
};

/// Writes atomically (temporary file + rename). Throws Error(Io).
void write_checkpoint(const std::string& path, const Checkpoint& ckpt);

/// Reads a checkpoint. Throws Error(Io) for a file that cannot be opened, Error(Scene) (a
/// malformed input) for a truncated, damaged or foreign one.
Checkpoint read_checkpoint(const std::string& path);

/// Whether `path` is a file that begins like a candela checkpoint (its magic bytes); false for a
/// missing or other file. Reads only the first bytes.
bool looks_like_checkpoint(const std::string& path);

/// 64-bit FNV-1a hash of a file's bytes. Throws Error(Io) when it cannot be read.
std::uint64_t file_hash(const std::string& path);

/// The default checkpoint path for an output image: `<output>.ckpt`.
std::string checkpoint_path_for(const std::string& output);

} // namespace candela
