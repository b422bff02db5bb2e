#pragma once
// The state a wavefront path carries from one vertex to the next, as a structure of arrays (one
// entry per live path). Its fields are listed once, in CANDELA_PATH_FIELDS: the arrays, growing
// them, a path's start and the move that compacts the live paths are all generated from that
// list, so a new field cannot be declared and then forgotten by one of them.
#include "candela/accel/accel.h"
#include "candela/math/vec.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela {

/// The per-path fields, X(type, name, value at the path's start), where a start value may read
/// `index` (the path's camera sample in the batch) and `camera` (its camera ray):
/// - request: index into the batch's requests;
/// - beta: the path throughput; L: the radiance it has gathered;
/// - eta_scale: radiance scaling by refraction (undone for roulette);
/// - prev_bsdf_pdf: density of the BSDF sample that made the current ray; prev_p: the vertex it
///   left from; prev_n: the orientation the light choice took there (receiving_normal(), for MIS);
///   prev_split_total: the infinite lights' total weight there where the vertex weighed its
///   directional lights by its BSDF (Integrator::vertex_shares), else -1 (recomputed from prev_n);
/// - survival: the Russian roulette survival probability the previous vertex left for the next
///   hit to test, after its emission (1: no test pending);
/// - specular: the current ray left a delta lobe (or the camera: emission counts fully);
/// - rays: the current ray of the path (written with set_batch_ray), then its hit.
#define CANDELA_PATH_FIELDS(X)                                                                     \
    X(std::uint32_t, request, std::uint32_t(index))                                                \
    X(Rgb, beta, Rgb(1.f))                                                                         \
    X(Rgb, L, Rgb(0.f))                                                                            \
    X(float, eta_scale, 1.f)                                                                       \
    X(float, prev_bsdf_pdf, 0.f)                                                                   \
    X(Vec3, prev_p, Vec3(0.f))                                                                     \
    X(Vec3, prev_n, Vec3(0.f))                                                                     \
    X(double, prev_split_total, -1.0)                                                              \
    X(float, survival, 1.f)                                                                        \
    X(std::uint8_t, specular, std::uint8_t(1))                                                     \
    X(BatchRayHit, rays, camera)

namespace path_state_detail {
/// Gives a field its start value. A ray is written in place: building a whole record and
/// copying it stalls on forwarding its partial stores (start_paths measured 2.8x slower).
template <class T, class V> inline void set(T& field, const V& value) {
    field = value;
}
inline void set(BatchRayHit& field, const Ray& ray) {
    set_batch_ray(field, ray);
}
} // namespace path_state_detail

/// The live paths of a batch, one array per field of CANDELA_PATH_FIELDS.
class PathArrays {
  public:
#define CANDELA_PATH_ARRAY(type, name, start) std::vector<type> name;
    CANDELA_PATH_FIELDS(CANDELA_PATH_ARRAY)
#undef CANDELA_PATH_ARRAY

    /// Grows every array to hold at least n paths (it never shrinks, so a thread's workspace
    /// stops allocating once it has seen its largest batch).
    void reserve(std::size_t n) {
#define CANDELA_PATH_GROW(type, name, start)                                                       \
    if (name.size() < n) name.resize(n);
        CANDELA_PATH_FIELDS(CANDELA_PATH_GROW)
#undef CANDELA_PATH_GROW
    }

    /// Starts path `index` of the batch on its camera ray: every field takes its start value.
    void start(std::size_t index, const Ray& camera) {
#define CANDELA_PATH_START(type, name, start) path_state_detail::set(name[index], start);
        CANDELA_PATH_FIELDS(CANDELA_PATH_START)
#undef CANDELA_PATH_START
    }

    /// Moves path `from` to entry `to` (to < from), every field of it.
    void move(std::size_t to, std::size_t from) {
#define CANDELA_PATH_MOVE(type, name, start) name[to] = name[from];
        CANDELA_PATH_FIELDS(CANDELA_PATH_MOVE)
#undef CANDELA_PATH_MOVE
    }
};

} // namespace candela
