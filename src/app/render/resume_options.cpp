// The render options a checkpoint stores (option_specs()) and the check that a resuming
// command line agrees with them.
#include "../cli_support.h"
#include "../output_paths.h"

#include "candela/render/adaptive.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <fmt/format.h>

#include <string>
#include <type_traits>
#include <vector>

namespace candela {

namespace cli {

namespace {

/// A single value as the checkpoint stores it (floats with all the digits that read back).
template <typename T> std::vector<std::string> one(const T& v) {
    if constexpr (std::is_same_v<T, std::string>)
        return {v};
    else if constexpr (std::is_floating_point_v<T>)
        return {fmt::format("{:.9g}", double(v))};
    else
        return {std::to_string(v)};
}

/// Numbers as the checkpoint stores them.
template <typename T> std::vector<std::string> floats(const std::vector<T>& v) {
    std::vector<std::string> out;
    for (const T& x : v)
        out.push_back(one(x).front());
    return out;
}

/// The entry of a render setting, named by its row (render/setting_table.h); `values` gives the
/// values of a row the command line settles itself (SettingType::Custom), the row's type those
/// of the others.
OptionSpec setting_spec(Setting id,
                        std::function<std::vector<std::string>(const RenderArgs&)> values = {}) {
    const SettingRow& row = setting_row(id);
    if (!values)
        values = [&row](const RenderArgs& a) -> std::vector<std::string> {
            // A flag is on when given (its field then holds the value the flag sets).
            if (row.type == SettingType::Flag)
                return row.text(a.settings) == (row.flag_value ? "1" : "0")
                           ? std::vector<std::string>{}
                           : std::vector<std::string>{"off"};
            // A choice that names none of its choices stays as given.
            const auto it = a.unknown_choices.find(row.flag);
            return {it != a.unknown_choices.end() ? it->second : row.text(a.settings)};
        };
    return {row.flag.c_str(), row.display.c_str(), row.runtime, std::move(values)};
}

} // namespace

const std::vector<OptionSpec>& option_specs() {
    using V = std::vector<std::string>;
    using A = const RenderArgs&;
    static const std::vector<OptionSpec> specs = {
        {"scene", "SCENE", false, [](A a) { return V{absolute_path(a.scene)}; }},
        {"--output", "-f/--output", false, [](A a) { return V{absolute_path(a.output)}; }},
        setting_spec(Setting::Spp),
        setting_spec(Setting::LightSamples),
        setting_spec(Setting::Threads),
        setting_spec(Setting::MaxDepth),
        setting_spec(Setting::Accumulate, [](A a) { return one(a.accumulate); }),
        {"--env", "-e/--env", false, [](A a) { return V{absolute_path(a.env_map)}; }},
        {"--lens-radius", "-b/--lens-radius", false,
         [](A a) { return a.lens_radius ? one(*a.lens_radius) : V{""}; }},
        {"--focal-distance", "-d/--focal-distance", false,
         [](A a) { return a.focal_distance ? one(*a.focal_distance) : V{""}; }},
        {"--resolution", "-r/--resolution", false,
         [](A a) {
             return a.resolution.size() == 2
                        ? V{std::to_string(a.resolution[0]), std::to_string(a.resolution[1])}
                        : V{"800", "600"};
         }},
        {"--region", "-p/--region", false,
         [](A a) {
             V v;
             for (int x : a.region)
                 v.push_back(std::to_string(x));
             return v;
         }},
        {"--camera-file", "-c/--camera-file", false,
         [](A a) { return V{absolute_path(a.camera_file)}; }},
        setting_spec(Setting::AdaptiveBatch, [](A a) { return floats(a.adaptive); }),
        setting_spec(Setting::Hemisphere),
        setting_spec(Setting::Adaptive,
                     [](A a) {
                         const std::string& flag = setting_row(Setting::Adaptive).flag;
                         return choice(a, flag, kAdaptiveKinds,
                                       a.adaptive_kind.value_or(AdaptiveKind::None));
                     }),
        setting_spec(Setting::NoiseThreshold, [](A a) { return one(a.noise_threshold); }),
        setting_spec(Setting::TimeBudget),
        {"--camera", "--camera", false,
         [](A a) { return choice(a, "--camera", kCameraModes, a.build.camera_mode); }},
        {"--framing", "--framing", false,
         [](A a) { return choice(a, "--framing", kFramings, a.build.framing); }},
        {"--look-from", "--look-from", false, [](A a) { return floats(a.look_from); }},
        {"--look-at", "--look-at", false, [](A a) { return floats(a.look_at); }},
        {"--fov", "--fov", false, [](A a) { return a.fov ? one(*a.fov) : V{""}; }},
        setting_spec(Setting::Accel),
        setting_spec(Setting::Triangle),
        setting_spec(Setting::EmbreeRobust),
        setting_spec(Setting::EmbreeQuality),
        setting_spec(Setting::Seed),
        setting_spec(Setting::SampleOffset),
        setting_spec(Setting::Sampler),
        setting_spec(Setting::LightSampler),
        setting_spec(Setting::Integrator),
        setting_spec(Setting::LightPaths),
        setting_spec(Setting::Mis),
        setting_spec(Setting::RrDepth),
        setting_spec(Setting::Aov, [](A a) { return one(a.aov); }),
        {"--half", "--half", false, [](A a) { return a.half ? V{} : V{"off"}; }},
        {"--compression", "--compression", false, [](A a) { return one(a.compression); }},
        {"--background-depth", "--background-depth", false,
         [](A a) { return one(a.background_depth); }},
        {"--preview", "--preview", false, [](A a) { return a.preview ? V{} : V{"off"}; }},
        {"--tonemap", "--tonemap", false,
         [](A a) { return choice(a, "--tonemap", kTonemaps, a.tonemap); }},
        {"--exposure", "--exposure", false, [](A a) { return one(a.exposure); }},
        {"--look", "--look", false, [](A a) { return choice(a, "--look", kLooks, a.look); }},
        setting_spec(Setting::PassSpp),
        {"--strict", "--strict", true, [](A a) { return a.strict ? V{} : V{"off"}; }},
        {"--quiet", "-q/--quiet", true, [](A) { return V{}; }},
        {"--verbose", "-v/--verbose", true, [](A) { return V{}; }},
        {"--log-level", "--log-level", true, [](A a) { return one(a.log.level); }},
        setting_spec(Setting::Progress),
        {"--checkpoint", "--checkpoint", true, [](A a) { return V{absolute_path(a.checkpoint)}; }},
        {"--checkpoint-every", "--checkpoint-every", true,
         [](A a) { return one(a.checkpoint_every); }},
        {"--max-memory", "--max-memory", true, [](A a) { return one(a.max_memory); }},
        {"--resume", "--resume", true, [](A a) { return V{absolute_path(a.resume)}; }},
        {"--keep-checkpoint", "--keep-checkpoint", true,
         [](A a) { return a.keep_checkpoint ? V{} : V{"off"}; }},
        {"--overwrite", "--overwrite", true, [](A a) { return a.overwrite ? V{} : V{"off"}; }},
        {"--write-every", "--write-every", true, [](A a) { return one(a.write_every); }},
        {"--display-server", "--display-server", true, [](A a) { return V{a.display_server}; }},
    };
    return specs;
}

const OptionSpec* find_spec(const std::string& name) {
    for (const OptionSpec& s : option_specs())
        if (name == s.name) return &s;
    return nullptr;
}

} // namespace cli

namespace {

using cli::find_spec;
using cli::option_specs;
using cli::OptionSpec;

/// Flags without a value in the canonical list (their value vector is empty when set).
bool is_flag(const std::string& name) {
    if (const SettingRow* row = find_setting(name)) return row->type == SettingType::Flag;
    return name == "--half" || name == "--preview" || name == "--strict" || name == "--quiet" ||
           name == "--verbose" || name == "--keep-checkpoint" || name == "--overwrite";
}

std::string quoted_list(const std::vector<std::string>& v) {
    if (v.empty()) return "on";
    std::string s;
    for (const std::string& x : v)
        s += (s.empty() ? "" : " ") + (x.empty() ? std::string("(unset)") : x);
    return s;
}

/// A resume that refines (render/refine.h) may raise -s and lower the relative sampler's noise
/// threshold (0 = none, the strictest). Returns whether `name` changes that way; throws the
/// refusal, naming the setting, when it changes the other way.
bool refines(const std::string& name, const RenderArgs& given, const RenderArgs& stored,
             const std::string& checkpoint, const std::vector<std::string>& here,
             const std::vector<std::string>& there) {
    const std::string refused = "refusing to refine: ";
    if (name == setting_row(Setting::Spp).flag) {
        if (given.settings.spp > stored.settings.spp) return true;
        throw Error(ErrorKind::Usage, SourceLoc{checkpoint},
                    refused + "-s/--spp is " + here.front() + " here but " + there.front() +
                        " in the checkpoint; a refinement may only raise it");
    }
    if (name == setting_row(Setting::NoiseThreshold).flag) {
        const std::string t_here = fmt::format("{:g}", given.noise_threshold);
        const std::string t_there = fmt::format("{:g}", stored.noise_threshold);
        if (!make_pass_policy(stored.settings)->reads_noise_threshold() || !stored.adaptive.empty())
            throw Error(ErrorKind::Usage, SourceLoc{checkpoint},
                        refused + "--noise-threshold is " + t_here +
                            " here, but the checkpoint's render does not stop at a noise "
                            "threshold (it uses " +
                            (stored.adaptive.empty()
                                 ? "--adaptive " + std::string(enum_name(kAdaptiveKinds,
                                                                         stored.settings.adaptive))
                                 : std::string("-a")) +
                            ")");
        const float t = given.noise_threshold, old = stored.noise_threshold;
        if ((t == 0.f && old > 0.f) || t < old) return true;
        throw Error(ErrorKind::Usage, SourceLoc{checkpoint},
                    refused + "--noise-threshold is " + t_here + " here but " + t_there +
                        " in the checkpoint; a refinement may only lower it (0 = no threshold)");
    }
    return false;
}

} // namespace

std::vector<std::string> canonical_render_args(const RenderArgs& a) {
    std::vector<std::string> out;
    for (const OptionSpec& spec : option_specs()) {
        if (spec.runtime) continue;
        const std::string name = spec.name;
        // The scene and the output are always stored, as absolute paths: the default output
        // lies in the directory the render started from.
        const bool always = name == "scene" || name == "--output";
        if (!always && !a.given.count(name)) continue;
        std::vector<std::string> v = spec.values(a);
        if (name == "scene") {
            out.push_back(v.front());
            continue;
        }
        if (is_flag(name)) {
            if (v.empty()) out.push_back(name);
            continue;
        }
        if (name == "--lens-radius" || name == "--focal-distance" || name == "--camera-file" ||
            name == "--env") {
            if (v.front().empty()) continue;
        }
        out.push_back(name);
        out.insert(out.end(), v.begin(), v.end());
    }
    return out;
}

std::string resume_runtime_options() {
    std::string s;
    for (const OptionSpec& spec : option_specs())
        if (spec.runtime && std::string(spec.name) != "--resume")
            s += (s.empty() ? "" : ", ") + std::string(spec.display);
    return s;
}

void check_resume_matches(const RenderArgs& given, const RenderArgs& stored,
                          const std::string& checkpoint) {
    for (const std::string& name : given.given) {
        const OptionSpec* spec = find_spec(name);
        CANDELA_CHECK(spec != nullptr, "no resume rule for option " + name);
        if (spec->runtime) continue;
        std::vector<std::string> here = spec->values(given), there = spec->values(stored);
        if (here != there && refines(name, given, stored, checkpoint, here, there)) continue;
        if (name == "scene" || name == "--output" || name == "--env" || name == "--camera-file") {
            // The same file under another name is the same setting.
            if (!here.front().empty() && !there.front().empty() &&
                (same_file_or_path(here.front(), there.front()) || here == there))
                continue;
        }
        if (here == there) continue;
        throw Error(ErrorKind::Usage, SourceLoc{checkpoint},
                    std::string("refusing to resume: ") + spec->display + " is " +
                        quoted_list(here) + " here but " + quoted_list(there) +
                        " in the checkpoint. Give --resume alone; only these options may "
                        "change: " +
                        resume_runtime_options() +
                        " (and, to refine the render, a larger -s/--spp or a lower "
                        "--noise-threshold)");
    }
}

} // namespace candela
