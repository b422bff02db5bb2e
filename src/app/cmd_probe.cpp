// `candela probe SCENE X Y [render options]`: where one pixel's light comes from
// (diagnostics/probe.h), as text or JSON.
#include "commands.h"
#include "scene_source.h"

#include "candela/app/cli.h"
#include "candela/diagnostics/probe.h"
#include "candela/util/log.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace candela::app {

namespace {

struct ProbeArgs {
    RenderArgs render;
    int x = -1, y = -1;
    bool json = false;
    int paths = 3; ///< heaviest samples whose paths are shown
};

double share_of(const Rgb& part, const Rgb& whole) {
    const double w = luminance(whole);
    return w > 0.0 ? double(luminance(part)) / w : 0.0;
}

bool empty_share(const ProbeShare& s) {
    return s.mean == Rgb(0.f) && s.std_error == Rgb(0.f);
}

nlohmann::ordered_json rgb_json(const Rgb& c) {
    return nlohmann::ordered_json::array({c.x, c.y, c.z});
}

nlohmann::ordered_json split_json(const std::vector<ProbeShare>& split, const Rgb& pixel) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (const ProbeShare& s : split)
        a.push_back({{"name", s.name},
                     {"rgb", rgb_json(s.mean)},
                     {"std_error", rgb_json(s.std_error)},
                     {"share", share_of(s.mean, pixel)}});
    return a;
}

std::string probe_json(const ProbeResult& r, const RenderArgs& args) {
    nlohmann::ordered_json j;
    j["scene"] = args.scene;
    j["x"] = r.x;
    j["y"] = r.y;
    j["samples"] = r.samples;
    j["dropped"] = r.dropped;
    j["pixel"] = rgb_json(r.pixel);
    j["std_error"] = rgb_json(r.std_error);
    j["brightest_1_percent_share"] = r.top_percent_share;
    j["by_order"] = split_json(r.by_order, r.pixel);
    j["by_light"] = split_json(r.by_light, r.pixel);
    j["by_first_material"] = split_json(r.by_first_material, r.pixel);
    j["by_first_object"] = split_json(r.by_first_object, r.pixel);
    j["by_last_scatter"] = split_json(r.by_last_scatter, r.pixel);
    nlohmann::ordered_json heavy = nlohmann::ordered_json::array();
    for (const ProbePath& p : r.heaviest) {
        nlohmann::ordered_json vertices = nlohmann::ordered_json::array(), lights = vertices;
        for (const ProbeVertex& v : p.vertices)
            vertices.push_back({{"depth", v.depth},
                                {"material", v.material},
                                {"object", v.object},
                                {"emits", v.emits},
                                {"scatter", v.scatter}});
        for (const ProbeLight& l : p.lights)
            lights.push_back({{"order", l.order}, {"light", l.light}, {"rgb", rgb_json(l.value)}});
        heavy.push_back({{"sample", p.sample},
                         {"rgb", rgb_json(p.L)},
                         {"vertices", vertices},
                         {"lights", lights}});
    }
    j["heaviest"] = heavy;
    return j.dump(2) + "\n";
}

std::string rgb_text(const Rgb& c) {
    return fmt::format("{:9.4g} {:9.4g} {:9.4g}", double(c.x), double(c.y), double(c.z));
}

std::string split_text(const char* title, const std::vector<ProbeShare>& split, const Rgb& pixel) {
    std::string out = std::string(title) + "\n";
    for (const ProbeShare& s : split) {
        if (empty_share(s)) continue;
        out += fmt::format("  {:6.1f} %  {}  +- {}  {}\n", 100.0 * share_of(s.mean, pixel),
                           rgb_text(s.mean), rgb_text(s.std_error), s.name);
    }
    return out;
}

std::string probe_text(const ProbeResult& r, const RenderArgs& args) {
    const RenderSettings& s = args.settings;
    std::string out = fmt::format("{}: pixel ({}, {}) of {}x{}, {} samples ({} non-finite "
                                  "dropped), max depth {}, seed {}\n",
                                  args.scene, r.x, r.y, s.width, s.height, r.samples, r.dropped,
                                  s.max_depth, s.seed);
    out +=
        "pixel      " + rgb_text(r.pixel) + "  +- " + rgb_text(r.std_error) + " (standard error)\n";
    out += fmt::format("the brightest 1 % of the samples carry {:.1f} % of the light\n",
                       100.0 * r.top_percent_share);
    out += "\n   share         R         G         B       standard error\n";
    out += split_text("by scattering order:", r.by_order, r.pixel);
    out += split_text("by light:", r.by_light, r.pixel);
    out += split_text("by material of the first hit:", r.by_first_material, r.pixel);
    out += split_text("by object of the first hit:", r.by_first_object, r.pixel);
    out += split_text(
        "by material of the last scattering event before the light:", r.by_last_scatter, r.pixel);
    if (!r.heaviest.empty()) out += "\nheaviest samples:\n";
    for (std::size_t i = 0; i < r.heaviest.size(); ++i) {
        const ProbePath& p = r.heaviest[i];
        out += fmt::format(
            "  #{} sample {}: {} ({:.1f} x the pixel)\n", i + 1, p.sample, rgb_text(p.L),
            luminance(r.pixel) > 0.f ? double(luminance(p.L) / luminance(r.pixel)) : 0.0);
        for (const ProbeVertex& v : p.vertices)
            out += "     vertex " + std::to_string(v.depth) + ": " + v.material + " on " +
                   v.object + (v.emits.empty() ? "" : ", emits as " + v.emits) +
                   (v.scatter.empty() ? "" : " -> " + v.scatter) + "\n";
        for (const ProbeLight& l : p.lights)
            out += "     light: order " + std::to_string(l.order) + " from " + l.light + ": " +
                   rgb_text(l.value) + "\n";
    }
    return out;
}

} // namespace

void add_probe_command(CLI::App& app, int* status) {
    auto args = std::make_shared<ProbeArgs>();
    CLI::App* cmd = app.add_subcommand(
        "probe",
        "Where one pixel's light comes from: its value split by scattering order, light, "
        "first-hit material and object, and the last scattering event before the light, the "
        "share of the brightest 1 % of samples and the paths of the heaviest. Takes the render "
        "options of the image (output, adaptive and checkpoint options are ignored); the "
        "pixel's value is what `candela render --adaptive none` gives with them");
    add_render_options(*cmd, args->render);
    cmd->add_option("x", args->x, "Pixel column (0 = left)")->required();
    cmd->add_option("y", args->y, "Pixel row (0 = top, as in the image)")->required();
    cmd->add_flag("--json", args->json, "Machine-readable JSON");
    cmd->add_option("--paths", args->paths, "Heaviest samples whose paths are shown")
        ->capture_default_str();
    cmd->callback([args, cmd, status] {
        RenderArgs& a = args->render;
        record_given_options(*cmd, a);
        finalize_render_args(a);
        set_log_level(a.log_level);
        if (args->paths < 0) throw Error(ErrorKind::Usage, "--paths must be >= 0");
        check_scene_file(a.scene);
        const Scene scene = load_render_scene(a);
        const std::unique_ptr<Accel> accel = make_accel(scene, a.settings.accel);
        const ProbeResult r = probe_pixel(scene, *accel, a.settings, args->x, args->y, args->paths);
        const std::string text = args->json ? probe_json(r, a) : probe_text(r, a);
        std::fwrite(text.data(), 1, text.size(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
