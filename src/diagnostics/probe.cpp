// Where one pixel's light comes from: the render core records each sample's path events
// (render/integrator.h, PathEvents); this file turns them into named shares (probe.h).
#include "candela/diagnostics/probe.h"

#include "candela/bsdf/bsdf.h"
#include "candela/render/film.h"
#include "candela/render/integrator.h"
#include "candela/util/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace candela {

namespace {

/// Samples rendered per call of the integrator: enough for its batch traversal to pay off,
/// few enough that one batch's events stay small.
constexpr std::size_t kProbeBatch = 1024;
/// The brightest samples whose share of the pixel's light is reported: 1 %, the fireflies.
constexpr double kTopFraction = 0.01;

/// One split of the pixel's samples into classes: each sample's radiance parts are summed per
/// class, then each class's per-sample total is added to its sums (in double) and sums of
/// squares, for the class's mean and standard error.
class Split {
  public:
    explicit Split(std::size_t classes)
        : sum_(classes, {0.0, 0.0, 0.0}), sumsq_(classes, {0.0, 0.0, 0.0}), now_(classes, Rgb(0.f)),
          touched_(classes, 0) {}

    void add(std::size_t c, const Rgb& v) {
        if (!touched_[c]) {
            touched_[c] = 1;
            list_.push_back(c);
        }
        now_[c] += v;
    }

    /// Ends the current sample: its class totals join the sums.
    void end_sample() {
        for (std::size_t c : list_) {
            for (int k = 0; k < 3; ++k) {
                const double v = double(now_[c][k]);
                sum_[c][std::size_t(k)] += v;
                sumsq_[c][std::size_t(k)] += v * v;
            }
            now_[c] = Rgb(0.f);
            touched_[c] = 0;
        }
        list_.clear();
    }

    /// The classes' means and standard errors over `n` samples, named by `names`.
    std::vector<ProbeShare> shares(const std::vector<std::string>& names, std::uint64_t n) const {
        std::vector<ProbeShare> out(sum_.size());
        for (std::size_t c = 0; c < sum_.size(); ++c) {
            out[c].name = names[c];
            if (n == 0) continue;
            for (int k = 0; k < 3; ++k) {
                const double mean = sum_[c][std::size_t(k)] / double(n);
                const double var =
                    n > 1 ? std::max(0.0, (sumsq_[c][std::size_t(k)] - double(n) * mean * mean) /
                                              double(n - 1))
                          : 0.0;
                out[c].mean[k] = float(mean);
                out[c].std_error[k] = float(std::sqrt(var / double(n)));
            }
        }
        return out;
    }

  private:
    std::vector<std::array<double, 3>> sum_, sumsq_;
    std::vector<Rgb> now_;
    std::vector<std::uint8_t> touched_;
    std::vector<std::size_t> list_;
};

std::string material_name(const Scene& scene, std::uint32_t m) {
    const Material& mat = scene.materials[m];
    return (mat.name.empty() ? "material " + std::to_string(m) : "'" + mat.name + "'") + " (" +
           bsdf_kind_name(mat.kind) + ")";
}

std::string object_name(const Scene& scene, std::uint32_t object) {
    if (object < scene.meshes.size())
        return scene.meshes[object].name.empty() ? "mesh " + std::to_string(object)
                                                 : "'" + scene.meshes[object].name + "'";
    return "sphere " + std::to_string(object - scene.meshes.size());
}

std::string lobe_text(std::uint8_t flags) {
    const char* kind = (flags & kSpecular)  ? "specular"
                       : (flags & kGlossy)  ? "glossy"
                       : (flags & kDiffuse) ? "diffuse"
                                            : "";
    return std::string(kind) + ((flags & kTransmission) ? " transmission" : " reflection");
}

/// The events of one batch grouped by request, each request's in path order.
struct EventsByRequest {
    std::vector<std::uint32_t> hit_start, light_start, scatter_start;
    std::vector<std::uint32_t> hits, lights, scatters; ///< indices into the PathEvents lists

    void build(const PathEvents& ev, std::size_t n) {
        group(ev.hits, n, hit_start, hits);
        group(ev.contributions, n, light_start, lights);
        group(ev.scatters, n, scatter_start, scatters);
    }

  private:
    /// A stable counting sort of `events` by request.
    template <class E>
    static void group(const std::vector<E>& events, std::size_t n,
                      std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& order) {
        start.assign(n + 1, 0);
        for (const E& e : events)
            ++start[e.request + 1];
        std::partial_sum(start.begin(), start.end(), start.begin());
        order.resize(events.size());
        std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
        for (std::uint32_t i = 0; i < events.size(); ++i)
            order[next[events[i].request]++] = i;
    }
};

/// The one infinite area light of the scene, or PathEvents::kEscaped when there are none or
/// several.
std::int32_t sky_light(const Scene& scene) {
    std::int32_t found = PathEvents::kEscaped;
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        if (!l.is_infinite() || l.is_delta()) continue;
        if (found != PathEvents::kEscaped) return PathEvents::kEscaped;
        found = std::int32_t(i);
    }
    return found;
}

} // namespace

std::string light_display_name(const Scene& scene, std::int32_t light) {
    if (light < 0) return "infinite lights (rays that left the scene)";
    const Light& l = scene.lights[std::size_t(light)];
    std::string name = "light " + std::to_string(light) + " (" + light_kind_name(l.kind);
    if (l.kind == LightKind::Mesh && l.geom_id < scene.meshes.size())
        name += " " + object_name(scene, l.geom_id);
    return name + ")";
}

ProbeResult probe_pixel(const Scene& scene, const Accel& accel, const RenderSettings& settings,
                        int x, int y, int heaviest) {
    if (x < 0 || y < 0 || x >= settings.width || y >= settings.height)
        throw Error(ErrorKind::Usage, "probe: pixel (" + std::to_string(x) + ", " +
                                          std::to_string(y) + ") is not inside the " +
                                          std::to_string(settings.width) + "x" +
                                          std::to_string(settings.height) + " frame");
    if (settings.integrator == IntegratorKind::Normals)
        throw Error(ErrorKind::Usage, "probe: the normals integrator carries no light");
    const Integrator integrator(scene, accel, settings);
    const std::size_t lights = scene.lights.size(), materials = scene.materials.size();
    const std::size_t objects = scene.meshes.size() + scene.spheres.size();
    const std::size_t orders = std::size_t(std::max(0, settings.max_depth)) + 1;
    // Rays that left the scene found the infinite area lights together: with one such light
    // (an ambient light or an environment map) the light is that one.
    const std::int32_t escaped = sky_light(scene);
    Split by_order(orders), by_light(lights + 1), by_first_material(materials + 1),
        by_first_object(objects + 1), by_last(materials + 1);

    ProbeResult r;
    r.x = x;
    r.y = y;
    Film film(1, 1, AovSet::all(), true);
    BatchWorkspace ws;
    RenderCounters counters;
    PathEvents events;
    EventsByRequest grouped;
    std::vector<SampleRequest> requests;
    std::vector<SampleResult> results;
    std::vector<std::pair<float, std::uint64_t>> luminances; // finite samples: (Y, index)
    const std::uint64_t spp = std::uint64_t(std::max(0, settings.spp));
    for (std::uint64_t first = 0; first < spp; first += kProbeBatch) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(kProbeBatch, spp - first));
        requests.resize(n);
        results.resize(n);
        for (std::size_t k = 0; k < n; ++k)
            requests[k] = SampleRequest{std::uint32_t(x), std::uint32_t(y),
                                        settings.sample_offset + first + k};
        events.clear();
        integrator.render(requests.data(), n, results.data(), ws, counters, &events);
        r.dropped += film.add_samples(
            0, 0, int(n), [&](int k) -> const FilmSample& { return results[std::size_t(k)].fs; });
        grouped.build(events, n);
        for (std::size_t k = 0; k < n; ++k) {
            if (!is_finite(results[k].fs.L)) continue; // dropped, as by the film
            luminances.push_back({luminance(results[k].fs.L), settings.sample_offset + first + k});
            const std::uint32_t h0 = grouped.hit_start[k], h1 = grouped.hit_start[k + 1];
            const PathEvents::Hit* first_hit = h1 > h0 ? &events.hits[grouped.hits[h0]] : nullptr;
            for (std::uint32_t j = grouped.light_start[k]; j < grouped.light_start[k + 1]; ++j) {
                const PathEvents::Contribution& c = events.contributions[grouped.lights[j]];
                by_order.add(std::size_t(std::min<int>(c.order, int(orders) - 1)), c.value);
                const std::int32_t light = c.light < 0 ? escaped : c.light;
                by_light.add(light < 0 ? lights : std::size_t(light), c.value);
                by_first_material.add(first_hit ? first_hit->material : materials, c.value);
                by_first_object.add(first_hit ? first_hit->object : objects, c.value);
                // The last scattering event before the light is the path's vertex order - 1.
                std::size_t last = materials;
                if (c.order > 0 && h0 + std::uint32_t(c.order - 1) < h1)
                    last = events.hits[grouped.hits[h0 + std::uint32_t(c.order - 1)]].material;
                by_last.add(last, c.value);
            }
            for (Split* s : {&by_order, &by_light, &by_first_material, &by_first_object, &by_last})
                s->end_sample();
        }
    }
    r.samples = spp;
    r.pixel = film.mean(0, 0);
    const Rgb vm = film.variance_of_mean(0, 0);
    r.std_error = Rgb(std::sqrt(vm.x), std::sqrt(vm.y), std::sqrt(vm.z));

    // Names of the classes: `count` named by `name`, then the one after them, if any.
    const std::uint64_t n = film.count(0, 0);
    auto names = [](std::size_t count, const auto& name, const char* last) {
        std::vector<std::string> v;
        for (std::size_t i = 0; i < count; ++i)
            v.push_back(name(i));
        if (last) v.push_back(last);
        return v;
    };
    r.by_order = by_order.shares(
        names(
            orders,
            [](std::size_t o) { return o == 0 ? "0 (emitters seen directly)" : std::to_string(o); },
            nullptr),
        n);
    r.by_light = by_light.shares(
        names(
            lights, [&](std::size_t l) { return light_display_name(scene, std::int32_t(l)); },
            light_display_name(scene, PathEvents::kEscaped).c_str()),
        n);
    const auto material = [&](std::size_t m) { return material_name(scene, std::uint32_t(m)); };
    r.by_first_material = by_first_material.shares(names(materials, material, "nothing hit"), n);
    r.by_last_scatter =
        by_last.shares(names(materials, material, "camera (emitters seen directly)"), n);
    r.by_first_object = by_first_object.shares(
        names(
            objects, [&](std::size_t o) { return object_name(scene, std::uint32_t(o)); },
            "nothing hit"),
        n);

    // The brightest samples' share, and the heaviest samples' paths (rendered again, alone:
    // a sample's result depends only on its own request).
    std::sort(luminances.begin(), luminances.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    double total = 0.0, top = 0.0;
    const std::size_t top_count =
        std::max<std::size_t>(1, std::size_t(std::ceil(kTopFraction * double(luminances.size()))));
    for (std::size_t i = 0; i < luminances.size(); ++i) {
        total += luminances[i].first;
        if (i < top_count) top += luminances[i].first;
    }
    r.top_percent_share = total > 0.0 ? top / total : 0.0;
    for (std::size_t i = 0;
         i < std::min<std::size_t>(std::size_t(std::max(0, heaviest)), luminances.size()); ++i) {
        const SampleRequest req{std::uint32_t(x), std::uint32_t(y), luminances[i].second};
        SampleResult res;
        events.clear();
        integrator.render(&req, 1, &res, ws, counters, &events);
        ProbePath p;
        p.sample = req.index;
        p.L = res.fs.L;
        for (const PathEvents::Hit& h : events.hits) {
            ProbeVertex v;
            v.depth = h.depth;
            v.material = material_name(scene, h.material);
            v.object = object_name(scene, h.object);
            if (h.light >= 0) v.emits = light_display_name(scene, h.light);
            for (const PathEvents::Scatter& s : events.scatters)
                if (s.depth == h.depth) v.scatter = lobe_text(s.flags);
            p.vertices.push_back(v);
        }
        for (const PathEvents::Contribution& c : events.contributions)
            p.lights.push_back(
                {c.order, light_display_name(scene, c.light < 0 ? escaped : c.light), c.value});
        r.heaviest.push_back(std::move(p));
    }
    return r;
}

} // namespace candela
