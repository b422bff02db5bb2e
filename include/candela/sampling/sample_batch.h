#pragma once
// Sampler values for a whole batch of camera samples at once. A wavefront integrator knows, at
// each path vertex, which sampler requests (dimension, 1-D or 2-D) every path of the batch may
// make: the list is a plan. SampleBatch::fill computes the plan's values for every path before
// the paths are shaded, with the same integer arithmetic as Sampler, so every value is bit for
// bit the one Sampler returns for the same (seed, pixel, sample index, dimension). The Sobol
// scramble then runs as one loop per request over the batch, which the compiler vectorises
// (sample_batch.cpp), instead of once per request inside each path's shading.
// PathSampler is the sampler one path's shading draws from: it serves planned requests from
// the batch and computes any other request with a Sampler, so a plan that misses a request
// costs time, never a different value.
#include "candela/math/vec.h"
#include "candela/sampling/sampler.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela {

/// One camera sample: a pixel of the frame (row 0 at the top) and a sample index.
struct SamplePoint {
    std::uint32_t px = 0, py = 0;
    std::uint64_t index = 0;
};

/// One request of a plan: the 1-D value or the 2-D point that starts at dimension `dim`.
struct PlannedDraw {
    std::uint32_t dim = 0;
    bool two_d = false;
    /// A 2-D point's cosine-weighted hemisphere direction square_to_cosine_hemisphere(u) too
    /// (warp.h): a Lambertian BSDF sample is that direction, and its division, polynomial and
    /// square root, a chain of long latencies per path, run vectorised over the batch instead.
    bool cosine = false;
    /// A request served as raw 32 bits (get_1d_bits, or get_2d_bits for a 2-D point) instead
    /// of floats.
    bool bits = false;
};

class SampleBatch {
  public:
    /// Computes the values of `plan` (at most one entry per dimension and kind) for n paths:
    /// path i is camera sample points[which[i]] (points[i] when `which` is null). Paths with
    /// skip[i] != 0 (when `skip` is given) get no values; they must not draw.
    void fill(Sampler& sampler, const SamplePoint* points, const std::uint32_t* which,
              const std::uint8_t* skip, std::size_t n, const std::vector<PlannedDraw>& plan);

    /// The slot of a planned request, or -1 when the plan does not hold it.
    int slot_1d(std::uint32_t dim) const { return lookup(slot_1d_, dim); }
    int slot_2d(std::uint32_t dim) const { return lookup(slot_2d_, dim); }
    /// The slot of a planned raw 32-bit request, or -1 (a 2-D point's second coordinate is in
    /// slot + 1).
    int slot_bits(std::uint32_t dim) const { return lookup(slot_bits_, dim); }
    int slot_bits_2d(std::uint32_t dim) const { return lookup(slot_bits_2d_, dim); }
    /// The first of the three slots (x, y, z) of the cosine direction of the 2-D point at
    /// `dim`, or -1 when the plan does not ask for it.
    int slot_cosine(std::uint32_t dim) const { return lookup(slot_cosine_, dim); }
    /// The value in `slot` of path i (a 2-D point's second coordinate is in slot + 1).
    float value(int slot, std::size_t i) const {
        return values_[std::size_t(slot) * capacity_ + i];
    }
    /// The raw 32-bit value in `slot` of path i.
    std::uint32_t bits(int slot, std::size_t i) const {
        return bits_[std::size_t(slot) * capacity_ + i];
    }

  private:
    /// The cosine directions of the plan's 2-D points that ask for them (after their values).
    void fill_cosine_directions(std::size_t n, const std::vector<PlannedDraw>& plan);

    int lookup(const std::vector<int>& table, std::uint32_t dim) const {
        const std::uint32_t k = dim - first_dim_;
        return dim >= first_dim_ && k < table.size() ? table[k] : -1;
    }

    std::size_t capacity_ = 0; ///< paths per slot in values_
    std::uint32_t first_dim_ = 0;
    /// By dim - first_dim_; -1: not planned.
    std::vector<int> slot_1d_, slot_2d_, slot_cosine_, slot_bits_, slot_bits_2d_;
    std::vector<float> values_;       ///< slot-major: values_[slot * capacity_ + path]
    std::vector<std::uint32_t> bits_; ///< raw 32-bit requests, slot-major like values_
    // Inputs of the vectorised steps (sample_batch.cpp): each path's sample index and run (a
    // run is consecutive paths of one pixel), and each request's seeds by run (request-major).
    std::vector<std::uint32_t> index_, run_;
    std::vector<std::uint32_t> shuffle_, scramble_x_, scramble_y_;
};

/// The Sampler interface (get_1d, get_2d, get_1d_bits, get_2d_bits, set_dimension, dimension)
/// for one path of a filled batch. Requests outside the plan are computed by `fallback`,
/// positioned on the path's sample, and counted (fallbacks()): a complete plan leaves the count
/// at zero.
class PathSampler {
  public:
    PathSampler(const SampleBatch& batch, std::size_t path, const SamplePoint& point,
                Sampler& fallback)
        : batch_(batch), path_(path), point_(point), fallback_(fallback) {}

    [[gnu::always_inline]] float get_1d() {
        const std::uint32_t dim = dimension_++;
        const int slot = batch_.slot_1d(dim);
        if (slot >= 0) return batch_.value(slot, path_);
        position_fallback(dim);
        return fallback_.get_1d();
    }
    [[gnu::always_inline]] Vec2 get_2d() {
        const std::uint32_t dim = dimension_;
        dimension_ += 2;
        const int slot = batch_.slot_2d(dim);
        if (slot >= 0) return {batch_.value(slot, path_), batch_.value(slot + 1, path_)};
        position_fallback(dim);
        return fallback_.get_2d();
    }
    /// get_2d(), and the point's cosine-weighted hemisphere direction in *cosine when the plan
    /// computed it (returns false, leaving *cosine alone, when it did not).
    [[gnu::always_inline]] bool get_2d_cosine(Vec2* u, Vec3* cosine) {
        const int slot = batch_.slot_cosine(dimension_);
        *u = get_2d();
        if (slot < 0) return false;
        *cosine = Vec3(batch_.value(slot, path_), batch_.value(slot + 1, path_),
                       batch_.value(slot + 2, path_));
        return true;
    }
    [[gnu::always_inline]] std::uint32_t get_1d_bits() {
        const std::uint32_t dim = dimension_++;
        const int slot = batch_.slot_bits(dim);
        if (slot >= 0) return batch_.bits(slot, path_);
        position_fallback(dim);
        return fallback_.get_1d_bits();
    }
    [[gnu::always_inline]] Bits2 get_2d_bits() {
        const std::uint32_t dim = dimension_;
        dimension_ += 2;
        const int slot = batch_.slot_bits_2d(dim);
        if (slot >= 0) return {batch_.bits(slot, path_), batch_.bits(slot + 1, path_)};
        position_fallback(dim);
        return fallback_.get_2d_bits();
    }
    void set_dimension(std::uint32_t dim) { dimension_ = dim; }
    std::uint32_t dimension() const { return dimension_; }
    /// Requests this path served outside the plan.
    std::uint32_t fallbacks() const { return fallbacks_; }

  private:
    void position_fallback(std::uint32_t dim) {
        ++fallbacks_;
        fallback_.start(point_.px, point_.py, point_.index);
        fallback_.set_dimension(dim);
    }

    const SampleBatch& batch_;
    std::size_t path_;
    const SamplePoint& point_; ///< read only by a fallback: not copied for every path
    Sampler& fallback_;
    std::uint32_t dimension_ = 0;
    std::uint32_t fallbacks_ = 0;
};

} // namespace candela
