#pragma once
// Stiff light transport and numerical guards: the cases of the stress suite that render small
// scenes with a closed-form (or otherwise independently known) answer, and the cases that feed
// extreme inputs into every BSDF and light function. Each function runs its cases and returns one
// StressResult row per (case, method); a row passes when the measured value meets the expected
// one and no non-finite value was produced. Renders use fixed seeds, so every figure is
// reproducible; statistical rows compare with a z-test whose bound comes from the estimator's
// own variance (|z| < 4).
#include "candela/numerics/stress.h"

#include <vector>

namespace candela::numerics {

/// Group name of the rendered cases.
inline constexpr const char* kStiffTransportGroup = "stiff transport";
/// Group name of the extreme-input cases.
inline constexpr const char* kGuardsGroup = "guards";

/// Every case below, in order.
std::vector<StressResult> run_transport_cases(StressSize size);

/// Closed glowing diffuse sphere of albedo 0.99 and 0.999 seen from inside: radiance
/// Le / (1 - a) with Russian roulette (unbiased, finite), and Le (1 - a^(D+1)) / (1 - a) with
/// roulette off and depth cap D (the truncation is the only bias).
std::vector<StressResult> furnace_cases(StressSize size);

/// Beckmann conductor with alpha = 1e-4 and 1e-3: directional albedo tends to the smooth
/// conductor Fresnel term F(cos theta_o) (BSDF level), and a near-mirror floor under a uniform
/// sky renders F(cos theta_o) L_sky.
std::vector<StressResult> near_delta_microfacet_cases(StressSize size);

/// Lossless glass (IOR 1.0001 and 3.5, sphere and cube) inside a uniformly glowing enclosure is
/// invisible; a nearly index-matched slab over a diffuse floor changes nothing; a light inside a
/// glass cube of IOR 3.5 (total internal reflection trap) renders finitely and matches the
/// straight-through value.
std::vector<StressResult> dielectric_cases(StressSize size);

/// Conductor Fresnel with k = 0: equals the dielectric Fresnel term (no NaN at eta < 1, eta = 1),
/// and a rough k = 0 floor renders its quadrature directional albedo; eta = 1, k = 0 is black.
std::vector<StressResult> conductor_k0_cases(StressSize size);

/// A 1e-6-area light of radiance 1e8 beside a dim 4-unit-area light: irradiance at a point equals
/// the closed form with light sampling (direct and path); uniform hemisphere sampling is reported.
std::vector<StressResult> tiny_light_cases(StressSize size);

/// Camera inside closed objects: a diffuse sphere and a diffuse cube mesh with every light
/// outside render exactly black; an emitting sphere and cube render exactly their radiance.
std::vector<StressResult> camera_inside_cases(StressSize size);

/// Extreme inputs (cos = 0, tangent wo, wi = -wo, zero vectors, alpha = 0, eta = 1, points on a
/// light, zero-area lights) into every BSDF, Fresnel, microfacet, warp and light function: counts
/// of non-finite or negative outputs; and a render with a poisoned (NaN) material: every bad
/// sample is dropped and counted, none reaches the film.
std::vector<StressResult> guard_cases();

} // namespace candela::numerics
