// Checkpoint files: writing one atomically, reading and checking it back, the scene file's hash.
#include "candela/render/checkpoint.h"

#include "candela/io/image_io.h"
#include "candela/util/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace candela {

namespace {

constexpr char kMagic[8] = {'C', 'N', 'D', 'L', 'C', 'K', 'P', 'T'};
/// Version 2 added the relative sampler's per-pixel costs and cost budget. Version 3 stores the
/// film's hit counts and nearest depth (alpha and Z, film.h), absolute paths in the arguments,
/// and the time and number of sessions so far; older films cannot give alpha, so older
/// checkpoints are refused with a message. Version 4 adds the command line of every session
/// (version 3 is read with none). Version 5 keeps the relative sampler's share of its budget
/// apart from the uniform and cs184 samplers' next sample index, and whether the sampler has
/// ended the render; versions 3 and 4 held the share in the next sample's place (read so below).
constexpr std::uint32_t kVersion = 5;
constexpr std::uint32_t kOldestVersion = 3;
/// Bounds that a genuine checkpoint never exceeds (in arguments, and in sessions' commands); a
/// foreign or corrupt file that claims more is rejected before anything is allocated.
constexpr std::uint32_t kMaxArgs = 4096;
constexpr std::uint32_t kMaxArgLength = 1 << 16;

template <typename T> void put(std::ostream& out, const T& v) {
    out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <typename T> void get(std::istream& in, T& v, const std::string& path) {
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v))
        throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is truncated");
}

void put_strings(std::ostream& out, const std::vector<std::string>& v) {
    put(out, std::uint32_t(v.size()));
    for (const std::string& a : v) {
        put(out, std::uint32_t(a.size()));
        out.write(a.data(), std::streamsize(a.size()));
    }
}

std::vector<std::string> get_strings(std::istream& in, const std::string& path) {
    std::uint32_t count = 0;
    get(in, count, path);
    if (count > kMaxArgs) throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is corrupt");
    std::vector<std::string> v;
    for (std::uint32_t i = 0; i < count; ++i) {
        std::uint32_t len = 0;
        get(in, len, path);
        if (len > kMaxArgLength)
            throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is corrupt");
        std::string a(len, '\0');
        if (!in.read(a.data(), len))
            throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is truncated");
        v.push_back(std::move(a));
    }
    return v;
}

} // namespace

std::string checkpoint_path_for(const std::string& output) {
    return output + ".ckpt";
}

bool looks_like_checkpoint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[sizeof kMagic];
    return in && in.read(magic, sizeof magic) && std::memcmp(magic, kMagic, sizeof kMagic) == 0;
}

std::uint64_t file_hash(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot read file to hash it");
    std::uint64_t h = 1469598103934665603ull; // FNV-1a offset basis
    char buf[1 << 16];
    while (in) {
        in.read(buf, sizeof buf);
        for (std::streamsize i = 0; i < in.gcount(); ++i) {
            h ^= static_cast<unsigned char>(buf[i]);
            h *= 1099511628211ull; // FNV-1a prime
        }
    }
    return h;
}

void write_checkpoint(const std::string& path, const Checkpoint& c) {
    std::string tmp = temp_path_for(path);
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out)
            throw Error(ErrorKind::Io, SourceLoc{path},
                        std::string("cannot write checkpoint: ") + std::strerror(errno));
        out.write(kMagic, sizeof kMagic);
        put(out, kVersion);
        put_strings(out, c.args);
        put(out, c.scene_hash);
        put(out, c.env_hash);
        put(out, c.render_seconds);
        put(out, std::int32_t(c.sessions));
        put_strings(out, c.commands);
        put(out, std::int32_t(c.state.next_sample));
        put(out, std::int32_t(c.state.passes));
        put(out, std::int32_t(c.state.budget_spp));
        put(out, std::uint8_t(c.state.stopped ? 1 : 0));
        put(out, std::uint64_t(c.state.done.size()));
        out.write(reinterpret_cast<const char*>(c.state.done.data()),
                  std::streamsize(c.state.done.size()));
        put(out, std::uint64_t(c.state.cost.size()));
        out.write(reinterpret_cast<const char*>(c.state.cost.data()),
                  std::streamsize(c.state.cost.size() * sizeof(std::uint64_t)));
        put(out, c.state.cost_budget);
        c.state.film.write(out);
        out.flush();
        if (!out) {
            out.close();
            std::remove(tmp.c_str());
            throw Error(ErrorKind::Io, SourceLoc{path}, "cannot write checkpoint (disk full?)");
        }
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        int e = errno;
        std::remove(tmp.c_str());
        throw Error(ErrorKind::Io, SourceLoc{path},
                    std::string("cannot write checkpoint: ") + std::strerror(e));
    }
}

Checkpoint read_checkpoint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw Error(ErrorKind::Io, SourceLoc{path},
                    std::string("cannot open checkpoint: ") + std::strerror(errno));
    char magic[sizeof kMagic];
    if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0)
        throw Error(ErrorKind::Scene, SourceLoc{path}, "not a candela checkpoint");
    std::uint32_t version = 0;
    get(in, version, path);
    if (version < kOldestVersion)
        throw Error(ErrorKind::Scene, SourceLoc{path},
                    "checkpoint version " + std::to_string(version) +
                        " was written by an older candela and cannot be "
                        "resumed (render again)");
    if (version > kVersion)
        throw Error(ErrorKind::Scene, SourceLoc{path},
                    "checkpoint version " + std::to_string(version) +
                        " was written by a newer candela");
    Checkpoint c;
    c.args = get_strings(in, path);
    get(in, c.scene_hash, path);
    get(in, c.env_hash, path);
    std::int32_t sessions = 0;
    get(in, c.render_seconds, path);
    get(in, sessions, path);
    if (sessions < 0 || !(c.render_seconds >= 0.0))
        throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is corrupt");
    c.sessions = sessions;
    if (version >= 4) c.commands = get_strings(in, path);
    std::int32_t next = 0, passes = 0, budget_spp = 0;
    std::uint8_t stopped = 0;
    get(in, next, path);
    get(in, passes, path);
    if (version >= 5) {
        get(in, budget_spp, path);
        get(in, stopped, path);
    }
    c.state.next_sample = next;
    c.state.passes = passes;
    c.state.budget_spp = budget_spp;
    c.state.stopped = stopped != 0;
    std::uint64_t ndone = 0;
    get(in, ndone, path);
    if (ndone > (1ull << 28))
        throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is corrupt");
    c.state.done.resize(ndone);
    if (!in.read(reinterpret_cast<char*>(c.state.done.data()), std::streamsize(ndone)))
        throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is truncated");
    {
        std::uint64_t ncost = 0;
        get(in, ncost, path);
        if (ncost > (1ull << 28))
            throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is corrupt");
        c.state.cost.resize(ncost);
        if (!in.read(reinterpret_cast<char*>(c.state.cost.data()),
                     std::streamsize(ncost * sizeof(std::uint64_t))))
            throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is truncated");
        get(in, c.state.cost_budget, path);
    }
    try {
        c.state.film = Film::read(in);
    } catch (const Error& e) {
        throw Error(ErrorKind::Scene, SourceLoc{path}, e.message());
    }
    if (c.state.done.size() != c.state.film.pixel_count() ||
        (!c.state.cost.empty() && c.state.cost.size() != c.state.film.pixel_count()) || next < 0 ||
        passes < 0 || budget_spp < 0 || stopped > 1)
        throw Error(ErrorKind::Scene, SourceLoc{path}, "checkpoint is inconsistent");
    if (version < 5 && !c.state.cost.empty()) {
        // A relative render (the only one with per-pixel costs) of an older version: its next
        // sample was the share of the budget, -s once the sampler had ended the render; the
        // relative sampler ends a render whose share reached -s (PassPolicy::prepare).
        c.state.budget_spp = next;
        c.state.next_sample = 0;
    }
    return c;
}

} // namespace candela
