#include "candela/scene/scene.h"

namespace candela {

const char* bsdf_kind_name(BsdfKind k) {
    switch (k) {
    case BsdfKind::Diffuse: return "diffuse";
    case BsdfKind::Emission: return "emission";
    case BsdfKind::Mirror: return "mirror";
    case BsdfKind::Glass: return "glass";
    case BsdfKind::Refraction: return "refraction";
    case BsdfKind::Microfacet: return "microfacet";
    case BsdfKind::Count: break;
    }
    return "?";
}

Light rect_light(const Vec3& center, const Vec3& n, const Vec3& dx, const Vec3& dy,
                 const Rgb& L) {
    Light l;
    l.kind = LightKind::Rect;
    l.L = L;
    l.p = center;
    l.n = n;
    l.dx = dx;
    l.dy = dy;
    l.area = length(cross(dx, dy));
    return l;
}

const char* light_kind_name(LightKind k) {
    switch (k) {
    case LightKind::Rect: return "area";
    case LightKind::Mesh: return "mesh";
    case LightKind::Sphere: return "sphere";
    case LightKind::Point: return "point";
    case LightKind::Spot: return "spot";
    case LightKind::Directional: return "directional";
    case LightKind::Ambient: return "ambient";
    case LightKind::Environment: return "environment";
    case LightKind::Count: break;
    }
    return "?";
}

void Scene::finalize() {
    bounds = Bounds3{};
    features = SceneFeatures{};
    for (const auto& m : meshes) {
        for (const Vec3& p : m.positions) bounds.grow(p);
        if (m.triangle_count() > 0)
            features.bsdf_mask |= 1u << static_cast<int>(materials.at(m.material).kind);
    }
    for (const auto& s : spheres) {
        bounds.grow(s.center - Vec3(s.radius));
        bounds.grow(s.center + Vec3(s.radius));
        features.bsdf_mask |= 1u << static_cast<int>(materials.at(s.material).kind);
    }
    for (const auto& l : lights) features.light_mask |= 1u << static_cast<int>(l.kind);
}

} // namespace candela
