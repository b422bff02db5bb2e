// Sampler values for a whole batch of camera samples, dimension by dimension (sample_batch.h).
#include "candela/sampling/sample_batch.h"

#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"
#include "candela/util/batch_kernel.h"

#include <algorithm>

namespace candela {

namespace {

/// Grows v to hold at least n elements (never shrinks, so a batch loop stops allocating).
template <typename T> void grow(std::vector<T>& v, std::size_t n) {
    if (v.size() < n) v.resize(n);
}

// The padded Sobol values of one request for n paths, the arithmetic of Sampler::get_1d and
// Sampler::get_2d (sampler.h) written as loops over the batch. The loop bodies are integer
// multiplications, shifts and byte swaps, which GCC vectorises; target_clones builds an AVX2
// version (eight paths per instruction, with vpmulld and vpshufb) beside the x86-64 baseline
// and picks one when the program loads.

/// The first coordinate of each path's point (Sampler::get_1d). Path i has sample index
/// index[i] and the seeds of run run[i] (one pixel's samples).
CANDELA_BATCH_KERNEL void sobol_1d_values(std::size_t n, const std::uint32_t* __restrict index,
                                          const std::uint32_t* __restrict run,
                                          const std::uint32_t* __restrict shuffle,
                                          const std::uint32_t* __restrict scramble,
                                          float* __restrict out) {
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = run[i];
        const std::uint32_t idx =
            sobol::shuffle_reversed_index(sobol::reverse_bits(index[i]), shuffle[r]);
        out[i] = bits_to_unit_float(sobol::scrambled_first(idx, scramble[r]));
    }
}

/// The raw 32 bits of each path's first coordinate (Sampler::get_1d_bits).
CANDELA_BATCH_KERNEL void sobol_1d_bits(std::size_t n, const std::uint32_t* __restrict index,
                                        const std::uint32_t* __restrict run,
                                        const std::uint32_t* __restrict shuffle,
                                        const std::uint32_t* __restrict scramble,
                                        std::uint32_t* __restrict out) {
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = run[i];
        const std::uint32_t idx =
            sobol::shuffle_reversed_index(sobol::reverse_bits(index[i]), shuffle[r]);
        out[i] = sobol::scrambled_first(idx, scramble[r]);
    }
}

/// The raw 32 bits of both coordinates of each path's point (Sampler::get_2d_bits).
CANDELA_BATCH_KERNEL void sobol_2d_bits(std::size_t n, const std::uint32_t* __restrict index,
                                        const std::uint32_t* __restrict run,
                                        const std::uint32_t* __restrict shuffle,
                                        const std::uint32_t* __restrict scramble_x,
                                        const std::uint32_t* __restrict scramble_y,
                                        std::uint32_t* __restrict out_x,
                                        std::uint32_t* __restrict out_y) {
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = run[i];
        const std::uint32_t idx =
            sobol::shuffle_reversed_index(sobol::reverse_bits(index[i]), shuffle[r]);
        out_x[i] = sobol::scrambled_first(idx, scramble_x[r]);
        out_y[i] = sobol::scrambled_second(idx, scramble_y[r]);
    }
}

/// Both coordinates of each path's point (Sampler::get_2d).
CANDELA_BATCH_KERNEL void sobol_2d_values(std::size_t n, const std::uint32_t* __restrict index,
                                          const std::uint32_t* __restrict run,
                                          const std::uint32_t* __restrict shuffle,
                                          const std::uint32_t* __restrict scramble_x,
                                          const std::uint32_t* __restrict scramble_y,
                                          float* __restrict out_x, float* __restrict out_y) {
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = run[i];
        const std::uint32_t idx =
            sobol::shuffle_reversed_index(sobol::reverse_bits(index[i]), shuffle[r]);
        out_x[i] = bits_to_unit_float(sobol::scrambled_first(idx, scramble_x[r]));
        out_y[i] = bits_to_unit_float(sobol::scrambled_second(idx, scramble_y[r]));
    }
}

/// square_to_cosine_hemisphere of each point (u_x[i], u_y[i]), into three coordinate arrays.
/// Branch-free after if-conversion, so it vectorises like the loops above.
CANDELA_BATCH_KERNEL void cosine_directions(std::size_t n, const float* __restrict u_x,
                                            const float* __restrict u_y, float* __restrict x,
                                            float* __restrict y, float* __restrict z) {
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 d = square_to_cosine_hemisphere(Vec2(u_x[i], u_y[i]));
        x[i] = d.x;
        y[i] = d.y;
        z[i] = d.z;
    }
}

} // namespace

void SampleBatch::fill(Sampler& sampler, const SamplePoint* points, const std::uint32_t* which,
                       const std::uint8_t* skip, std::size_t n,
                       const std::vector<PlannedDraw>& plan) {
    // Slots: one per 1-D request, two per 2-D request, found by dimension.
    first_dim_ = plan.empty() ? 0u : plan.front().dim;
    std::uint32_t last_dim = first_dim_;
    for (const PlannedDraw& d : plan) {
        first_dim_ = std::min(first_dim_, d.dim);
        last_dim = std::max(last_dim, d.dim);
    }
    const std::size_t span = plan.empty() ? 0 : std::size_t(last_dim - first_dim_) + 1;
    slot_1d_.assign(span, -1);
    slot_2d_.assign(span, -1);
    slot_cosine_.assign(span, -1);
    slot_bits_.assign(span, -1);
    slot_bits_2d_.assign(span, -1);
    int slots = 0, bit_slots = 0;
    for (const PlannedDraw& d : plan) {
        if (d.bits) {
            int& slot = (d.two_d ? slot_bits_2d_ : slot_bits_)[d.dim - first_dim_];
            if (slot >= 0) continue;
            slot = bit_slots;
            bit_slots += d.two_d ? 2 : 1;
            continue;
        }
        int& slot = (d.two_d ? slot_2d_ : slot_1d_)[d.dim - first_dim_];
        if (slot >= 0) continue; // planned twice: one set of values serves both
        slot = slots;
        slots += d.two_d ? 2 : 1;
        if (d.two_d && d.cosine) {
            slot_cosine_[d.dim - first_dim_] = slots;
            slots += 3;
        }
    }
    capacity_ = batch_stride(n);
    const std::size_t cap = capacity_;
    grow(values_, std::size_t(slots) * cap);
    grow(bits_, std::size_t(bit_slots) * cap);
    auto point = [&](std::size_t i) -> const SamplePoint& { return points[which ? which[i] : i]; };

    if (sampler.kind() == SamplerKind::Independent) {
        // A hash per request: no batch arithmetic to share, so the Sampler computes them.
        for (std::size_t i = 0; i < n; ++i) {
            if (skip && skip[i]) continue;
            const SamplePoint& p = point(i);
            sampler.start(p.px, p.py, p.index);
            for (const PlannedDraw& d : plan) {
                sampler.set_dimension(d.dim);
                if (d.bits && d.two_d) {
                    const int s = slot_bits_2d_[d.dim - first_dim_];
                    const Bits2 u = sampler.get_2d_bits();
                    bits_[std::size_t(s) * cap + i] = u.x;
                    bits_[std::size_t(s + 1) * cap + i] = u.y;
                } else if (d.bits) {
                    bits_[std::size_t(slot_bits_[d.dim - first_dim_]) * cap + i] =
                        sampler.get_1d_bits();
                } else if (d.two_d) {
                    const int s = slot_2d_[d.dim - first_dim_];
                    const Vec2 u = sampler.get_2d();
                    values_[std::size_t(s) * cap + i] = u.x;
                    values_[std::size_t(s + 1) * cap + i] = u.y;
                } else {
                    values_[std::size_t(slot_1d_[d.dim - first_dim_]) * cap + i] = sampler.get_1d();
                }
            }
        }
        fill_cosine_directions(n, plan);
        return;
    }

    // The seeds depend only on the pixel: they are looked up once per run of one pixel's
    // samples (a batch holds each pixel's samples next to each other) into per-run tables, one
    // per request, which the vectorised loops read through each path's run number.
    const std::size_t m = plan.size();
    grow(index_, n);
    grow(run_, n);
    grow(shuffle_, m * n);
    grow(scramble_x_, m * n);
    grow(scramble_y_, m * n);
    std::size_t runs = 0;
    std::uint32_t px = 0, py = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (skip && skip[i]) {
            // Values computed from the first run's seeds, never read.
            index_[i] = 0;
            run_[i] = 0;
            continue;
        }
        const SamplePoint& p = point(i);
        if (runs == 0 || p.px != px || p.py != py) {
            sampler.select_pixel(p.px, p.py);
            for (std::size_t k = 0; k < m; ++k) {
                const Sampler::DimensionSeeds d = sampler.dimension_seeds(plan[k].dim);
                shuffle_[k * n + runs] = d.shuffle;
                scramble_x_[k * n + runs] = d.scramble;
                scramble_y_[k * n + runs] =
                    plan[k].two_d ? sampler.dimension_seeds(plan[k].dim + 1u).scramble : 0u;
            }
            px = p.px;
            py = p.py;
            ++runs;
        }
        index_[i] = static_cast<std::uint32_t>(p.index); // Sobol uses indices modulo 2^32
        run_[i] = std::uint32_t(runs - 1);
    }
    for (std::size_t k = 0; k < m; ++k) {
        const PlannedDraw& d = plan[k];
        if (d.bits && d.two_d) {
            std::uint32_t* out =
                bits_.data() + std::size_t(slot_bits_2d_[d.dim - first_dim_]) * cap;
            sobol_2d_bits(n, index_.data(), run_.data(), shuffle_.data() + k * n,
                          scramble_x_.data() + k * n, scramble_y_.data() + k * n, out, out + cap);
            continue;
        }
        if (d.bits) {
            sobol_1d_bits(n, index_.data(), run_.data(), shuffle_.data() + k * n,
                          scramble_x_.data() + k * n,
                          bits_.data() + std::size_t(slot_bits_[d.dim - first_dim_]) * cap);
            continue;
        }
        const int s = (d.two_d ? slot_2d_ : slot_1d_)[d.dim - first_dim_];
        float* out = values_.data() + std::size_t(s) * cap;
        if (d.two_d)
            sobol_2d_values(n, index_.data(), run_.data(), shuffle_.data() + k * n,
                            scramble_x_.data() + k * n, scramble_y_.data() + k * n, out, out + cap);
        else
            sobol_1d_values(n, index_.data(), run_.data(), shuffle_.data() + k * n,
                            scramble_x_.data() + k * n, out);
    }
    fill_cosine_directions(n, plan);
}

void SampleBatch::fill_cosine_directions(std::size_t n, const std::vector<PlannedDraw>& plan) {
    for (const PlannedDraw& d : plan) {
        if (!d.two_d || !d.cosine || d.bits) continue;
        const float* u = values_.data() + std::size_t(slot_2d_[d.dim - first_dim_]) * capacity_;
        float* out = values_.data() + std::size_t(slot_cosine_[d.dim - first_dim_]) * capacity_;
        cosine_directions(n, u, u + capacity_, out, out + capacity_, out + 2 * capacity_);
    }
}

} // namespace candela
