#pragma once
// Everything a render needs besides the scene. Filled from the command line (io/cli) or by
// tests; defaults are the documented defaults of `candela render --help`.
#include "candela/accel/accel.h"
#include "candela/light/light_choice.h"
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

/// Most samples per pixel a render may ask for (-s, -a's batch) and most one pixel may take
/// under the relative sampler: 2^24, so sample counts stay exact in the EXR's float samples
/// channel.
constexpr int kMaxSpp = 1 << 24;
/// Samples per pixel of a uniform pass when --pass-spp does not say (pass_spp = 0): a pass is
/// min(spp, this), short enough that a stop request or a checkpoint comes within a fraction of
/// the render.
constexpr int kAutoPassSpp = 16;

struct RenderSettings {
    int width = 800, height = 600;
    /// -s: samples per pixel, which means one thing per sampler (`adaptive`): with None the
    /// samples every pixel takes; with Cs184 the most a pixel takes (it stops earlier when it
    /// meets adaptive_tol); with Relative the budget, the cost of a uniform render of spp
    /// samples per pixel, which the sampler spreads unevenly (one pixel may take up to
    /// kRelativeMaxOversampling x spp) and may stop short of at noise_threshold.
    int spp = 16;
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
    /// --light-sampler: how next-event estimation chooses a light (light/light_choice.h).
    LightSamplerKind light_sampler = LightSamplerKind::Auto;
    std::uint64_t seed = 0;
    std::uint64_t sample_offset = 0; ///< first sample index (disjoint ranges merge exactly)
    AccelOptions accel;
    AovSet aovs = AovSet::all();
    Region region;
    AdaptiveKind adaptive = AdaptiveKind::None;
    int adaptive_batch = 32; ///< -a BATCH: samples per pixel of each adaptive pass
    /// -a TOLERANCE under Cs184: a pixel stops when its 95 % confidence half-width falls below
    /// this times its mean (render/adaptive.h). Not used by the other samplers.
    float adaptive_tol = 0.05f;
    /// --noise-threshold (or -a's TOLERANCE) under Relative: the render stops when the estimated
    /// relative RMS error of the image reaches it; 0 = spend the whole budget. Not used by the
    /// other samplers.
    float noise_threshold = 0.05f;
    int pass_spp = 0; ///< samples per pixel per uniform pass; 0 = min(spp, kAutoPassSpp)
    /// --time-budget: seconds after which no new pass starts (whole passes); 0 = no limit.
    /// -s stays the upper bound on samples per pixel.
    double time_budget = 0.0;
    bool quiet = false;
    /// How progress is shown (render/progress.h); quiet silences all but an explicit Json.
    ProgressMode progress = ProgressMode::Auto;
};

} // namespace candela
