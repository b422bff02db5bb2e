// Refining a render (refine.h): the checks every sampler shares; the rest is the policy's.
#include "candela/render/refine.h"

#include "candela/render/adaptive.h"
#include "candela/util/error.h"

#include <string>

namespace candela {

void reopen_for_refinement(const RenderSettings& before, const RenderSettings& after,
                           RenderState& st) {
    if (after.spp < before.spp)
        throw Error(ErrorKind::Usage, "a refinement cannot lower -s (" +
                                          std::to_string(before.spp) + " to " +
                                          std::to_string(after.spp) + ")");
    const std::unique_ptr<PassPolicy> policy = make_pass_policy(after);
    // 0 is no threshold: the strictest.
    const bool stricter_or_same =
        after.noise_threshold == 0.f || after.noise_threshold <= before.noise_threshold;
    if (policy->reads_noise_threshold() && !stricter_or_same)
        throw Error(ErrorKind::Usage, "a refinement cannot raise the noise threshold");
    const bool finished = make_pass_policy(before)->finished(st);
    if (!finished && after.spp == before.spp && after.noise_threshold == before.noise_threshold)
        return;
    policy->reopen(before, finished, st);
}

RefineForecast forecast_refinement(const RenderSettings& s, RenderState& st,
                                   double seconds_so_far) {
    RefineForecast f;
    const std::unique_ptr<PassPolicy> policy = make_pass_policy(s);
    policy->prepare(st);
    if (policy->finished(st)) return f;
    const std::uint64_t taken = st.film.total_samples() + st.film.total_dropped();
    f.noise = policy->estimated_error();
    f.samples = double(policy->samples_left(st));
    f.seconds = taken > 0 ? f.samples * seconds_so_far / double(taken) : 0.0;
    return f;
}

} // namespace candela
