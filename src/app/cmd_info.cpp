// `candela info`: what a scene contains and which render features it needs, as text or JSON.
#include "commands.h"

#include "candela/app/cli.h"
#include "candela/io/collada.h"
#include "candela/light/light_choice.h"
#include "candela/scene/builder.h"
#include "candela/scene/cs184_differences.h"
#include "candela/scene/scene_desc.h"
#include "candela/scene/scene_info.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace candela::app {

namespace {
struct InfoArgs {
    std::string scene;
    bool json = false;
    bool strict = false;
    bool vs_cs184 = false;
    std::string camera_mode = enum_name(kCameraModes, CameraMode::Framed);
    LogArgs log;
};
/// `info --vs-cs184`: the rows of docs/cs184-differences.md that apply to the scene.
std::string differences_text(const std::string& path, const SceneDesc& desc, const Scene& scene,
                             bool json) {
    const std::vector<AppliedDifference> rows = cs184_differences_for(desc, scene);
    if (json) {
        nlohmann::ordered_json j;
        j["scene"] = path;
        j["rows"] = nlohmann::ordered_json::array();
        for (const AppliedDifference& d : rows)
            j["rows"].push_back({{"topic", d.row->topic},
                                 {"why", d.why},
                                 {"cs184", d.row->cs184},
                                 {"candela", d.row->candela}});
        return j.dump(2) + "\n";
    }
    std::string out = path + ": " + std::to_string(rows.size()) + " of the " +
                      std::to_string(cs184_differences().size()) +
                      " rows of docs/cs184-differences.md apply\n";
    for (const AppliedDifference& d : rows)
        out += std::string("  ") + d.row->topic + " (" + d.why +
               ")\n      CS184:   " + d.row->cs184 + "\n      candela: " + d.row->candela + "\n";
    return out;
}

} // namespace

void add_info_command(CLI::App& app, int* status) {
    auto args = std::make_shared<InfoArgs>();
    CLI::App* cmd = app.add_subcommand(
        "info", "Print what a scene holds and what a render of it will need and leave out");
    cmd->add_option("scene", args->scene, "COLLADA scene file (.dae)")->required();
    cmd->add_flag("--json", args->json, "Machine-readable JSON");
    cmd->add_flag("--strict", args->strict, "Treat scene warnings as errors");
    cmd->add_flag("--vs-cs184", args->vs_cs184,
                  "List the rows of docs/cs184-differences.md that apply to this scene (where "
                  "its image differs from the course reference's by design, and why)");
    cmd->add_option("--camera", args->camera_mode,
                    enum_choices(kCameraModes, {", ", " or ", "", "", false}))
        ->capture_default_str();
    add_log_options(*cmd, args->log);
    cmd->callback([args, status] {
        set_log_level(log_level_of(args->log));
        BuildOptions opt;
        opt.camera_mode = parse_enum(kCameraModes, "--camera", args->camera_mode);
        check_scene_file(args->scene);
        Diagnostics diag(args->strict);
        const SceneDesc desc = load_collada(args->scene, diag);
        Scene scene = build_scene(desc, opt, diag);
        diag.flush();
        if (args->vs_cs184) {
            const std::string text = differences_text(args->scene, desc, scene, args->json);
            std::fwrite(text.data(), 1, text.size(), stdout);
            *status = 0;
            return;
        }
        std::string text = describe_scene(scene, args->json);
        // The light choice of a default render (--light-sampler auto).
        const std::string selection = describe_light_selection(scene, LightSamplerKind::Auto);
        if (args->json) {
            nlohmann::ordered_json j = nlohmann::ordered_json::parse(text);
            j["light_sampler"] = selection;
            text = j.dump(2) + "\n";
        } else {
            text += "light pick " + selection + "\n";
        }
        std::fwrite(text.data(), 1, text.size(), stdout);
        *status = 0;
    });
}

} // namespace candela::app
