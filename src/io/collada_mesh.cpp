// COLLADA reader: <geometry> (meshes with every primitive group, and CGL spheres).
#include "collada_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace candela::collada_detail {

namespace {

/// A triangle is degenerate when the sine of its angle at the first corner is below this (or an
/// edge is zero). Positions are single precision: collinear points written with ~7 significant
/// digits come back with sines around 1e-7, so anything smaller is zero area up to rounding.
constexpr double kDegenerateSine = 1e-7;
/// Fan triangulation matches the author's polygon when every fan triangle faces the same way as
/// the polygon's Newell normal; cosines below this mark a non-planar or non-convex polygon.
/// 1e-4 allows for float rounding in planar input (about 0.8 degrees of bend).
constexpr double kFanCosine = 1.0 - 1e-4;

bool tag_is(const XMLElement* e, const char* tag) {
    return std::strcmp(e->Name(), tag) == 0;
}

Vec3d to_d(const Vec3& v) {
    return Vec3d(v);
}

/// Reads a `<source>` of 3-component vectors, honouring its accessor when present.
void read_vec3_source(Context& ctx, const XMLElement* source, std::vector<Vec3>& out) {
    const std::string sid = display_id(source);
    const XMLElement* fa = source->FirstChildElement("float_array");
    if (!fa) ctx.fail(source, "source '" + sid + "' has no <float_array>");
    const std::string aid = display_id(fa);
    std::uint32_t count = ctx.uint_attr(fa, "count", true, 0);
    // The count is only compared with what the text holds: nothing is allocated from it.
    std::vector<float> v;
    ctx.parse_floats(fa, v, "float_array '" + aid + "'");
    if (v.size() != count)
        ctx.fail(fa, "float_array '" + aid + "' has count=\"" + std::to_string(count) + "\" but " +
                         std::to_string(v.size()) + " numbers");
    std::size_t n = 0, stride = 3, offset = 0;
    const XMLElement* tc = source->FirstChildElement("technique_common");
    const XMLElement* acc = tc ? tc->FirstChildElement("accessor") : nullptr;
    if (acc) {
        n = ctx.uint_attr(acc, "count", true, 0);
        stride = ctx.uint_attr(acc, "stride", false, 1);
        offset = ctx.uint_attr(acc, "offset", false, 0);
        if (stride > loader_limits::kMaxAccessorStride)
            ctx.fail(acc, "accessor of source '" + sid + "' has stride " + std::to_string(stride) +
                              ", more than the limit of " +
                              std::to_string(loader_limits::kMaxAccessorStride));
        if (stride < 3)
            ctx.fail(acc, "accessor of source '" + sid + "' has stride " + std::to_string(stride) +
                              ", need at least 3 for vectors");
        // n, stride and offset are below 2^32 and stride below 2^11: no 64-bit overflow.
        if (n > 0 && offset + (n - 1) * stride + 3 > v.size())
            ctx.fail(acc, "accessor of source '" + sid + "' reads " + std::to_string(n) +
                              " vectors of stride " + std::to_string(stride) +
                              " past the end of float_array '" + aid + "' (" +
                              std::to_string(v.size()) + " numbers)");
    } else {
        if (v.size() % 3 != 0)
            ctx.fail(fa, "float_array '" + aid + "' has " + std::to_string(v.size()) +
                             " numbers, not a multiple of 3");
        n = v.size() / 3;
    }
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const float* p = &v[offset + i * stride];
        out[i] = Vec3(p[0], p[1], p[2]);
    }
}

struct Input {
    std::uint32_t offset = 0;
    const XMLElement* elem = nullptr;
};

class MeshParser {
  public:
    MeshParser(Context& ctx, const XMLElement* mesh, DescGeometry& out)
        : ctx_(ctx), mesh_(mesh), out_(out) {}

    void run() {
        vertices_ = mesh_->FirstChildElement("vertices");
        if (!vertices_) ctx_.fail(mesh_, "mesh '" + out_.name + "' has no <vertices>");
        const XMLElement* pos_input = nullptr;
        for (const XMLElement* in = vertices_->FirstChildElement("input"); in;
             in = in->NextSiblingElement("input")) {
            const char* sem = in->Attribute("semantic");
            if (sem && std::strcmp(sem, "POSITION") == 0) pos_input = in;
            if (sem && std::strcmp(sem, "NORMAL") == 0) vertex_normal_input_ = in;
        }
        if (!pos_input)
            ctx_.fail(vertices_, "<vertices> of mesh '" + out_.name + "' has no POSITION input");
        read_vec3_source(ctx_, ctx_.resolve(pos_input, "source", "source"), out_.positions);
        if (vertex_normal_input_) {
            NormalSource ns = normal_source(ctx_.resolve(vertex_normal_input_, "source", "source"));
            if (ns.count < out_.positions.size())
                ctx_.fail(vertex_normal_input_, "<vertices> NORMAL source of mesh '" + out_.name +
                                                    "' has fewer vectors than POSITION");
            vertex_normal_base_ = ns.base;
        }

        for (const XMLElement* g = mesh_->FirstChildElement(); g; g = g->NextSiblingElement()) {
            if (tag_is(g, "triangles") || tag_is(g, "polylist") || tag_is(g, "polygons"))
                parse_group(g);
            else if (tag_is(g, "lines") || tag_is(g, "linestrips") || tag_is(g, "trifans") ||
                     tag_is(g, "tristrips"))
                ctx_.warn_once(g->Name(), g,
                               std::string("<") + g->Name() +
                                   "> primitives ignored (not supported)");
        }
        std::size_t kept = out_.triangle_count();
        if (kept == 0 && degenerate_ == 0)
            ctx_.fail(mesh_, "mesh '" + out_.name + "' has no polygons");
        if (kept == 0)
            ctx_.fail(mesh_, "mesh '" + out_.name + "': all " + std::to_string(degenerate_) +
                                 " triangles are degenerate (zero area)");
        if (degenerate_ > 0)
            ctx_.warn(mesh_, "mesh '" + out_.name + "': dropped " + std::to_string(degenerate_) +
                                 " degenerate (zero-area) triangle" + (degenerate_ > 1 ? "s" : ""));
        out_.fanned_polygons = ngons_;
        if (ngons_ > 0)
            ctx_.note(mesh_, "mesh '" + out_.name + "': " + std::to_string(ngons_) + " polygon" +
                                 (ngons_ > 1 ? "s" : "") +
                                 " with more than 3 vertices fan-triangulated (the course "
                                 "reference renders one triangle of each)");
        if (bent_ngons_ > 0)
            ctx_.warn(mesh_, "mesh '" + out_.name + "': " + std::to_string(bent_ngons_) +
                                 " non-planar or non-convex polygon" +
                                 (bent_ngons_ > 1 ? "s" : "") +
                                 " fan-triangulated; the result may differ from the intended "
                                 "surface");
    }

  private:
    Context& ctx_;
    const XMLElement* mesh_;
    DescGeometry& out_;
    const XMLElement* vertices_ = nullptr;
    const XMLElement* vertex_normal_input_ = nullptr;
    std::uint32_t vertex_normal_base_ = 0;
    struct NormalSource {
        const XMLElement* elem;
        std::uint32_t base; ///< first index in out_.normals
        std::size_t count;  ///< number of vectors
    };
    std::vector<NormalSource> normal_sources_;
    std::size_t degenerate_ = 0, ngons_ = 0, bent_ngons_ = 0;
    std::uint64_t total_triangles_ = 0; ///< fan triangles of every group so far

    /// `<p>` holds `n` indices where `corners` x `stride` were expected.
    [[noreturn]] void fail_index_count(const XMLElement* pe, const std::string& gname,
                                       std::size_t n, std::uint64_t corners,
                                       std::uint32_t stride) const {
        const bool fits = corners <= std::numeric_limits<std::uint64_t>::max() / stride;
        ctx_.fail(pe,
                  "<p> of " + gname + " has " + std::to_string(n) + " indices but " +
                      std::to_string(corners) + " corners x stride " + std::to_string(stride) +
                      " = " +
                      (fits ? std::to_string(corners * stride) : std::string("more than 2^64")) +
                      " expected");
    }

    /// Appends a NORMAL source to out_.normals once; returns where it sits there.
    NormalSource normal_source(const XMLElement* source) {
        for (auto& s : normal_sources_)
            if (s.elem == source) return s;
        std::vector<Vec3> n;
        read_vec3_source(ctx_, source, n);
        NormalSource ns{source, static_cast<std::uint32_t>(out_.normals.size()), n.size()};
        out_.normals.insert(out_.normals.end(), n.begin(), n.end());
        normal_sources_.push_back(ns);
        return ns;
    }

    void parse_group(const XMLElement* g) {
        const std::string gname = std::string("<") + g->Name() + "> of mesh '" + out_.name + "'";
        DescPrimGroup grp;
        grp.line = g->GetLineNum();
        if (const char* m = g->Attribute("material")) grp.material_symbol = m;

        // Inputs; the index stride is max(offset)+1 over every input, recognised or not.
        Input vertex, normal;
        std::uint32_t stride = 0;
        std::size_t normal_n = 0;
        std::uint32_t normal_base = 0;
        for (const XMLElement* in = g->FirstChildElement("input"); in;
             in = in->NextSiblingElement("input")) {
            std::uint32_t off = ctx_.uint_attr(in, "offset", true, 0);
            if (off > loader_limits::kMaxInputOffset)
                ctx_.fail(in, "<input> of " + gname + " has offset " + std::to_string(off) +
                                  ", more than the limit of " +
                                  std::to_string(loader_limits::kMaxInputOffset));
            stride = std::max(stride, off + 1);
            const char* sem = in->Attribute("semantic");
            if (!sem) ctx_.fail(in, "<input> of " + gname + " has no 'semantic' attribute");
            if (std::strcmp(sem, "VERTEX") == 0) {
                const XMLElement* v = ctx_.resolve(in, "source", "vertices");
                if (v != vertices_)
                    ctx_.fail(in, "VERTEX input of " + gname + " names '" +
                                      std::string(in->Attribute("source")) +
                                      "', not this mesh's <vertices>");
                vertex = {off, in};
            } else if (std::strcmp(sem, "NORMAL") == 0) {
                NormalSource ns = normal_source(ctx_.resolve(in, "source", "source"));
                normal = {off, in};
                normal_n = ns.count;
                normal_base = ns.base;
            } else if (std::strcmp(sem, "TEXCOORD") == 0) {
                ctx_.resolve(in, "source", "source"); // validated, not used (no textures)
            }
        }
        if (!vertex.elem) ctx_.fail(g, gname + " has no VERTEX input");

        // Polygon sizes.
        std::vector<std::uint32_t> sizes;
        const bool polygons = tag_is(g, "polygons");
        std::uint32_t count = ctx_.uint_attr(g, "count", !polygons, 0);
        std::vector<std::uint32_t> p;
        const XMLElement* first_p = g->FirstChildElement("p");
        if (tag_is(g, "triangles")) {
            if (count > 0 && !first_p) ctx_.fail(g, gname + " has no <p>");
            // Every corner needs `stride` indices in <p>. A count that the text cannot hold is
            // reported from the (text-bounded) indices, before count polygon sizes are allocated.
            if (std::uint64_t(count) * 3 * stride > Context::max_numbers_in(first_p)) {
                ctx_.parse_uints(first_p, p, "<p> of " + gname);
                fail_index_count(first_p, gname, p.size(), std::uint64_t(count) * 3, stride);
            }
            sizes.assign(count, 3);
        } else if (tag_is(g, "polylist")) {
            const XMLElement* vc = g->FirstChildElement("vcount");
            if (!vc && count > 0) ctx_.fail(g, gname + " has no <vcount>");
            if (vc) ctx_.parse_uints(vc, sizes, "<vcount> of " + gname);
            if (sizes.size() != count)
                ctx_.fail(vc, "<vcount> of " + gname + " has " + std::to_string(sizes.size()) +
                                  " numbers but count=\"" + std::to_string(count) + "\"");
        }
        if (polygons) {
            std::vector<std::uint32_t> one;
            for (const XMLElement* pe = g->FirstChildElement("p"); pe;
                 pe = pe->NextSiblingElement("p")) {
                ctx_.parse_uints(pe, one, "<p> of " + gname);
                if (one.size() % stride != 0)
                    ctx_.fail(pe, "<p> of " + gname + " has " + std::to_string(one.size()) +
                                      " indices, not a multiple of the input stride " +
                                      std::to_string(stride));
                sizes.push_back(static_cast<std::uint32_t>(one.size() / stride));
                p.insert(p.end(), one.begin(), one.end());
            }
            if (g->FirstChildElement("ph"))
                ctx_.warn_once("ph", g->FirstChildElement("ph"),
                               "<ph> (polygons with holes) ignored (not supported)");
            if (g->Attribute("count") && sizes.size() != count)
                ctx_.fail(g, gname + " has count=\"" + std::to_string(count) + "\" but " +
                                 std::to_string(sizes.size()) + " <p> elements");
        }
        // At most 2^32 - 1 per polygon and fewer polygons than text bytes: no overflow.
        std::uint64_t corners = 0;
        for (std::size_t i = 0; i < sizes.size(); ++i) {
            if (sizes[i] < 3)
                ctx_.fail(g, gname + ": polygon " + std::to_string(i) + " has " +
                                 std::to_string(sizes[i]) + " vertices (need at least 3)");
            corners += sizes[i];
        }
        if (!polygons && count > 0) {
            const XMLElement* pe = g->FirstChildElement("p");
            if (!pe) ctx_.fail(g, gname + " has no <p>");
            ctx_.parse_uints(pe, p, "<p> of " + gname);
            // corners * stride may not fit 64 bits (vcounts near 2^32 with a stride near the
            // limit): compare by division, which is exact here.
            if (p.size() % stride != 0 || p.size() / stride != corners)
                fail_index_count(pe, gname, p.size(), corners, stride);
        }
        // Fan triangulation makes n - 2 triangles of an n-gon (corners are now backed by text).
        const std::uint64_t fan_triangles = corners - 2 * sizes.size();
        total_triangles_ += fan_triangles;
        if (total_triangles_ > loader_limits::kMaxTriangles)
            ctx_.fail(g, "mesh '" + out_.name + "' has more than " +
                             std::to_string(loader_limits::kMaxTriangles) +
                             " triangles (the loader's limit)");

        // Corners -> fan triangles.
        const std::size_t npos = out_.positions.size();
        const bool with_normals = normal.elem || vertex_normal_input_;
        std::vector<std::uint32_t> pi, ni;
        std::size_t k = 0; // corner counter
        const XMLElement* pe = g->FirstChildElement("p");
        for (std::uint32_t n : sizes) {
            pi.resize(n);
            ni.resize(n);
            for (std::uint32_t c = 0; c < n; ++c, ++k) {
                std::uint32_t vi = p[k * stride + vertex.offset];
                if (vi >= npos)
                    ctx_.fail(pe, "<p> of " + gname + ": VERTEX index " + std::to_string(vi) +
                                      " out of range (" + std::to_string(npos) + " positions)");
                pi[c] = vi;
                if (normal.elem) {
                    std::uint32_t nn = p[k * stride + normal.offset];
                    if (nn >= normal_n)
                        ctx_.fail(pe, "<p> of " + gname + ": NORMAL index " + std::to_string(nn) +
                                          " out of range (" + std::to_string(normal_n) +
                                          " normals)");
                    ni[c] = normal_base + nn;
                } else if (vertex_normal_input_) {
                    ni[c] = vertex_normal_base_ + vi;
                }
            }
            if (n > 3) check_fan(pi);
            for (std::uint32_t c = 1; c + 1 < n; ++c) {
                if (degenerate(pi[0], pi[c], pi[c + 1])) {
                    ++degenerate_;
                    continue;
                }
                grp.position_index.insert(grp.position_index.end(), {pi[0], pi[c], pi[c + 1]});
                if (with_normals)
                    grp.normal_index.insert(grp.normal_index.end(), {ni[0], ni[c], ni[c + 1]});
            }
        }
        out_.groups.push_back(std::move(grp));
    }
    bool degenerate(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
        Vec3d p0 = to_d(out_.positions[a]);
        Vec3d e1 = to_d(out_.positions[b]) - p0, e2 = to_d(out_.positions[c]) - p0;
        double l1 = length(e1), l2 = length(e2);
        if (l1 == 0.0 || l2 == 0.0) return true;
        return length(cross(e1, e2)) <= kDegenerateSine * l1 * l2;
    }

    void check_fan(const std::vector<std::uint32_t>& pi) {
        ++ngons_;
        Vec3d N(0.0);
        const std::size_t n = pi.size();
        for (std::size_t i = 0; i < n; ++i) { // Newell's method
            Vec3d a = to_d(out_.positions[pi[i]]), b = to_d(out_.positions[pi[(i + 1) % n]]);
            N += Vec3d((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x),
                       (a.x - b.x) * (a.y + b.y));
        }
        double ln = length(N);
        if (ln == 0.0) return; // fully degenerate: its triangles are dropped and counted
        N /= ln;
        Vec3d p0 = to_d(out_.positions[pi[0]]);
        for (std::size_t c = 1; c + 1 < n; ++c) {
            Vec3d t = cross(to_d(out_.positions[pi[c]]) - p0, to_d(out_.positions[pi[c + 1]]) - p0);
            double lt = length(t);
            if (lt == 0.0) continue;
            if (dot(t, N) / lt < kFanCosine) {
                ++bent_ngons_;
                return;
            }
        }
    }
};

} // namespace

bool parse_geometry(Context& ctx, const XMLElement* g, DescGeometry& out) {
    out.name = display_id(g);
    out.line = g->GetLineNum();
    if (const XMLElement* mesh = g->FirstChildElement("mesh")) {
        out.kind = DescGeometryKind::Mesh;
        MeshParser(ctx, mesh, out).run();
        return true;
    }
    // CGL sphere extension (spec §1.6).
    for (const XMLElement* x = g->FirstChildElement("extra"); x; x = x->NextSiblingElement("extra"))
        for (const XMLElement* t = x->FirstChildElement("technique"); t;
             t = t->NextSiblingElement("technique")) {
            const char* prof = t->Attribute("profile");
            if (!prof || std::strcmp(prof, "CGL") != 0) continue;
            const XMLElement* s = t->FirstChildElement("sphere");
            if (!s) ctx.fail(t, "CGL technique of geometry '" + out.name + "' has no <sphere>");
            const XMLElement* r = s->FirstChildElement("radius");
            if (!r) ctx.fail(s, "<sphere> of geometry '" + out.name + "' has no <radius>");
            float radius = 0.f;
            ctx.parse_exact(r, &radius, 1, "sphere radius of geometry '" + out.name + "'");
            if (!(radius > 0.f))
                ctx.fail(r, "sphere radius of geometry '" + out.name + "' is " +
                                std::to_string(radius) + ", must be positive");
            out.kind = DescGeometryKind::Sphere;
            out.radius = radius;
            return true;
        }
    const XMLElement* first = g->FirstChildElement();
    std::string kind = first ? first->Name() : "empty";
    ctx.warn_once("geometry:" + kind, g,
                  "geometry '" + out.name + "' (<" + kind +
                      ">) is neither a <mesh> nor a CGL sphere; ignored");
    return false;
}

} // namespace candela::collada_detail
