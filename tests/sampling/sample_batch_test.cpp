#include "candela/sampling/rng.h"
#include "candela/sampling/sample_batch.h"
#include "candela/sampling/sampler.h"
#include "candela/sampling/warp.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <vector>

using namespace candela;

namespace {

/// The bits of a float, so that values compare exactly (a batch value must be the Sampler's
/// value, not a close one).
std::uint32_t bits(float f) {
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

/// Camera samples in runs of one pixel, as a batch holds them: `runs` pixels with 1 to 9
/// consecutive sample indices each, starting anywhere (sample offsets, large indices too).
std::vector<SamplePoint> make_points(Pcg32& rng, int runs) {
    std::vector<SamplePoint> points;
    for (int r = 0; r < runs; ++r) {
        const std::uint32_t px = rng.next_u32() % 50, py = rng.next_u32() % 40;
        const std::uint64_t first =
            r % 3 == 0 ? (std::uint64_t(rng.next_u32()) << 8) : rng.next_u32() % 100;
        const int count = 1 + int(rng.next_u32() % 9);
        for (int k = 0; k < count; ++k)
            points.push_back({px, py, first + std::uint64_t(k)});
    }
    return points;
}

} // namespace

TEST_CASE("batch sampler values equal the Sampler's bit for bit", "[sampling][quick]") {
    // Plans with 1-D and 2-D requests, adjacent and distant dimensions, dimensions past the
    // Sampler's per-pixel seed cache (64), and a dimension asked as 1-D and as 2-D.
    const std::vector<std::vector<PlannedDraw>> plans = {
        {{0, true}},
        {{0, true}, {2, true}},
        {{4, false}, {5, true}, {7, true}, {9, false}, {10, false}},
        {{60, true}, {62, true}, {64, false}, {65, true}, {130, false}},
        {{11, true}, {11, false}},
    };
    Pcg32 rng(77, 5);
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (const std::vector<PlannedDraw>& plan : plans) {
            const std::vector<SamplePoint> points = make_points(rng, 40);
            // Paths reach the batch through an index list (compacted wavefront), some skipped.
            std::vector<std::uint32_t> which(points.size());
            std::vector<std::uint8_t> skip(points.size());
            for (std::size_t i = 0; i < points.size(); ++i) {
                which[i] = std::uint32_t(i);
                skip[i] = rng.next_u32() % 4 == 0 ? 1 : 0;
            }
            Sampler batch_sampler(kind, 99), reference(kind, 99);
            SampleBatch batch;
            batch.fill(batch_sampler, points.data(), which.data(), skip.data(), points.size(),
                       plan);
            std::size_t checked = 0;
            for (std::size_t i = 0; i < points.size(); ++i) {
                if (skip[i]) continue;
                const SamplePoint& p = points[i];
                for (const PlannedDraw& d : plan) {
                    reference.start(p.px, p.py, p.index);
                    reference.set_dimension(d.dim);
                    if (d.two_d) {
                        const int slot = batch.slot_2d(d.dim);
                        REQUIRE(slot >= 0);
                        const Vec2 u = reference.get_2d();
                        REQUIRE(bits(batch.value(slot, i)) == bits(u.x));
                        REQUIRE(bits(batch.value(slot + 1, i)) == bits(u.y));
                    } else {
                        const int slot = batch.slot_1d(d.dim);
                        REQUIRE(slot >= 0);
                        REQUIRE(bits(batch.value(slot, i)) == bits(reference.get_1d()));
                    }
                    ++checked;
                }
            }
            REQUIRE(checked > 0);
        }
}

TEST_CASE("a path sampler serves planned requests from the batch and computes the others",
          "[sampling][quick]") {
    Pcg32 rng(3, 8);
    const std::vector<SamplePoint> points = make_points(rng, 12);
    const std::vector<PlannedDraw> plan = {{4, false}, {5, true}, {7, true}};
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent}) {
        Sampler filler(kind, 5), fallback(kind, 5), reference(kind, 5);
        SampleBatch batch;
        batch.fill(filler, points.data(), nullptr, nullptr, points.size(), plan);
        CHECK(batch.slot_1d(5) < 0); // planned as 2-D only
        CHECK(batch.slot_2d(4) < 0);
        CHECK(batch.slot_1d(3) < 0);
        for (std::size_t i = 0; i < points.size(); ++i) {
            const SamplePoint& p = points[i];
            PathSampler path(batch, i, p, fallback);
            reference.start(p.px, p.py, p.index);
            // The same request sequence from both: planned (4, 5-6, 7-8), then unplanned ones
            // (9, a 2-D point at 4, a 1-D value at 5), in an order that moves the fallback.
            path.set_dimension(4);
            reference.set_dimension(4);
            REQUIRE(bits(path.get_1d()) == bits(reference.get_1d()));
            Vec2 a = path.get_2d(), b = reference.get_2d();
            REQUIRE(bits(a.x) == bits(b.x));
            REQUIRE(bits(a.y) == bits(b.y));
            a = path.get_2d();
            b = reference.get_2d();
            REQUIRE(bits(a.y) == bits(b.y));
            REQUIRE(path.dimension() == 9u);
            REQUIRE(bits(path.get_1d()) == bits(reference.get_1d()));
            path.set_dimension(4);
            reference.set_dimension(4);
            a = path.get_2d();
            b = reference.get_2d();
            REQUIRE(bits(a.x) == bits(b.x));
            REQUIRE(bits(a.y) == bits(b.y));
            REQUIRE(bits(path.get_1d()) == bits(reference.get_1d()));
        }
    }
}

TEST_CASE("planned cosine directions are the warp of the batch's 2-D points", "[sampling][quick]") {
    Pcg32 rng(12, 34);
    const std::vector<SamplePoint> points = make_points(rng, 30);
    const std::vector<PlannedDraw> plan = {{3, true, true}, {5, true, false}, {7, false}};
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent}) {
        Sampler filler(kind, 21), fallback(kind, 21);
        SampleBatch batch;
        batch.fill(filler, points.data(), nullptr, nullptr, points.size(), plan);
        REQUIRE(batch.slot_cosine(3) >= 0);
        CHECK(batch.slot_cosine(5) < 0);
        for (std::size_t i = 0; i < points.size(); ++i) {
            PathSampler path(batch, i, points[i], fallback);
            path.set_dimension(3);
            Vec2 u;
            Vec3 cosine;
            REQUIRE(path.get_2d_cosine(&u, &cosine));
            REQUIRE(path.dimension() == 5u);
            const Vec3 expected = square_to_cosine_hemisphere(u);
            REQUIRE(bits(cosine.x) == bits(expected.x));
            REQUIRE(bits(cosine.y) == bits(expected.y));
            REQUIRE(bits(cosine.z) == bits(expected.z));
            // Not planned with a direction: the point alone, *cosine untouched.
            Vec3 untouched(7.f);
            REQUIRE_FALSE(path.get_2d_cosine(&u, &untouched));
            REQUIRE(untouched == Vec3(7.f));
        }
    }
}

TEST_CASE("planned raw bits equal the sampler's, and their floats its float values",
          "[sampling][quick]") {
    Pcg32 rng(7, 29);
    const std::vector<SamplePoint> points = make_points(rng, 20);
    // A 1-D and a 2-D request in raw bits, a float 2-D point after them.
    const std::vector<PlannedDraw> plan = {
        {4, false, false, true}, {5, true, false, true}, {7, true}};
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent}) {
        Sampler filler(kind, 9), fallback(kind, 9), reference(kind, 9);
        SampleBatch batch;
        batch.fill(filler, points.data(), nullptr, nullptr, points.size(), plan);
        REQUIRE(batch.slot_bits(4) >= 0);
        REQUIRE(batch.slot_bits_2d(5) >= 0);
        CHECK(batch.slot_bits_2d(4) < 0);
        CHECK(batch.slot_2d(5) < 0);
        for (std::size_t i = 0; i < points.size(); ++i) {
            const SamplePoint& p = points[i];
            PathSampler path(batch, i, p, fallback);
            reference.start(p.px, p.py, p.index);
            path.set_dimension(4);
            reference.set_dimension(4);
            REQUIRE(path.get_1d_bits() == reference.get_1d_bits());
            const Bits2 a = path.get_2d_bits(), b = reference.get_2d_bits();
            REQUIRE(a.x == b.x);
            REQUIRE(a.y == b.y);
            const Vec2 fa = path.get_2d(), fb = reference.get_2d();
            REQUIRE(bits(fa.x) == bits(fb.x));
            REQUIRE(path.fallbacks() == 0u); // all planned
            // The float point at 5 is the top 24 bits of the raw one, and maps back exactly.
            reference.set_dimension(5);
            const Vec2 f = reference.get_2d();
            REQUIRE(bits(f.x) == bits(bits_to_unit_float(b.x)));
            REQUIRE(bits(f.y) == bits(bits_to_unit_float(b.y)));
            REQUIRE(unit_point_to_bits(f).x == (b.x & 0xffffff00u));
            REQUIRE(unit_point_to_bits(f).y == (b.y & 0xffffff00u));
            // Unplanned: computed by the fallback, counted.
            path.set_dimension(9);
            reference.set_dimension(9);
            const Bits2 c = path.get_2d_bits(), d = reference.get_2d_bits();
            REQUIRE(c.x == d.x);
            REQUIRE(c.y == d.y);
            REQUIRE(path.fallbacks() == 1u);
        }
    }
}
