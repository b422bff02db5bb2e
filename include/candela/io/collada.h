#pragma once
// COLLADA (.dae) reader for the CS184 dialect (spec §1, with candela's decisions of §11).
//
// The reader produces a SceneDesc (scene/scene_desc.h): a plain description of what the file
// says. It holds no rendering logic; the scene builder (scene/builder.h) turns it into a Scene.
#include "candela/scene/builder.h"
#include "candela/scene/scene_desc.h"
#include "candela/util/log.h"

#include <cstdint>
#include <string>

namespace candela {

/// Resource limits of the reader (the triangle limit, shared with the builder, is in
/// scene/scene_desc.h). Inputs beyond them are rejected with a `file:line: error:` message before
/// anything proportional to the claimed size is allocated, so a hostile file fails fast instead
/// of exhausting memory.
namespace loader_limits {
/// Largest scene file load_collada() reads (and largest text parse_collada() accepts). The
/// largest course scene is ~2 MiB; 512 MiB leaves room for big exports yet keeps the parsed DOM
/// (several times the text) well inside a workstation's memory.
constexpr std::uint64_t kMaxFileBytes = std::uint64_t(512) << 20;
/// Deepest nesting of elements with content (the document element is level 1); a
/// self-closing element may sit one level deeper. This is tinyxml2 9's own limit (it counts
/// the document node too and stops at TINYXML2_MAX_ELEMENT_DEPTH = 100); the reader reports it
/// as a nesting error, and its recursive <node> walk is bounded by it.
constexpr int kMaxXmlDepth = 98;
/// Largest accessor stride (floats per vector). Real files interleave a handful of components.
constexpr std::uint32_t kMaxAccessorStride = 1024;
/// Largest `offset` of a primitive group's `<input>`; the index stride is the largest offset + 1.
/// Real files use one offset per input (at most a handful).
constexpr std::uint32_t kMaxInputOffset = 1023;
} // namespace loader_limits

/// Reads and parses the file at `path`. Throws Error(Io) when it cannot be read or is larger
/// than loader_limits::kMaxFileBytes (checked before reading), and Error(Scene) with a
/// the place (`path:line`) when its content is invalid.
SceneDesc load_collada(const std::string& path, Diagnostics& diag);

/// Parses COLLADA text; `display_name` prefixes every message. Throws Error(Scene), also when
/// the text breaks a loader_limits bound.
SceneDesc parse_collada(const std::string& xml_text, const std::string& display_name,
                        Diagnostics& diag);

/// load_collada() then build_scene(): the one call the commands use (the environment map, if
/// any, is read beforehand into opt.env_map, io/envmap_file.h).
Scene load_scene(const std::string& path, const BuildOptions& opt, Diagnostics& diag);

} // namespace candela
