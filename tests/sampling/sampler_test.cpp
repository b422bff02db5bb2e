#include "candela/sampling/rng.h"
#include "candela/sampling/sampler.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace candela;

TEST_CASE("pcg32 matches the reference sequence and stays in the unit interval",
          "[sampling][quick]") {
    // First outputs of O'Neill's pcg32-demo with seed(42, 54).
    Pcg32 rng(42u, 54u);
    const std::uint32_t expected[6] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u,
                                       0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    for (std::uint32_t e : expected)
        CHECK(rng.next_u32() == e);
    Pcg32 r2(1, 2);
    for (int i = 0; i < 100000; ++i) {
        float u = r2.next_float();
        REQUIRE(u >= 0.f);
        REQUIRE(u < 1.f);
    }
}

TEST_CASE("sampler values lie in the unit interval and are deterministic", "[sampling][quick]") {
    for (SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol}) {
        Sampler a(kind, 1234), b(kind, 1234), c(kind, 4321);
        int differ = 0;
        // Visit pixels in opposite orders: results must only depend on (seed, pixel, index).
        for (int i = 0; i < 200; ++i) {
            auto px = static_cast<std::uint32_t>(i % 17), py = static_cast<std::uint32_t>(i / 17);
            auto qx = static_cast<std::uint32_t>((199 - i) % 17);
            auto qy = static_cast<std::uint32_t>((199 - i) / 17);
            for (std::uint64_t s = 0; s < 16; ++s) {
                a.start(px, py, s);
                b.start(qx, qy, 15 - s); // unrelated state in between
                b.get_2d();
                b.start(px, py, s);
                c.start(px, py, s);
                for (int d = 0; d < 6; ++d) {
                    float x = a.get_1d(), y = b.get_1d(), z = c.get_1d();
                    Vec2 p = a.get_2d(), q = b.get_2d();
                    c.get_2d();
                    REQUIRE(x >= 0.f);
                    REQUIRE(x < 1.f);
                    REQUIRE(p.x >= 0.f);
                    REQUIRE(p.x < 1.f);
                    REQUIRE(p.y >= 0.f);
                    REQUIRE(p.y < 1.f);
                    REQUIRE(x == y);
                    REQUIRE(p.x == q.x);
                    REQUIRE(p.y == q.y);
                    differ += (x != z);
                }
            }
        }
        // Another seed gives another stream (a few coincidences of 24-bit values are possible).
        CHECK(differ > 200 * 16 * 6 - 10);
    }
}

namespace {

/// Counts points per cell of a 2^a x 2^b grid and checks every cell holds exactly one.
bool is_elementary_net(const std::vector<Vec2>& pts, int a, int b) {
    std::vector<int> count(std::size_t(1) << (a + b), 0);
    for (const Vec2& p : pts) {
        auto i = static_cast<std::size_t>(p.x * float(1 << a));
        auto j = static_cast<std::size_t>(p.y * float(1 << b));
        ++count[(j << a) | i];
    }
    for (int c : count)
        if (c != 1) return false;
    return true;
}

} // namespace

TEST_CASE("Sobol 2-D points of a pixel form (0,k,2)-nets", "[sampling][quick]") {
    Sampler s(SamplerKind::Sobol, 99);
    for (int k = 1; k <= 10; ++k) {
        const std::uint64_t n = std::uint64_t(1) << k;
        for (std::uint32_t px : {0u, 5u, 77u}) {
            // Samples [0, n) and the next aligned block [n, 2n); dimension pairs 0, 1 and 2
            // (the third pair is reached after a 1-D request, as a path tracer would).
            for (std::uint64_t base : {std::uint64_t(0), n}) {
                std::vector<std::vector<Vec2>> pts(3);
                std::vector<Vec2> pts1d;
                for (std::uint64_t i = base; i < base + n; ++i) {
                    s.start(px, 3, i);
                    pts[0].push_back(s.get_2d());
                    pts[1].push_back(s.get_2d());
                    float u = s.get_1d();
                    pts1d.emplace_back(u, 0.5f);
                    pts[2].push_back(s.get_2d());
                }
                for (int d = 0; d < 3; ++d)
                    for (int a = 0; a <= k; ++a) {
                        INFO("k = " << k << ", px = " << px << ", base = " << base
                                    << ", pair = " << d << ", grid 2^" << a << " x 2^" << k - a);
                        CHECK(is_elementary_net(pts[d], a, k - a));
                    }
                INFO("1-D strata, k = " << k);
                CHECK(is_elementary_net(pts1d, k, 0));
            }
        }
    }
}

namespace {

/// Pearson correlation coefficient of paired samples.
double correlation(const std::vector<double>& x, const std::vector<double>& y) {
    double n = double(x.size()), mx = 0, my = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        mx += x[i];
        my += y[i];
    }
    mx /= n;
    my /= n;
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        sxy += (x[i] - mx) * (y[i] - my);
        sxx += (x[i] - mx) * (x[i] - mx);
        syy += (y[i] - my) * (y[i] - my);
    }
    return sxy / std::sqrt(sxx * syy);
}

} // namespace

TEST_CASE("sampler streams are uncorrelated across pixels and dimensions", "[sampling][stat]") {
    // Under independence the sample correlation of N pairs has standard deviation ~1/sqrt(N);
    // 5 sigma keeps the false-alarm rate below 1e-6 per check.
    constexpr double kSigmas = 5.0;
    for (SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol}) {
        Sampler s(kind, 7);
        std::vector<double> a, right, below, dim2;
        for (std::uint32_t py = 0; py < 64; ++py)
            for (std::uint32_t px = 0; px < 64; ++px)
                for (std::uint64_t i = 0; i < 4; ++i) {
                    s.start(px, py, i);
                    Vec2 p = s.get_2d();
                    Vec2 q = s.get_2d();
                    a.push_back(p.x);
                    dim2.push_back(q.x);
                    s.start(px + 1, py, i);
                    right.push_back(s.get_2d().x);
                    s.start(px, py + 1, i);
                    below.push_back(s.get_2d().x);
                }
        double bound = kSigmas / std::sqrt(double(a.size()));
        double r1 = correlation(a, right), r2 = correlation(a, below), r3 = correlation(a, dim2);
        INFO("kind " << int(kind) << ": r(right) = " << r1 << ", r(below) = " << r2
                     << ", r(dim 0, dim 2) = " << r3 << ", bound " << bound);
        CHECK(std::abs(r1) < bound);
        CHECK(std::abs(r2) < bound);
        CHECK(std::abs(r3) < bound);
    }
}

TEST_CASE("Sobol integrates a smooth function with lower error than independent sampling",
          "[sampling][stat]") {
    // f(x, y) = x e^x * y e^y has integral exactly 1 over the unit square.
    auto f = [](Vec2 p) {
        return double(p.x) * std::exp(double(p.x)) * p.y * std::exp(double(p.y));
    };
    constexpr int kPixels = 64;       // independent estimates (different scrambles) per sampler
    constexpr std::uint64_t kN = 256; // samples per estimate
    // Owen-scrambled Sobol has MSE O(N^-3) on smooth integrands versus O(N^-1) for independent
    // samples; at N = 256 the expected ratio is in the thousands, so a ratio of 20 is a very
    // conservative floor that the 64-estimate MSEs resolve reliably.
    constexpr double kMinRatio = 20.0;
    double mse[2] = {0, 0};
    int idx = 0;
    for (SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol}) {
        Sampler s(kind, 2024);
        for (std::uint32_t px = 0; px < kPixels; ++px) {
            double sum = 0;
            for (std::uint64_t i = 0; i < kN; ++i) {
                s.start(px, 0, i);
                s.get_2d(); // use the second pair, as after the camera sample
                sum += f(s.get_2d());
            }
            double err = sum / double(kN) - 1.0;
            mse[idx] += err * err / kPixels;
        }
        ++idx;
    }
    INFO("MSE independent = " << mse[0] << ", MSE Sobol = " << mse[1]
                              << ", ratio = " << mse[0] / mse[1]);
    CHECK(mse[0] / mse[1] > kMinRatio);
    // The independent MSE must match its theoretical value Var(f)/N (Var(x e^x) = (e^2+1)/4 - 1,
    // so Var(f) = E[g^2]^2 - 1 with E[g^2] = (e^2 - 1)/4): a 64-sample MSE has relative standard
    // deviation sqrt(2/64) = 0.18, so accept a factor of 2 either way.
    const double e2 = std::exp(2.0);
    double eg2 = (e2 - 1.0) / 4.0;
    double var = eg2 * eg2 - 1.0;
    double mse_theory = var / double(kN);
    INFO("theoretical independent MSE = " << mse_theory);
    CHECK(mse[0] > 0.5 * mse_theory);
    CHECK(mse[0] < 2.0 * mse_theory);
}

TEST_CASE("a Sobol value depends on its dimension, not on what was drawn before it",
          "[sampling][quick]") {
    // The integrators' fixed dimension layout rests on this: the BSDF sample of bounce 2 draws
    // the same dimensions whether or not bounce 1 drew its roulette number.
    Sampler a(SamplerKind::Sobol, 99), b(SamplerKind::Sobol, 99);
    for (std::uint64_t index = 0; index < 64; ++index) {
        a.start(3, 5, index);
        b.start(3, 5, index);
        for (int k = 0; k < 7; ++k)
            a.get_1d(); // a path that used dimensions 0..6
        a.set_dimension(11);
        b.set_dimension(11); // one that skipped them
        const Vec2 ua = a.get_2d(), ub = b.get_2d();
        CHECK(ua.x == ub.x);
        CHECK(ua.y == ub.y);
        CHECK(a.get_1d() == b.get_1d()); // dimension 13 for both
        CHECK(a.dimension() == 14);
    }
}
