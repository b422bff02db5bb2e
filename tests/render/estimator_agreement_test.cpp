// Estimator agreement on random scenes (tests/support/random_scene.h): every pair of estimators
// that must agree in expectation does, scene after scene. MIS on and off, hemisphere sampling,
// direct + indirect light paths against all, Sobol against independent samples, the relative
// adaptive sampler against uniform sampling, and the builtin BVH against Embree, each compared
// with one reference render (path tracing, MIS, independent samples, Embree) by a z-test on
// the image's mean luminance. The bound is Bonferroni's for a stated family-wise error rate
// over every comparison of the run, so a run of hundreds of scenes is as unlikely to fail
// falsely as a run of a few.
#include "render_support.h"

#include "../support/random_scene.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <functional>
#include <sstream>
#include <unistd.h>

using namespace candela;
using namespace candela::test;

namespace {

/// Family-wise error rate of one run: the probability that any comparison of a correct
/// renderer fails, whatever the number of scenes.
constexpr double kFamilyWiseError = 1e-3;
/// Comparisons per scene: no-mis, hemisphere, direct + indirect, sobol, relative, builtin, and
/// the light choice the default does not make (bvh or power).
constexpr int kComparisonsPerScene = 7;
/// A comparison has power when it can see a difference of this fraction of the image's mean at
/// its bound: the errors the test guards against (an infinite light counted twice against the
/// other's pdf, a light's normal off the rectangle, delta lights lost under -H) change a
/// random scene's mean by 10% to 70%.
constexpr double kDetectableFraction = 0.15;
/// Share of comparisons allowed to fall short of that power even after raising their samples
/// (glossy highlights of small lights seen through glass, found only by rare paths): the test's
/// stated power is "95% of comparisons see a 15% difference".
constexpr double kMaxUnderpoweredShare = 0.05;

/// z such that a two-sided normal test has false-alarm probability `alpha`: 2 (1 - Phi(z)).
double two_sided_z(double alpha) {
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

Estimate sum(const Estimate& a, const Estimate& b) {
    return {a.mean + b.mean, std::sqrt(a.std_err * a.std_err + b.std_err * b.std_err)};
}

struct AgreementRun {
    int scenes = 0;
    int comparisons = 0;
    int underpowered = 0; ///< comparisons that cannot see kDetectableFraction at the bound
    std::string underpowered_list;
    double worst_z = 0.0;
    std::string worst;
};

/// Renders scenes [first, first + count) with every estimator and checks each against the
/// reference at the Bonferroni bound of the whole run.
AgreementRun check_agreement(std::uint64_t first, int count) {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("candela-agree-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string env = (dir / "env.exr").string();
    write_test_envmap(env);
    RandomSceneMaker maker(env);

    const double z_bound = two_sided_z(kFamilyWiseError / (double(count) * kComparisonsPerScene));
    AgreementRun run;
    for (int k = 0; k < count; ++k) {
        const std::uint64_t index = first + std::uint64_t(k);
        RandomSceneInfo info;
        const Scene scene = maker.make(index, info);

        // Samples are raised for a comparison that cannot see kDetectableFraction of the mean
        // at its first sample count (hemisphere sampling of a glossy highlight, light through
        // glass): both renders again with enough samples, up to this factor.
        constexpr int kMaxSampleFactor = 64;
        RenderSettings base;
        base.width = 24;
        base.height = 18;
        base.spp = 160;
        base.max_depth = 5;
        base.rr_min_depth = 3;
        base.light_samples = 1 + int(index % 2);
        base.quiet = true;
        base.aovs = AovSet::parse("variance");
        std::uint64_t seed = hash_combine(index, 0x41475245ULL);
        auto render = [&](RenderSettings s) {
            s.seed = ++seed;
            return film_estimate(render_film(scene, s));
        };
        const Estimate ref = render(base);
        INFO(info.summary << " (-l " << base.light_samples << "), reference " << ref.mean << " +- "
                          << ref.std_err << ", bound z = " << z_bound);
        REQUIRE(ref.mean > 0.0);

        // Compares an estimator, rendered by `variant` at a sample factor, with the reference.
        auto compare = [&](const char* what, const std::function<Estimate(int)>& variant) {
            Estimate r = ref, e = variant(1);
            double se = std::sqrt(r.std_err * r.std_err + e.std_err * e.std_err);
            const double needed = std::pow(z_bound * se / (kDetectableFraction * r.mean), 2.0);
            int factor = 1;
            if (needed > 1.0) {
                factor = std::min(kMaxSampleFactor, int(std::ceil(needed)));
                RenderSettings more = base;
                more.spp *= factor;
                r = render(more);
                e = variant(factor);
                se = std::sqrt(r.std_err * r.std_err + e.std_err * e.std_err);
            }
            const double z = (e.mean - r.mean) / se;
            INFO(what << " (samples x" << factor << "): reference " << r.mean << " +- " << r.std_err
                      << ", this " << e.mean << " +- " << e.std_err << ", z = " << z);
            CHECK(std::abs(z) < z_bound);
            if (!(z_bound * se < kDetectableFraction * r.mean)) {
                ++run.underpowered;
                run.underpowered_list += "\n  " + info.summary + " " + what;
            }
            ++run.comparisons;
            if (std::abs(z) > std::abs(run.worst_z)) {
                run.worst_z = z;
                std::ostringstream os;
                os << info.summary << " " << what;
                run.worst = os.str();
            }
        };

        // A variant of the base settings at `factor` times its samples.
        auto variant = [&](const std::function<void(RenderSettings&)>& change) {
            return [&, change](int factor) {
                RenderSettings s = base;
                s.spp *= factor;
                change(s);
                return render(s);
            };
        };
        compare("--no-mis", variant([](RenderSettings& s) { s.mis = false; }));
        compare("-H", variant([](RenderSettings& s) { s.hemisphere = true; }));
        compare("--light-paths direct + indirect", [&](int factor) {
            RenderSettings direct = base, indirect = base;
            direct.spp *= factor;
            indirect.spp *= factor;
            direct.light_paths = LightPaths::Direct;
            indirect.light_paths = LightPaths::Indirect;
            return sum(render(direct), render(indirect));
        });
        compare("--sampler sobol",
                variant([](RenderSettings& s) { s.sampler = SamplerKind::Sobol; }));
        compare("relative adaptive", variant([](RenderSettings& s) {
                    s.adaptive = AdaptiveKind::Relative;
                    s.adaptive_batch = 16;
                    s.noise_threshold = 1e-6f; // spend the whole budget
                }));
        compare("--accel builtin",
                variant([](RenderSettings& s) { s.accel.kind = AccelKind::Builtin; }));
        // The reference chooses lights as --light-sampler auto does; the other rule must agree.
        const bool auto_is_bvh =
            LightChooser(scene, LightSamplerKind::Auto).kind() == LightSamplerKind::Bvh;
        compare(auto_is_bvh ? "--light-sampler power" : "--light-sampler bvh",
                variant([auto_is_bvh](RenderSettings& s) {
                    s.light_sampler = auto_is_bvh ? LightSamplerKind::Power : LightSamplerKind::Bvh;
                }));
        ++run.scenes;
    }
    std::filesystem::remove_all(dir);
    return run;
}

/// The run's summary and its checks: every comparison made, and the stated power.
void check_run(const AgreementRun& run) {
    WARN("estimator agreement: " << run.scenes << " scenes, " << run.comparisons
                                 << " comparisons, largest z " << run.worst_z << " (" << run.worst
                                 << "); without power: " << run.underpowered
                                 << run.underpowered_list);
    CHECK(run.comparisons == run.scenes * kComparisonsPerScene);
    CHECK(run.underpowered <= kMaxUnderpoweredShare * run.comparisons);
}

} // namespace

TEST_CASE("estimators agree on random scenes", "[render][stat][agreement]") {
    // 40 scenes, 240 comparisons at a family-wise false-alarm rate of 1e-3.
    check_run(check_agreement(0, 40));
}

// Hundreds of scenes, on demand: build/tests/candela_tests "[agreement-slow]".
TEST_CASE("estimators agree on hundreds of random scenes", "[.][agreement-slow]") {
    check_run(check_agreement(1000, 400));
}
