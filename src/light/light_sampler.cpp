#include "candela/light/light_sampler.h"

#include "candela/light/light_sampling.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

namespace {

std::string light_label(const Scene& scene, std::size_t k) {
    return scene.source + ": error: light " + std::to_string(k) + " (" +
           light_kind_name(scene.lights[k].kind) + ")";
}

/// Checks that a light's references into the scene are usable by sample_li.
void validate_light(const Scene& scene, std::size_t k) {
    const Light& light = scene.lights[k];
    if (light.kind == LightKind::Mesh) {
        if (light.geom_id >= scene.meshes.size())
            throw Error(ErrorKind::Internal, light_label(scene, k) + " refers to mesh " +
                                                 std::to_string(light.geom_id) + " of " +
                                                 std::to_string(scene.meshes.size()));
        const Mesh& mesh = scene.meshes[light.geom_id];
        if (light.tri_cdf.size() != mesh.triangle_count())
            throw Error(ErrorKind::Internal,
                        light_label(scene, k) + " has " + std::to_string(light.tri_cdf.size()) +
                            " triangle CDF entries for " + std::to_string(mesh.triangle_count()) +
                            " triangles");
        for (std::uint32_t idx : mesh.indices)
            if (idx >= mesh.positions.size())
                throw Error(ErrorKind::Internal,
                            light_label(scene, k) + ": mesh index out of range");
    } else if (light.kind == LightKind::Sphere) {
        if (light.geom_id >= scene.spheres.size())
            throw Error(ErrorKind::Internal, light_label(scene, k) + " refers to sphere " +
                                                 std::to_string(light.geom_id) + " of " +
                                                 std::to_string(scene.spheres.size()));
    } else if (light.kind == LightKind::Environment && !scene.env) {
        throw Error(ErrorKind::Internal, light_label(scene, k) + " has no environment map");
    }
}

} // namespace

LightSampler::LightSampler(const Scene& scene) {
    const std::size_t n = scene.lights.size();
    if (n == 0) return;
    std::vector<float> power(n);
    for (std::size_t k = 0; k < n; ++k) {
        validate_light(scene, k);
        float p = light_power(scene, scene.lights[k]);
        if (!std::isfinite(p) || p < 0.f)
            throw Error(ErrorKind::Scene,
                        light_label(scene, k) + " has invalid power " + std::to_string(p));
        power[k] = p;
    }
    dist_ = Distribution1D(power);
    n_ = n;
    pmf_.resize(n);
    for (std::size_t k = 0; k < n; ++k)
        pmf_[k] = dist_.pmf(k);
}

std::optional<LightChoice> LightSampler::sample_table(float u) const {
    if (n_ == 0) return std::nullopt;
    float pmf = 0.f;
    std::size_t k = dist_.sample_discrete(u, &pmf);
    return LightChoice{static_cast<std::uint32_t>(k), pmf};
}

float LightSampler::pmf(std::size_t index) const {
    return index < n_ ? pmf_[index] : 0.f;
}

} // namespace candela
