// The optimised Sampler (per-pixel hash cache, bit-trick Sobol dimension 2, cancelled bit
// reversals) against a direct transcription of its definition in sampler.h: every value must be
// bit-identical.
#include "candela/sampling/rng.h"
#include "candela/sampling/sampler.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <vector>

using namespace candela;

namespace {

// The salts of sampler.h, part of its definition (any change alters every image).
constexpr std::uint64_t kRefIndependentSalt = 0x494e444550ULL;
constexpr std::uint64_t kRefShuffleSalt = 0x53485546464cULL;

std::uint32_t ref_reverse(std::uint32_t x) {
    std::uint32_t r = 0;
    for (int b = 0; b < 32; ++b)
        if (x & (1u << b)) r |= 1u << (31 - b);
    return r;
}

/// Sobol dimension 2 by its generator matrix, column by column over all 32 bits.
std::uint32_t ref_sobol_dim1(std::uint32_t index) {
    std::uint32_t r = 0, v = 1u << 31;
    for (int b = 0; b < 32; ++b) {
        if (index & (1u << b)) r ^= v;
        v ^= v >> 1;
    }
    return r;
}

std::uint32_t ref_laine_karras(std::uint32_t x, std::uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

std::uint32_t ref_owen(std::uint32_t x, std::uint32_t seed) {
    return ref_reverse(ref_laine_karras(ref_reverse(x), seed));
}

float ref_unit(std::uint32_t x) {
    return float(x >> 8) * 0x1p-24f;
}

std::uint64_t ref_pixel_hash(std::uint64_t seed, std::uint32_t px, std::uint32_t py) {
    return hash_combine(hash_combine(seed, px), py);
}

/// Shuffled sample index of dimension `dim` and that dimension's scramble seed.
void ref_index_and_scramble(std::uint64_t ph, std::uint64_t index, std::uint32_t dim,
                            std::uint32_t& idx, std::uint32_t& scramble) {
    std::uint64_t h = hash_combine(ph, dim);
    idx = ref_owen(std::uint32_t(index), std::uint32_t(hash_combine(h, kRefShuffleSalt)));
    scramble = std::uint32_t(h);
}

float ref_sobol_1d(std::uint64_t ph, std::uint64_t index, std::uint32_t dim) {
    std::uint32_t idx, s;
    ref_index_and_scramble(ph, index, dim, idx, s);
    return ref_unit(ref_owen(ref_reverse(idx), s));
}

Vec2 ref_sobol_2d(std::uint64_t ph, std::uint64_t index, std::uint32_t dim) {
    std::uint32_t idx, s0, unused, s1;
    ref_index_and_scramble(ph, index, dim, idx, s0);
    ref_index_and_scramble(ph, index, dim + 1, unused, s1);
    return {ref_unit(ref_owen(ref_reverse(idx), s0)), ref_unit(ref_owen(ref_sobol_dim1(idx), s1))};
}

std::uint32_t bits_of(float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

/// One start() of the scripted visits.
struct Visit {
    std::uint32_t px, py;
    std::uint64_t index;
};

/// Visits that exercise the per-pixel cache: runs of one pixel, returns to an earlier pixel,
/// neighbouring pixels with swapped coordinates, indices beyond 2^32 (used modulo 2^32).
std::vector<Visit> scripted_visits() {
    std::vector<Visit> v;
    for (std::uint64_t i = 0; i < 6; ++i)
        v.push_back({3, 7, i});
    v.push_back({7, 3, 0});
    v.push_back({3, 7, 6});
    v.push_back({0, 0, 0});
    v.push_back({0, 0, (std::uint64_t(1) << 32) + 5});
    v.push_back({0, 0, 5});
    v.push_back({4000000000u, 17, 123456789});
    v.push_back({4000000000u, 17, 0xffffffffull});
    v.push_back({1, 0, 1000});
    v.push_back({0, 1, 1000});
    return v;
}

} // namespace

TEST_CASE("sobol dimension 2 matches its generator matrix", "[sampler][sampling][quick]") {
    Pcg32 rng(5, 6);
    int checked = 0;
    for (int b = 0; b < 32; ++b) { // every single column of the matrix
        REQUIRE(sobol::sobol_dim1(1u << b) == ref_sobol_dim1(1u << b));
        ++checked;
    }
    for (int i = 0; i < 20000; ++i) {
        std::uint32_t x = i < 4096 ? std::uint32_t(i) : rng.next_u32();
        REQUIRE(sobol::sobol_dim1(x) == ref_sobol_dim1(x));
        REQUIRE(sobol::reverse_bits(x) == ref_reverse(x));
        ++checked;
    }
    CHECK(checked == 20032);
}

TEST_CASE("optimised Sobol sampler is bit-identical to the reference definition",
          "[sampler][sampling][quick]") {
    // Request patterns: 2-D only, 1-D only, and a path-tracer-like mix; 40 requests reach
    // dimension 80, past the sampler's per-pixel seed cache.
    const std::vector<std::vector<int>> patterns = {
        {2, 2, 2, 2}, {1, 1, 1, 1, 1}, {2, 1, 2, 2, 1, 1, 2, 1}, std::vector<int>(40, 2)};
    int compared = 0;
    for (std::uint64_t seed :
         {std::uint64_t(0), std::uint64_t(42), std::uint64_t(0xdeadbeefcafef00dULL)}) {
        Sampler s(SamplerKind::Sobol, seed);
        for (const std::vector<int>& pattern : patterns)
            for (const Visit& v : scripted_visits()) {
                s.start(v.px, v.py, v.index);
                const std::uint64_t ph = ref_pixel_hash(seed, v.px, v.py);
                std::uint32_t dim = 0;
                for (int req : pattern) {
                    INFO("seed " << seed << " pixel " << v.px << "," << v.py << " index " << v.index
                                 << " dim " << dim);
                    if (req == 1) {
                        REQUIRE(bits_of(s.get_1d()) == bits_of(ref_sobol_1d(ph, v.index, dim)));
                        ++compared;
                    } else {
                        Vec2 got = s.get_2d(), want = ref_sobol_2d(ph, v.index, dim);
                        REQUIRE(bits_of(got.x) == bits_of(want.x));
                        REQUIRE(bits_of(got.y) == bits_of(want.y));
                        compared += 2;
                    }
                    dim += std::uint32_t(req);
                    REQUIRE(s.dimension() == dim);
                }
            }
    }
    // 3 seeds x 15 visits x (8 + 5 + 12 + 80) values.
    CHECK(compared == 3 * 15 * 105);
}

TEST_CASE("optimised independent sampler is bit-identical to the reference definition",
          "[sampler][sampling][quick]") {
    // Definition: dimension d of sample i of a pixel is hashed from (pixel hash, i, salt, d);
    // a 1-D value is the top 24 bits of the hash's upper half, a 2-D point takes both halves.
    auto bits = [](std::uint64_t seed, const Visit& v, std::uint32_t dim) {
        return hash_combine(
            hash_combine(ref_pixel_hash(seed, v.px, v.py), v.index, kRefIndependentSalt), dim);
    };
    int compared = 0;
    for (std::uint64_t seed : {std::uint64_t(1), std::uint64_t(99)}) {
        Sampler s(SamplerKind::Independent, seed);
        for (const Visit& v : scripted_visits()) {
            s.start(v.px, v.py, v.index);
            std::uint32_t dim = 0;
            for (int k = 0; k < 6; ++k) {
                float a = s.get_1d();
                REQUIRE(bits_of(a) == bits_of(ref_unit(std::uint32_t(bits(seed, v, dim) >> 32))));
                Vec2 p = s.get_2d();
                const std::uint64_t h = bits(seed, v, dim + 1);
                REQUIRE(bits_of(p.x) == bits_of(ref_unit(std::uint32_t(h >> 32))));
                REQUIRE(bits_of(p.y) == bits_of(ref_unit(std::uint32_t(h))));
                dim += 3;
                compared += 3;
            }
            // A jump to a dimension gives what a visit through every earlier one gives.
            s.start(v.px, v.py, v.index);
            s.set_dimension(7);
            REQUIRE(bits_of(s.get_1d()) ==
                    bits_of(ref_unit(std::uint32_t(bits(seed, v, 7) >> 32))));
        }
    }
    CHECK(compared == 2 * 15 * 18);
}

TEST_CASE("Sobol sampler values are pinned", "[sampler][sampling][quick]") {
    // Values of the sampler as first written (before the optimisation), as 24-bit integers
    // (value x 2^24): any change of the sequence, scramble or hashing breaks them.
    Sampler s(SamplerKind::Sobol, 7);
    s.start(5, 9, 3);
    Vec2 p = s.get_2d();
    float u = s.get_1d();
    Vec2 q = s.get_2d();
    s.start(5, 9, 1000);
    Vec2 r = s.get_2d();
    const std::uint32_t got[7] = {std::uint32_t(p.x * 0x1p24f), std::uint32_t(p.y * 0x1p24f),
                                  std::uint32_t(u * 0x1p24f),   std::uint32_t(q.x * 0x1p24f),
                                  std::uint32_t(q.y * 0x1p24f), std::uint32_t(r.x * 0x1p24f),
                                  std::uint32_t(r.y * 0x1p24f)};
    const std::uint32_t want[7] = {13520636u, 8761192u, 13305999u, 6138919u,
                                   10524303u, 5173182u, 14337526u};
    for (int i = 0; i < 7; ++i) {
        INFO("value " << i);
        CHECK(got[i] == want[i]);
    }
}
