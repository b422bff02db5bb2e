#pragma once
// Everything a render needs besides the scene. Filled from the command line (io/cli) or by
// tests; defaults are the documented defaults of `candela render --help`.
#include "candela/accel/accel.h"
#include "candela/light/light_sampler.h"
#include "candela/render/film.h"
#include "candela/render/progress.h"
#include "candela/sampling/sampler.h"
#include "candela/util/enum_table.h"

#include <cstdint>
#include <string>

namespace candela {

enum class IntegratorKind { Path, Direct, Normals };
/// --integrator (util/enum_table.h).
inline constexpr EnumTable<IntegratorKind, 3> kIntegratorKinds = {{
    {IntegratorKind::Path, "path", ""},
    {IntegratorKind::Direct, "direct", ""},
    {IntegratorKind::Normals, "normals", ""},
}};

/// Which scattering orders reach the image: all, direct (emitters seen directly plus one
/// scattering event) or indirect (two or more events).
enum class LightPaths { All, Direct, Indirect };
/// --light-paths.
inline constexpr EnumTable<LightPaths, 3> kLightPaths = {{
    {LightPaths::All, "all", ""},
    {LightPaths::Direct, "direct", "emitters seen directly + one bounce"},
    {LightPaths::Indirect, "indirect", "two or more"},
}};

/// cs184: per-pixel stopping of spec §5.4. relative: the cost of a uniform render at spp,
/// redistributed each pass by a smoothed relative-error estimate per unit of cost
/// (render/adaptive.h).
enum class AdaptiveKind { None, Cs184, Relative };
/// --adaptive.
inline constexpr EnumTable<AdaptiveKind, 3> kAdaptiveKinds = {{
    {AdaptiveKind::Relative, "relative",
     "default: the cost of a uniform -s render, spent in batches on the pixels with the most "
     "relative error per unit of cost, judged from their neighbours; stops at "
     "--noise-threshold"},
    {AdaptiveKind::Cs184, "cs184",
     "the default with -a: a pixel stops at 1.96 sigma/sqrt(n) <= TOL mu"},
    {AdaptiveKind::None, "none", "-s samples in every pixel"},
}};

struct Region {
    int x = 0, y = 0, w = 0, h = 0; ///< frame coordinates, origin top-left; w = 0: full frame
    bool full() const { return w == 0 || h == 0; }
};

struct RenderSettings {
    int width = 800, height = 600;
    int spp = 16;           ///< -s: samples per pixel (the maximum when adaptive)
    int light_samples = 1;  ///< -l: light samples per vertex (per non-delta light for direct)
    int max_depth = 8;      ///< -m: maximum number of scattering events
    bool accumulate = true; ///< -o: 1 accumulate orders 0..m; 0 only order m
    int threads = 0;        ///< -t: 0 = all cores
    IntegratorKind integrator = IntegratorKind::Path;
    LightPaths light_paths = LightPaths::All;
    bool hemisphere = false; ///< -H: direct light by uniform hemisphere sampling
    bool mis = true;         ///< --no-mis turns multiple importance sampling off
    int rr_min_depth = 3;    ///< Russian roulette starts after this many scattering events
    SamplerKind sampler = SamplerKind::Independent;
    /// --light-sampler: how next-event estimation chooses a light (light/light_sampler.h).
    LightSamplerKind light_sampler = LightSamplerKind::Auto;
    std::uint64_t seed = 0;
    std::uint64_t sample_offset = 0; ///< first sample index (disjoint ranges merge exactly)
    AccelOptions accel;
    AovSet aovs = AovSet::all();
    Region region;
    AdaptiveKind adaptive = AdaptiveKind::None;
    int adaptive_batch = 32;    ///< -a: samples per batch
    float adaptive_tol = 0.05f; ///< -a: tolerance
    int pass_spp = 0;           ///< samples per pixel per pass; 0 = automatic (min(spp, 16))
    /// --time-budget: seconds after which no new pass starts (whole passes); 0 = no limit.
    /// -s stays the upper bound on samples per pixel.
    double time_budget = 0.0;
    bool quiet = false;
    /// How progress is shown (render/progress.h); quiet silences all but an explicit Json.
    ProgressMode progress = ProgressMode::Auto;
};

} // namespace candela
