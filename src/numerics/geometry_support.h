#pragma once
// Helpers shared by the geometric stress cases (not a public interface).
#include "candela/accel/accel.h"
#include "candela/numerics/stress.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/warp.h"

#include <fmt/printf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace candela::numerics::detail {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// One accelerator configuration of the suite.
struct Backend {
    const char* name;
    AccelOptions opt;
    /// Builtin and brute with the watertight test: the configurations that must not leak.
    bool watertight;
};

/// The six configurations every geometric case runs: brute and builtin with each triangle
/// test, Embree default and Embree robust.
inline std::vector<Backend> all_backends() {
    std::vector<Backend> b;
    auto add = [&](const char* name, AccelKind k, TriangleTest t, bool robust) {
        AccelOptions o;
        o.kind = k;
        o.triangle = t;
        o.embree_robust = robust;
        o.build_threads = 1;
        b.push_back(Backend{name, o, t == TriangleTest::Watertight && k != AccelKind::Embree});
    };
    add("brute Moller-Trumbore", AccelKind::Brute, TriangleTest::MollerTrumbore, false);
    add("brute watertight", AccelKind::Brute, TriangleTest::Watertight, false);
    add("builtin Moller-Trumbore", AccelKind::Builtin, TriangleTest::MollerTrumbore, false);
    add("builtin watertight", AccelKind::Builtin, TriangleTest::Watertight, false);
    add("embree", AccelKind::Embree, TriangleTest::MollerTrumbore, false);
    add("embree robust", AccelKind::Embree, TriangleTest::MollerTrumbore, true);
    return b;
}

/// A hit with a NaN or infinite t, u or v: never acceptable from any backend.
inline bool non_finite_hit(const std::optional<Hit>& h) {
    return h && !(std::isfinite(h->t) && std::isfinite(h->u) && std::isfinite(h->v));
}

inline StressResult make_row(const std::string& group, const std::string& name,
                             const std::string& method, const std::string& expected,
                             const std::string& measured, bool required, bool pass) {
    StressResult r;
    r.group = group;
    r.name = name;
    r.method = method;
    r.expected = required ? expected : "reported (" + expected + " not required)";
    r.measured = measured;
    r.reported_only = !required;
    r.pass = required ? pass : true;
    return r;
}

/// The deterministic generator of case `seed`, so that the cases do not depend on the standard
/// library's distributions.
inline SplitMix64 case_rng(std::uint64_t seed) {
    return SplitMix64(seed * kGoldenGamma + 0x632BE59BD9B4E019ull);
}

} // namespace candela::numerics::detail
