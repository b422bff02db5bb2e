#pragma once
// Refining a render: continuing the state of a finished (or interrupted) render with a larger
// -s or, under the relative sampler, a stricter noise threshold, and predicting what that takes.
//
// Why the result is the render the final settings would have made from the start: every
// decision of the pass loop depends only on the film, the recorded costs, the pass count and
// the settings, and the settings that may change enter those decisions late.
//  - --adaptive none: a pixel's sample k draws the same numbers whatever -s is, and the film
//    adds each pixel's samples in index order, so the passes' boundaries do not matter:
//    -s 32 refined to -s 64 is bit-identical to -s 64.
//  - relative, stricter threshold: the threshold only ends the render (PassPolicy::decide); every
//    pass before the looser threshold was reached had an error above both, so a direct render
//    to the stricter one went through the same passes and continues from the same state:
//    bit-identical.
//  - relative, larger -s: the budget (-s times the first pass's cost per sample) and the most
//    one pixel may take (kRelativeMaxOversampling x -s) grow with -s, so the allocations differ
//    slightly from a direct render's: the image agrees statistically, not bit for bit.
//  - cs184 (-a), larger -s: the pixels that had not converged are tested at the old -s, as a
//    direct render tests them at that pass boundary; bit-identical when the old -s is a whole
//    number of the direct render's passes (min(-s, BATCH) samples each), else statistically.
#include "candela/render/render_state.h"
#include "candela/render/settings.h"

namespace candela {

/// What continuing a render will take, predicted before it starts.
struct RefineForecast {
    /// Relative sampler: the state's estimated relative RMS error (the sampler's own estimate,
    /// adaptive.h); -1 in the other modes.
    double noise = -1.0;
    double samples = 0.0; ///< camera samples still to take
    double seconds = 0.0; ///< render seconds for them, at the state's measured cost
};

/// Prepares `st`, the state of a render with settings `before` (finished or interrupted), for
/// Renderer::run with settings `after`, which may differ from `before` only by a larger or
/// equal -s and (a sampler that reads it) a noise threshold at most as large (0 = none, the
/// strictest); the sampler's policy does the rest (PassPolicy::reopen). A no-op when nothing
/// differs and the render was interrupted. Throws Error(Usage) when `after` loosens a setting.
void reopen_for_refinement(const RenderSettings& before, const RenderSettings& after,
                           RenderState& st);

/// Predicts the rest of the render of `st` (after reopen_for_refinement) with `settings`, from
/// the cost per sample of `seconds_so_far` of rendering: the samples are the policy's
/// samples_left() once it has prepared `st` (PassPolicy::prepare, which run() does again), the
/// noise its estimated_error().
RefineForecast forecast_refinement(const RenderSettings& settings, RenderState& st,
                                   double seconds_so_far);

} // namespace candela
