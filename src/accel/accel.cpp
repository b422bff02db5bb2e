// The accelerator choice (make_accel), the batch defaults of the Accel interface and the
// closed-room test.
#include "candela/accel/accel.h"

#include "candela/accel/brute.h"
#include "candela/accel/bvh.h"
#include "candela/math/constants.h"
#include "candela/util/error.h"
#include "embree_accel.h"

#include <algorithm>
#include <cmath>

namespace candela {

Ray batch_ray(const BatchRay& r) {
    Ray ray;
    ray.o = Vec3(r.org_x, r.org_y, r.org_z);
    ray.d = Vec3(r.dir_x, r.dir_y, r.dir_z);
    // [tnear, tfar] over floats is (the float below tnear, tfar].
    ray.tmin = r.tnear > 0.f && r.tnear <= std::numeric_limits<float>::min()
                   ? 0.f
                   : next_float_down(r.tnear);
    ray.tmax = r.tfar;
    return ray;
}

void Accel::intersect_batch(BatchRayHit* rays, std::size_t n, BatchCoherence) const {
    for (std::size_t i = 0; i < n; ++i) {
        if (!(rays[i].ray.tnear <= rays[i].ray.tfar)) continue;
        std::optional<Hit> h = intersect(batch_ray(rays[i].ray));
        if (!h) continue;
        rays[i].ray.tfar = h->t;
        rays[i].hit.u = h->u;
        rays[i].hit.v = h->v;
        rays[i].hit.geom_id = h->geom_id;
        rays[i].hit.prim_id = h->prim_id;
    }
}

void Accel::occluded_batch(BatchRay* rays, std::size_t n) const {
    for (std::size_t i = 0; i < n; ++i)
        if (rays[i].tnear <= rays[i].tfar && occluded(batch_ray(rays[i])))
            rays[i].tfar = -std::numeric_limits<float>::infinity();
}

namespace {
/// Directions of the enclosure test: a Fibonacci spiral of 64 points leaves no gap wider than
/// about 25 degrees, so an opening the size of a Cornell box's missing front wall seen from
/// inside (90 degrees) is always found, while the test costs microseconds.
constexpr int kEnclosureRays = 64;
} // namespace

bool enclosed_point(const Accel& accel, const Vec3& p) {
    const float golden = kPi * (3.f - std::sqrt(5.f));
    for (int i = 0; i < kEnclosureRays; ++i) {
        const float z = 1.f - (2.f * float(i) + 1.f) / float(kEnclosureRays);
        const float r = std::sqrt(std::max(0.f, 1.f - z * z));
        const float phi = golden * float(i);
        Ray ray;
        ray.o = p;
        ray.d = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        if (!accel.occluded(ray)) return false;
    }
    return true;
}

std::unique_ptr<Accel> make_accel(const Scene& scene, const AccelOptions& opt) {
    switch (opt.kind) {
    case AccelKind::Embree:
        return std::make_unique<EmbreeAccel>(
            scene, opt, opt.embree_isa.empty() ? embree_default_isa() : opt.embree_isa);
    case AccelKind::Builtin:
        return std::make_unique<BvhAccel>(scene, opt.triangle, opt.build_threads);
    case AccelKind::Brute:
        return std::make_unique<BruteAccel>(scene, opt.triangle);
    }
    throw Error(ErrorKind::Internal, "make_accel: unknown accelerator kind");
}

AccelKind parse_accel_kind(const std::string& s) {
    return parse_enum(kAccelKinds, "--accel", s);
}

} // namespace candela
