#include "candela/accel/accel.h"

#include "candela/accel/brute.h"
#include "candela/accel/bvh.h"
#include "candela/accel/embree_accel.h"
#include "candela/util/error.h"

namespace candela {

std::unique_ptr<Accel> make_accel(const Scene& scene, const AccelOptions& opt) {
    switch (opt.kind) {
    case AccelKind::Embree:
        return std::make_unique<EmbreeAccel>(scene, opt);
    case AccelKind::Builtin:
        return std::make_unique<BvhAccel>(scene, opt.triangle, opt.build_threads);
    case AccelKind::Brute:
        return std::make_unique<BruteAccel>(scene, opt.triangle);
    }
    throw Error(ErrorKind::Internal, "make_accel: unknown accelerator kind");
}

AccelKind parse_accel_kind(const std::string& s) {
    if (s == "embree") return AccelKind::Embree;
    if (s == "builtin") return AccelKind::Builtin;
    if (s == "brute") return AccelKind::Brute;
    throw Error(ErrorKind::Usage,
                "unknown accelerator '" + s + "' (expected embree, builtin or brute)");
}

const char* accel_kind_name(AccelKind k) {
    switch (k) {
    case AccelKind::Embree:
        return "embree";
    case AccelKind::Builtin:
        return "builtin";
    case AccelKind::Brute:
        return "brute";
    }
    return "?";
}

} // namespace candela
