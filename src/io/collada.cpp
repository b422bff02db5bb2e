// COLLADA reader: document, scene graph, materials, lights and cameras. Geometry lives in
// collada_mesh.cpp, the context and number parsing in collada_context.cpp. See spec §1 and §11 for
// the dialect.
#include "collada_internal.h"

#include "candela/math/constants.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace candela {

float DescCamera::hfov_deg() const {
    if (xfov) return *xfov;
    if (yfov && aspect_ratio)
        return static_cast<float>(
            rad_to_deg(2.0 * std::atan(std::tan(deg_to_rad(0.5 * *yfov)) * *aspect_ratio)));
    return 50.f; // COLLADA/CS184 default (spec §1.4)
}

float DescCamera::course_hfov_deg(double aspect) const {
    const float hfov = xfov.value_or(50.f);
    const double tan_h = std::tan(deg_to_rad(0.5 * double(hfov)));
    double tan_v = 0.0;
    if (yfov)
        tan_v = std::tan(deg_to_rad(0.5 * double(*yfov)));
    else if (aspect_ratio)
        tan_v = tan_h / double(*aspect_ratio);
    // Without either, the vertical field of view follows the window (nothing to widen).
    if (!(tan_v * aspect > tan_h)) return hfov;
    return static_cast<float>(rad_to_deg(2.0 * std::atan(tan_v * aspect)));
}

namespace {

using namespace collada_detail;

// The recursive <node> walk relies on tinyxml2's depth limit to bound its stack use.
static_assert(loader_limits::kMaxXmlDepth == TINYXML2_MAX_ELEMENT_DEPTH - 2,
              "loader_limits::kMaxXmlDepth must match tinyxml2's element depth limit");

bool tag_is(const XMLElement* e, const char* tag) {
    return std::strcmp(e->Name(), tag) == 0;
}

/// The `<technique profile="...">` inside any `<extra>` child of `e`, or null.
const XMLElement* find_extra_technique(const XMLElement* e, const char* profile) {
    for (const XMLElement* x = e->FirstChildElement("extra"); x; x = x->NextSiblingElement("extra"))
        for (const XMLElement* t = x->FirstChildElement("technique"); t;
             t = t->NextSiblingElement("technique")) {
            const char* p = t->Attribute("profile");
            if (p && std::strcmp(p, profile) == 0) return t;
        }
    return nullptr;
}

class SceneParser {
  public:
    SceneParser(Context& ctx, SceneDesc& desc) : ctx_(ctx), desc_(desc) {}

    void run(tinyxml2::XMLElement* root) {
        if (!tag_is(root, "COLLADA"))
            ctx_.fail(root, std::string("root element is <") + root->Name() +
                                ">, not <COLLADA>: not a COLLADA file");
        ctx_.index_ids(root);
        parse_up_axis(root);
        warn_ignored_libraries(root);

        const XMLElement* scene = root->FirstChildElement("scene");
        if (!scene) ctx_.fail(root, "missing <scene> element");
        const XMLElement* ivs = scene->FirstChildElement("instance_visual_scene");
        if (!ivs) ctx_.fail(scene, "<scene> has no <instance_visual_scene>");
        const XMLElement* vs = ctx_.resolve(ivs, "url", "visual_scene");
        for (const XMLElement* n = vs->FirstChildElement(); n; n = n->NextSiblingElement()) {
            if (tag_is(n, "node"))
                parse_node(n, desc_.up);
            else if (!tag_is(n, "extra") && !tag_is(n, "asset"))
                ctx_.warn_once(n->Name(), n,
                               std::string("<") + n->Name() + "> in <visual_scene> ignored");
        }
    }

  private:
    Context& ctx_;
    SceneDesc& desc_;
    std::unordered_map<const XMLElement*, int> geometry_index_, light_index_, camera_index_,
        material_index_;

    // ---- asset -------------------------------------------------------------------------------

    void parse_up_axis(const XMLElement* root) {
        // Spec §1.2: U maps the file's up axis to world +Y. A file without <asset>/<up_axis>
        // is taken as Y_UP (COLLADA's own default) with a warning, rather than collapsing the
        // scene as the course reference does or refusing an otherwise valid file.
        const XMLElement* asset = root->FirstChildElement("asset");
        const XMLElement* up = asset ? asset->FirstChildElement("up_axis") : nullptr;
        Mat4 U;
        if (!up) {
            ctx_.warn(asset ? asset : root, "no <asset>/<up_axis>; assuming Y_UP");
            desc_.up_axis_given = false;
        } else {
            std::string v = up->GetText() ? up->GetText() : "";
            v.erase(0, v.find_first_not_of(" \t\r\n"));
            v.erase(v.find_last_not_of(" \t\r\n") + 1);
            if (v == "Y_UP") {
            } else if (v == "Z_UP") {
                const double m[16] = {-1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 1};
                U = Mat4::from_row_major(m);
            } else if (v == "X_UP") {
                const double m[16] = {0, 1, 0, 0, 1, 0, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1};
                U = Mat4::from_row_major(m);
            } else {
                ctx_.fail(up, "<up_axis> is '" + v + "', expected X_UP, Y_UP or Z_UP");
            }
        }
        desc_.up = U;
    }

    void warn_ignored_libraries(const XMLElement* root) {
        static const char* const kIgnored[] = {
            "library_animations",     "library_animation_clips", "library_controllers",
            "library_physics_scenes", "library_physics_models",  "library_kinematics_models",
            "library_formulas"};
        for (const char* lib : kIgnored)
            if (const XMLElement* e = root->FirstChildElement(lib))
                if (e->FirstChildElement())
                    ctx_.warn_once(lib, e, std::string("<") + lib + "> ignored (not supported)");
    }

    // ---- nodes -------------------------------------------------------------------------------

    Mat4 local_transform(const XMLElement* node) {
        // COLLADA composes transform elements in document order: L = T1·T2·...·Tn, so the
        // last one is applied to the geometry first (candela does not reproduce the course
        // reference's reversed order or its stop at <matrix>).
        Mat4 L;
        std::vector<double> v;
        const std::string where = "node '" + display_id(node) + "'";
        for (const XMLElement* t = node->FirstChildElement(); t; t = t->NextSiblingElement()) {
            Mat4 m;
            if (tag_is(t, "matrix")) {
                ctx_.parse_doubles(t, v, "<matrix> of " + where);
                if (v.size() == 16) {
                    m = Mat4::from_row_major(v.data());
                } else if (v.size() >= 12 && v.size() < 16) {
                    // A truncated matrix (CBgems' camera has 15 numbers): keep the three
                    // affine rows that are complete and use (0 0 0 1) as the bottom row.
                    ctx_.warn(t, "<matrix> of " + where + " has " + std::to_string(v.size()) +
                                     " numbers, expected 16; bottom row taken as (0 0 0 1)");
                    ++desc_.short_matrices;
                    double full[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
                    for (int i = 0; i < 12; ++i)
                        full[i] = v[static_cast<std::size_t>(i)];
                    m = Mat4::from_row_major(full);
                } else {
                    ctx_.fail(t, "<matrix> of " + where + " has " + std::to_string(v.size()) +
                                     " numbers, expected 16");
                }
            } else if (tag_is(t, "translate") || tag_is(t, "scale")) {
                ++desc_.composed_transforms;
                ctx_.parse_doubles(t, v, std::string("<") + t->Name() + "> of " + where);
                if (v.size() != 3)
                    ctx_.fail(t, std::string("<") + t->Name() + "> of " + where + " has " +
                                     std::to_string(v.size()) + " numbers, expected 3");
                Vec3d a(v[0], v[1], v[2]);
                m = tag_is(t, "translate") ? Mat4::translate(a) : Mat4::scale(a);
            } else if (tag_is(t, "rotate")) {
                ++desc_.composed_transforms;
                ctx_.parse_doubles(t, v, "<rotate> of " + where);
                if (v.size() != 4)
                    ctx_.fail(t, "<rotate> of " + where + " has " + std::to_string(v.size()) +
                                     " numbers, expected 4 (axis x y z, angle in degrees)");
                Vec3d axis(v[0], v[1], v[2]);
                if (length(axis) == 0.0) ctx_.fail(t, "<rotate> of " + where + " has a zero axis");
                m = Mat4::rotate(axis, v[3]);
            } else if (tag_is(t, "lookat")) {
                ++desc_.composed_transforms;
                ctx_.parse_doubles(t, v, "<lookat> of " + where);
                if (v.size() != 9)
                    ctx_.fail(t, "<lookat> of " + where + " has " + std::to_string(v.size()) +
                                     " numbers, expected 9 (eye, interest, up)");
                Vec3d eye(v[0], v[1], v[2]), at(v[3], v[4], v[5]), up(v[6], v[7], v[8]);
                if (length(eye - at) == 0.0 || length(cross(up, eye - at)) == 0.0)
                    ctx_.fail(t, "<lookat> of " + where +
                                     " is degenerate (eye = interest, or up parallel to the "
                                     "view direction)");
                m = Mat4::look_at(eye, at, up);
            } else if (tag_is(t, "skew")) {
                ctx_.warn_once("skew", t, "<skew> ignored (not supported)");
                continue;
            } else {
                continue;
            }
            L = L * m;
        }
        return L;
    }

    void parse_node(const XMLElement* node, const Mat4& parent) {
        Mat4 W = parent * local_transform(node);
        if (!W.is_finite())
            ctx_.fail(node, "node '" + display_id(node) + "' has a non-finite world transform");
        const std::string node_name = display_id(node);
        for (const XMLElement* c = node->FirstChildElement(); c; c = c->NextSiblingElement()) {
            if (tag_is(c, "node")) {
                ++desc_.nested_nodes;
                parse_node(c, W);
            } else if (tag_is(c, "instance_geometry")) {
                add_geometry_instance(c, W, node_name);
            } else if (tag_is(c, "instance_light")) {
                const XMLElement* l = ctx_.resolve(c, "url", "light");
                int idx = light(l);
                if (idx >= 0) add_instance(DescInstanceKind::Light, idx, W, node_name, c);
            } else if (tag_is(c, "instance_camera")) {
                const XMLElement* cam = ctx_.resolve(c, "url", "camera");
                int idx = camera(cam);
                if (idx >= 0) add_instance(DescInstanceKind::Camera, idx, W, node_name, c);
            } else if (tag_is(c, "instance_node") || tag_is(c, "instance_controller")) {
                ctx_.warn_once(c->Name(), c,
                               std::string("<") + c->Name() + "> ignored (not supported)");
            }
        }
    }

    DescInstance& add_instance(DescInstanceKind kind, int idx, const Mat4& W,
                               const std::string& node_name, const XMLElement* e) {
        DescInstance inst;
        inst.kind = kind;
        inst.index = idx;
        inst.world = W;
        inst.node_name = node_name;
        inst.line = e->GetLineNum();
        desc_.instances.push_back(std::move(inst));
        return desc_.instances.back();
    }

    void add_geometry_instance(const XMLElement* ig, const Mat4& W, const std::string& node_name) {
        const XMLElement* g = ctx_.resolve(ig, "url", "geometry");
        int gi = geometry(g);
        if (gi < 0) return;
        // Materials bound by symbol (spec §1.8; candela honours the symbols, §11).
        std::vector<std::pair<std::string, int>> bound;
        if (const XMLElement* bm = ig->FirstChildElement("bind_material"))
            if (const XMLElement* tc = bm->FirstChildElement("technique_common"))
                for (const XMLElement* im = tc->FirstChildElement("instance_material"); im;
                     im = im->NextSiblingElement("instance_material")) {
                    const XMLElement* mat = ctx_.resolve(im, "target", "material");
                    const char* sym = im->Attribute("symbol");
                    bound.emplace_back(sym ? sym : "", material(mat));
                }
        DescInstance& inst = add_instance(DescInstanceKind::Geometry, gi, W, node_name, ig);
        inst.material = bound.empty() ? -1 : bound.front().second;
        for (const DescPrimGroup& grp : desc_.geometries[static_cast<std::size_t>(gi)].groups) {
            int m = inst.material;
            for (const auto& b : bound)
                if (!grp.material_symbol.empty() && b.first == grp.material_symbol) {
                    m = b.second;
                    break;
                }
            inst.group_materials.push_back(m);
        }
    }

    // ---- library objects (parsed once, on first reference) ----------------------------------

    int geometry(const XMLElement* g) {
        auto it = geometry_index_.find(g);
        if (it != geometry_index_.end()) return it->second;
        DescGeometry geo;
        int idx = -1;
        if (parse_geometry(ctx_, g, geo)) {
            idx = static_cast<int>(desc_.geometries.size());
            desc_.geometries.push_back(std::move(geo));
        }
        geometry_index_[g] = idx;
        return idx;
    }

    Rgb read_rgb(const XMLElement* e, const std::string& what) {
        std::vector<float> v;
        ctx_.parse_floats(e, v, what);
        if (v.size() < 3)
            ctx_.fail(e, what + " needs 3 numbers but has " + std::to_string(v.size()));
        return Rgb(v[0], v[1], v[2]);
    }
    const XMLElement* required(const XMLElement* parent, const char* tag, const std::string& what) {
        const XMLElement* e = parent->FirstChildElement(tag);
        if (!e) ctx_.fail(parent, what + " is missing <" + tag + ">");
        return e;
    }
    float read_float(const XMLElement* e, const std::string& what) {
        float f = 0.f;
        ctx_.parse_exact(e, &f, 1, what);
        return f;
    }

    int material(const XMLElement* mat) {
        auto it = material_index_.find(mat);
        if (it != material_index_.end()) return it->second;
        DescMaterial dm;
        dm.line = mat->GetLineNum();
        Material& m = dm.material;
        m.name = display_id(mat);
        const std::string what = "material '" + m.name + "'";
        const XMLElement* ie = mat->FirstChildElement("instance_effect");
        if (!ie) ctx_.fail(mat, what + " has no <instance_effect>");
        const XMLElement* effect = ctx_.resolve(ie, "url", "effect");

        // Common profile: phong, else lambert, diffuse colour (spec §1.8).
        Rgb common_diffuse(0.5f);
        if (const XMLElement* pc = effect->FirstChildElement("profile_COMMON"))
            if (const XMLElement* tech = pc->FirstChildElement("technique"))
                for (const char* shader : {"phong", "lambert"}) {
                    const XMLElement* s = tech->FirstChildElement(shader);
                    const XMLElement* d = s ? s->FirstChildElement("diffuse") : nullptr;
                    const XMLElement* c = d ? d->FirstChildElement("color") : nullptr;
                    if (c) {
                        common_diffuse = read_rgb(c, "diffuse colour of " + what);
                        break;
                    }
                }
        m.kind = BsdfKind::Diffuse;
        m.albedo = common_diffuse;

        // CGL technique: each recognised element replaces the BSDF; the last one wins.
        if (const XMLElement* cgl = find_extra_technique(effect, "CGL")) {
            for (const XMLElement* b = cgl->FirstChildElement(); b; b = b->NextSiblingElement()) {
                const std::string bw = "<" + std::string(b->Name()) + "> of " + what;
                if (tag_is(b, "emission")) {
                    m.kind = BsdfKind::Emission;
                    m.radiance = read_rgb(required(b, "radiance", bw), "radiance of " + what);
                } else if (tag_is(b, "mirror")) {
                    m.kind = BsdfKind::Mirror;
                    m.reflectance =
                        read_rgb(required(b, "reflectance", bw), "reflectance of " + what);
                } else if (tag_is(b, "glass") || tag_is(b, "refraction")) {
                    bool glass = tag_is(b, "glass");
                    m.kind = glass ? BsdfKind::Glass : BsdfKind::Refraction;
                    m.transmittance =
                        read_rgb(required(b, "transmittance", bw), "transmittance of " + what);
                    if (glass)
                        m.reflectance =
                            read_rgb(required(b, "reflectance", bw), "reflectance of " + what);
                    if (const XMLElement* r = b->FirstChildElement("roughness")) {
                        // Beckmann alpha of a rough interface (0 = smooth); see material.h.
                        m.roughness = read_float(r, "roughness of " + what);
                        if (!(m.roughness >= 0.f))
                            ctx_.fail(r, "roughness of " + what + " must be 0 or positive");
                    }
                    const XMLElement* ior = required(b, "ior", bw);
                    m.ior = read_float(ior, "ior of " + what);
                    if (!(m.ior > 0.f)) ctx_.fail(ior, "ior of " + what + " must be positive");
                } else if (tag_is(b, "microfacet")) {
                    m.kind = BsdfKind::Microfacet;
                    const XMLElement* a = required(b, "alpha", bw);
                    m.alpha = read_float(a, "alpha of " + what);
                    if (!(m.alpha > 0.f)) ctx_.fail(a, "alpha of " + what + " must be positive");
                    m.eta = read_rgb(required(b, "eta", bw), "eta of " + what);
                    m.k = read_rgb(required(b, "k", bw), "k of " + what);
                } else {
                    ctx_.warn(b, "unknown CGL BSDF <" + std::string(b->Name()) + "> in " + what +
                                     "; using the common diffuse colour");
                }
            }
        }
        int idx = static_cast<int>(desc_.materials.size());
        desc_.materials.push_back(std::move(dm));
        material_index_[mat] = idx;
        return idx;
    }

    int light(const XMLElement* l) {
        auto it = light_index_.find(l);
        if (it != light_index_.end()) return it->second;
        DescLight dl;
        dl.name = display_id(l);
        dl.line = l->GetLineNum();
        const std::string what = "light '" + dl.name + "'";
        // CGL extra wins over technique_common (spec §1.5).
        const XMLElement* tech = find_extra_technique(l, "CGL");
        if (!tech) tech = l->FirstChildElement("technique_common");
        if (!tech)
            if (const XMLElement* pc = l->FirstChildElement("profile_COMMON"))
                tech = pc->FirstChildElement("technique");
        if (!tech) ctx_.fail(l, what + " has neither a CGL technique nor <technique_common>");
        const XMLElement* type = tech->FirstChildElement();
        if (!type) ctx_.fail(tech, what + ": technique has no light type element");
        const std::string t = type->Name();
        if (t == "ambient")
            dl.kind = DescLightKind::Ambient;
        else if (t == "directional")
            dl.kind = DescLightKind::Directional;
        else if (t == "point")
            dl.kind = DescLightKind::Point;
        else if (t == "spot")
            dl.kind = DescLightKind::Spot;
        else if (t == "area")
            dl.kind = DescLightKind::Area;
        else
            ctx_.fail(type, what + " has unknown light type <" + t +
                                "> (expected ambient, directional, point, spot or area)");

        if (const XMLElement* c = type->FirstChildElement("color")) {
            dl.color = read_rgb(c, "colour of " + what);
        } else {
            const XMLElement* en = type->FirstChildElement("energy");
            const XMLElement* r = type->FirstChildElement("red");
            const XMLElement* g = type->FirstChildElement("green");
            const XMLElement* b = type->FirstChildElement("blue");
            if (!(en && r && g && b))
                ctx_.fail(type, what + " has neither <color> nor <energy>/<red>/<green>/<blue>");
            dl.color = Rgb(read_float(r, "red of " + what), read_float(g, "green of " + what),
                           read_float(b, "blue of " + what)) *
                       read_float(en, "energy of " + what);
        }
        if (dl.color.x < 0.f || dl.color.y < 0.f || dl.color.z < 0.f)
            ctx_.fail(type, what + " has a negative colour");
        for (const char* att :
             {"constant_attenuation", "linear_attenuation", "quadratic_attenuation"})
            if (type->FirstChildElement(att)) dl.has_attenuation = true;
        if (dl.kind == DescLightKind::Spot) {
            if (const XMLElement* fa = type->FirstChildElement("falloff_angle")) {
                dl.falloff_angle_deg = read_float(fa, "falloff_angle of " + what);
                if (!(dl.falloff_angle_deg > 0.f && dl.falloff_angle_deg <= 360.f))
                    ctx_.fail(fa, "falloff_angle of " + what + " must be in (0, 360] degrees");
            }
            if (const XMLElement* fe = type->FirstChildElement("falloff_exponent")) {
                dl.falloff_exponent = read_float(fe, "falloff_exponent of " + what);
                if (dl.falloff_exponent < 0.f)
                    ctx_.fail(fe, "falloff_exponent of " + what + " must not be negative");
            }
        }
        int idx = static_cast<int>(desc_.lights.size());
        desc_.lights.push_back(std::move(dl));
        light_index_[l] = idx;
        return idx;
    }

    int camera(const XMLElement* c) {
        auto it = camera_index_.find(c);
        if (it != camera_index_.end()) return it->second;
        DescCamera dc;
        dc.name = display_id(c);
        dc.line = c->GetLineNum();
        const std::string what = "camera '" + dc.name + "'";
        const XMLElement* optics = required(c, "optics", what);
        const XMLElement* tc = required(optics, "technique_common", what + " <optics>");
        const XMLElement* persp = tc->FirstChildElement("perspective");
        int idx = -1;
        if (!persp) {
            if (tc->FirstChildElement("orthographic")) {
                ctx_.warn_once("orthographic", tc,
                               "orthographic " + what + " ignored (only perspective cameras)");
                camera_index_[c] = idx;
                return idx;
            }
            ctx_.fail(tc, what + " has no <perspective>");
        }
        auto opt = [&](const char* tag) -> std::optional<float> {
            const XMLElement* e = persp->FirstChildElement(tag);
            if (!e) return std::nullopt;
            return read_float(e, std::string(tag) + " of " + what);
        };
        dc.xfov = opt("xfov");
        dc.yfov = opt("yfov");
        dc.aspect_ratio = opt("aspect_ratio");
        for (const auto* f : {&dc.xfov, &dc.yfov})
            if (*f && !(**f > 0.f && **f < 180.f))
                ctx_.fail(persp, what + ": field of view must be in (0, 180) degrees");
        if (dc.aspect_ratio && !(*dc.aspect_ratio > 0.f))
            ctx_.fail(persp, what + ": aspect_ratio must be positive");
        if (!dc.xfov && dc.yfov && !dc.aspect_ratio)
            ctx_.fail(persp, what + " has <yfov> but neither <xfov> nor <aspect_ratio>");
        if (auto zn = opt("znear")) dc.znear = *zn;
        if (auto zf = opt("zfar")) dc.zfar = *zf;
        if (!(dc.znear >= 0.f && dc.zfar > dc.znear))
            ctx_.fail(persp, what + ": need 0 <= znear < zfar");
        idx = static_cast<int>(desc_.cameras.size());
        desc_.cameras.push_back(std::move(dc));
        camera_index_[c] = idx;
        return idx;
    }
};

} // namespace

namespace {

/// What went wrong in a user's words (tinyxml2's own texts name its internal enums).
std::string xml_error_text(tinyxml2::XMLError err) {
    switch (err) {
    case tinyxml2::XML_ERROR_PARSING_ELEMENT:
        return "a bad element tag";
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE:
        return "a bad attribute";
    case tinyxml2::XML_ERROR_PARSING_TEXT:
        return "bad text (a stray '<' or '&'?)";
    case tinyxml2::XML_ERROR_PARSING_CDATA:
        return "a bad CDATA section";
    case tinyxml2::XML_ERROR_PARSING_COMMENT:
        return "a bad comment";
    case tinyxml2::XML_ERROR_PARSING_DECLARATION:
        return "a bad declaration";
    case tinyxml2::XML_ERROR_PARSING_UNKNOWN:
        return "unrecognised markup";
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT:
        return "a closing tag that does not match its opening tag";
    default:
        return "the file is not well-formed XML";
    }
}

/// The name of the first element of an XML text (after the declaration and comments), "" when
/// none is found.
std::string first_element_name(const std::string& xml) {
    for (std::size_t i = xml.find('<'); i != std::string::npos; i = xml.find('<', i + 1)) {
        if (xml.compare(i, 4, "<!--") == 0) { // skip the comment, which may quote tags
            i = xml.find("-->", i);
            if (i == std::string::npos) return "";
            continue;
        }
        if (i + 1 >= xml.size() || !std::isalpha(static_cast<unsigned char>(xml[i + 1]))) continue;
        std::size_t end = i + 1;
        while (end < xml.size() && (std::isalnum(static_cast<unsigned char>(xml[end])) ||
                                    xml[end] == '_' || xml[end] == ':' || xml[end] == '-'))
            ++end;
        return xml.substr(i + 1, end - i - 1);
    }
    return "";
}

/// The line of the last character that is not white space (1 for an empty text).
int last_text_line(const std::string& xml) {
    const std::size_t last = xml.find_last_not_of(" \t\r\n");
    const auto end = last == std::string::npos ? xml.begin() : xml.begin() + long(last);
    return 1 + int(std::count(xml.begin(), end, '\n'));
}

/// True when the text, trailing white space aside, ends with </name>.
bool ends_with_closing_tag(const std::string& xml, const std::string& name) {
    const std::size_t last = xml.find_last_not_of(" \t\r\n");
    if (last == std::string::npos) return false;
    const std::string tag = "</" + name;
    const std::size_t open = xml.rfind(tag, last);
    return open != std::string::npos &&
           xml.find_first_not_of(" \t\r\n", open + tag.size()) == last && xml[last] == '>';
}

} // namespace

SceneDesc parse_collada(const std::string& xml_text, const std::string& display_name,
                        Diagnostics& diag) {
    if (xml_text.size() > loader_limits::kMaxFileBytes)
        throw Error(ErrorKind::Scene, SourceLoc{display_name, 0},
                    "file too large (" + std::to_string(xml_text.size()) + " bytes, limit " +
                        std::to_string(loader_limits::kMaxFileBytes) + ")");
    tinyxml2::XMLDocument doc;
    tinyxml2::XMLError err = doc.Parse(xml_text.data(), xml_text.size());
    if (err == tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED)
        throw Error(ErrorKind::Scene, SourceLoc{display_name, doc.ErrorLineNum()},
                    "XML elements nested deeper than " +
                        std::to_string(loader_limits::kMaxXmlDepth) + " levels");
    if (err == tinyxml2::XML_ERROR_EMPTY_DOCUMENT)
        throw Error(ErrorKind::Scene, SourceLoc{display_name, 0},
                    xml_text.empty() ? "empty file" : "no XML in the file");
    if (err != tinyxml2::XML_SUCCESS) {
        const std::string root_name = first_element_name(xml_text);
        if (!root_name.empty() && !ends_with_closing_tag(xml_text, root_name))
            throw Error(ErrorKind::Scene, SourceLoc{display_name, last_text_line(xml_text)},
                        "the file ends early (truncated?): no closing </" + root_name + ">");
        throw Error(ErrorKind::Scene, SourceLoc{display_name, doc.ErrorLineNum()},
                    "malformed XML: " + xml_error_text(err));
    }
    tinyxml2::XMLElement* root = doc.RootElement();
    if (!root) throw Error(ErrorKind::Scene, SourceLoc{display_name, 1}, "no root element");
    Context ctx(display_name, diag);
    SceneDesc desc;
    desc.source = display_name;
    SceneParser(ctx, desc).run(root);
    return desc;
}

SceneDesc load_collada(const std::string& path, Diagnostics& diag) {
    namespace fs = std::filesystem;
    const auto too_large = [&](std::uint64_t bytes, bool at_least) {
        throw Error(ErrorKind::Io, SourceLoc{path},
                    "file too large (" + std::string(at_least ? "more than " : "") +
                        std::to_string(bytes) + " bytes, limit " +
                        std::to_string(loader_limits::kMaxFileBytes) + ")");
    };
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw Error(ErrorKind::Io, SourceLoc{path}, "is a directory, not a scene file");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw Error(ErrorKind::Io, SourceLoc{path},
                    std::string("cannot open scene file: ") + std::strerror(errno));
    // A regular file's size is known up front: a huge one is refused before any of it is read.
    if (fs::is_regular_file(path, ec)) {
        const std::uintmax_t size = fs::file_size(path, ec);
        if (!ec && size > loader_limits::kMaxFileBytes) too_large(size, false);
    }
    // Pipes, devices and files that grow while being read: stop one chunk past the limit.
    std::string text;
    std::vector<char> chunk(std::size_t(1) << 16);
    while (in) {
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
        if (text.size() > loader_limits::kMaxFileBytes)
            too_large(loader_limits::kMaxFileBytes, true);
    }
    if (in.bad()) throw Error(ErrorKind::Io, SourceLoc{path}, "cannot read scene file");
    return parse_collada(text, path, diag);
}

Scene load_scene(const std::string& path, const BuildOptions& opt, Diagnostics& diag) {
    const SceneDesc desc = load_collada(path, diag);
    return build_scene(desc, opt, diag);
}

} // namespace candela
