// The render settings' table (render/setting_table.h): one row per setting.
#include "candela/render/setting_table.h"
#include "candela/render/adaptive.h"

#include "candela/util/check.h"

#include <fmt/format.h>

#include <type_traits>

namespace candela {

namespace {

/// What a change of a setting changes.
enum class Scope {
    Samples, ///< what a sample computes: a resume refuses it, merge's parts must agree on it
    Render,  ///< this render only (its samples, budget, traversal): a resume refuses it, merge's
             ///< parts may differ in it
    Runtime, ///< how or where the render runs, never its pixels: a resume may change it
};

/// What every row states besides its value's type.
struct RowHead {
    Setting id;
    const char* names; ///< CLI11's names; "" for a setting without a flag of its own
    const char* group;
    const char* exr_key;
    Scope scope;
    std::string help;
};

/// The long form of CLI11's `names` ("-s,--spp" -> "--spp").
std::string long_flag(const std::string& names) {
    const std::size_t at = names.find("--");
    return at == std::string::npos ? names : names.substr(at, names.find(',', at) - at);
}

SettingRow start_row(const RowHead& h, SettingType type) {
    SettingRow r;
    r.id = h.id;
    r.names = h.names;
    r.flag = long_flag(r.names);
    r.display = r.names;
    for (char& c : r.display)
        if (c == ',') c = '/';
    r.help = h.help;
    r.group = h.group;
    r.exr_key = h.exr_key;
    r.runtime = h.scope == Scope::Runtime;
    r.merge_equal = h.scope == Scope::Samples;
    r.type = type;
    return r;
}

/// A field of RenderSettings as an accessor for const and mutable settings alike.
template <typename M> auto member(M RenderSettings::*m) {
    return [m](auto& s) -> auto& {
        return s.*m;
    };
}

/// A number as text, exactly: integers in full, floating point with the digits that read back.
template <typename T> std::string number_text(T v) {
    if constexpr (std::is_floating_point_v<T>)
        return fmt::format("{:.9g}", double(v));
    else
        return std::to_string(v);
}

/// A number held in its field as it is typed and written to the EXR as `Stored` (seeds and
/// sample indices as int: kMaxIndex keeps them in range); an Int is checked against [min, max]
/// (max < min: only the minimum), an Index against max (0: checked elsewhere).
template <typename Stored, typename Get>
SettingRow number_row(const RowHead& h, SettingType type, Get get, long long min = 0,
                      long long max = -1) {
    SettingRow r = start_row(h, type);
    r.min = min;
    r.max = max;
    r.field = [get](RenderSettings& s) -> void* { return &get(s); };
    r.text = [get](const RenderSettings& s) { return number_text(get(s)); };
    if (h.exr_key)
        r.attribute = [get, key = h.exr_key](const RenderSettings& s) {
            return Attribute(key, Stored(get(s)));
        };
    return r;
}

/// A bool written to the EXR as 1 or 0, set to `flag_value` by its flag (when it has one).
template <typename Get>
SettingRow bool_row(const RowHead& h, SettingType type, Get get, bool flag_value) {
    SettingRow r = start_row(h, type);
    r.flag_value = flag_value;
    if (type == SettingType::Flag) r.field = [get](RenderSettings& s) -> void* { return &get(s); };
    r.text = [get](const RenderSettings& s) { return std::string(get(s) ? "1" : "0"); };
    if (h.exr_key)
        r.attribute = [get, key = h.exr_key](const RenderSettings& s) {
            return Attribute(key, get(s) ? 1 : 0);
        };
    return r;
}

/// An enum named by `table`; `type` is Custom when the command line settles it itself.
template <typename E, std::size_t N, typename Get>
SettingRow choice_row(const RowHead& h, Get get, const EnumTable<E, N>& table,
                      SettingType type = SettingType::Choice) {
    SettingRow r = start_row(h, type);
    r.choices = enum_names(table);
    r.text = [get, &table](const RenderSettings& s) {
        return std::string(enum_name(table, get(s)));
    };
    r.set_choice = [get, &table](RenderSettings& s, const std::string& name) {
        const std::optional<E> e = find_enum(table, name);
        if (e) get(s) = *e;
        return e.has_value();
    };
    if (h.exr_key)
        r.attribute = [get, &table, key = h.exr_key](const RenderSettings& s) {
            return Attribute(key, enum_name(table, get(s)));
        };
    return r;
}

/// A value the command line settles itself: its text, and the value its EXR attribute holds.
template <typename Text, typename Value>
SettingRow custom_row(const RowHead& h, Text text, Value value) {
    SettingRow r = start_row(h, SettingType::Custom);
    r.text = text;
    r.attribute = [value, key = h.exr_key](const RenderSettings& s) {
        return Attribute(key, value(s));
    };
    return r;
}

// --help's groups (src/app/help.cpp orders them).
constexpr const char* kSampling = "Sampling";
constexpr const char* kTransport = "Light transport";
constexpr const char* kCheckpoints = "Checkpoints and resuming";
constexpr const char* kTraversal = "Ray traversal";
constexpr const char* kRunning = "Running and diagnostics";
constexpr const char* kExr = "EXR";

/// The styles of the choice lists in --help.
constexpr ChoiceStyle kSemicolons = {"; ", "; "};
constexpr ChoiceStyle kCommas = {", ", ", "};

/// The course's flags (-s, -l, -t, -m, -o, -H) and the adaptive samplers' settings.
void add_course_and_adaptive_rows(std::vector<SettingRow>& t) {
    using S = const RenderSettings&;
    t.push_back(
        number_row<int>({Setting::Spp, "-s,--spp", kSampling, "candela:spp", Scope::Render,
                         "Samples per pixel. With the default adaptive sampling the cap: the "
                         "render spends at most what this many uniform samples per pixel cost; "
                         "with -a/cs184 the most one pixel takes"},
                        SettingType::Int, member(&RenderSettings::spp), 1, kMaxSpp));
    t.back().command_line_default = [](RenderSettings& s) { s.spp = kDefaultSpp; };
    t.push_back(number_row<int>({Setting::LightSamples, "-l,--light-samples", kSampling,
                                 "candela:light_samples", Scope::Samples,
                                 "Light samples per shading point (per non-delta light for "
                                 "--integrator=direct); also the -H budget"},
                                SettingType::Int, member(&RenderSettings::light_samples), 1,
                                kMaxLightSamples));
    t.push_back(number_row<int>({Setting::Threads, "-t,--threads", kRunning, nullptr,
                                 Scope::Runtime, "Worker threads; 0 = all cores"},
                                SettingType::Int, member(&RenderSettings::threads), 0,
                                kMaxThreads));
    t.push_back(
        number_row<int>({Setting::MaxDepth, "-m,--max-depth", kTransport, "candela:max_depth",
                         Scope::Samples, "Maximum number of scattering events per path"},
                        SettingType::Int, member(&RenderSettings::max_depth), 0, kMaxScatterDepth));
    t.push_back(bool_row({Setting::Accumulate, "-o,--accumulate", kTransport, "candela:accumulate",
                          Scope::Samples,
                          "CS184 -o (not an output file): 1 sums light scattered 0..m times; 0 "
                          "keeps only light scattered exactly m times"},
                         SettingType::Custom, member(&RenderSettings::accumulate), true));
    t.push_back(bool_row({Setting::Hemisphere, "-H,--hemisphere", kSampling, "candela:hemisphere",
                          Scope::Samples,
                          "Direct light by uniform hemisphere sampling instead of light "
                          "sampling"},
                         SettingType::Flag, member(&RenderSettings::hemisphere), true));
    t.push_back(choice_row({Setting::Adaptive, "--adaptive", kSampling, "candela:adaptive",
                            Scope::Samples, "Adaptive sampling: " + enum_choices(kAdaptiveKinds)},
                           member(&RenderSettings::adaptive), kAdaptiveKinds, SettingType::Custom));
    // -a BATCH TOLERANCE: the batch has its key, the tolerance is the cs184 sampler's
    // adaptive_tol or the relative sampler's noise threshold.
    t.push_back(custom_row(
        {Setting::AdaptiveBatch, "-a,--adaptive-sampling", kSampling, "candela:adaptive_batch",
         Scope::Samples, "Adaptive sampling: BATCH TOLERANCE (CS184: batch 32, tolerance 0.05)"},
        [](S s) { return number_text(s.adaptive_batch); },
        [](S s) { return make_pass_policy(s)->reads_batch() ? s.adaptive_batch : 0; }));
    t.back().command_line_default = [](RenderSettings& s) {
        s.adaptive_batch = kDefaultAdaptiveBatch;
    };
    // The relative sampler's threshold (0 with the other samplers). Files written before it had
    // a key of its own kept it in adaptive_tol; render/merge.cpp reads them so.
    t.push_back(custom_row(
        {Setting::NoiseThreshold, "--noise-threshold", kSampling, "candela:noise_threshold",
         Scope::Samples,
         "Relative sampler: stop when the estimated relative RMS error of the image falls to "
         "this (0 = spend the whole -s budget); -a's TOLERANCE replaces it"},
        [](S s) { return number_text(s.noise_threshold); },
        [](S s) {
            return make_pass_policy(s)->reads_noise_threshold() ? s.noise_threshold : 0.f;
        }));
    t.back().command_line_default = [](RenderSettings& s) {
        s.noise_threshold = kDefaultNoiseThreshold;
    };
    // -a's TOLERANCE under the cs184 sampler (0 with the others); no flag of its own.
    t.push_back(custom_row(
        {Setting::AdaptiveTol, "", kSampling, "candela:adaptive_tol", Scope::Samples, ""},
        [](S s) { return number_text(s.adaptive_tol); },
        [](S s) { return make_pass_policy(s)->reads_tolerance() ? s.adaptive_tol : 0.f; }));
}

/// The time budget and the traversal backends' settings.
void add_budget_and_traversal_rows(std::vector<SettingRow>& t) {
    t.push_back(number_row<double>(
        {Setting::TimeBudget, "--time-budget", kSampling, "candela:time_budget", Scope::Render,
         "Stop starting passes after SECONDS of rendering (whole passes; -s "
         "stays the maximum); 0 = no limit"},
        SettingType::Seconds, member(&RenderSettings::time_budget)));
    t.push_back(choice_row(
        {Setting::Accel, "--accel", kTraversal, "candela:accel", Scope::Render,
         "Ray traversal backend: " + enum_choices(kAccelKinds)},
        [](auto& s) -> auto& { return s.accel.kind; }, kAccelKinds));
    t.push_back(choice_row(
        {Setting::Triangle, "--triangle", kTraversal, "candela:triangle", Scope::Samples,
         "Triangle test of builtin/brute: " + enum_choices(kTriangleTests)},
        [](auto& s) -> auto& { return s.accel.triangle; }, kTriangleTests));
    t.push_back(bool_row(
        {Setting::EmbreeRobust, "--embree-robust", kTraversal, "candela:embree_robust",
         Scope::Render, "Embree robust (watertight) traversal"},
        SettingType::Flag, [](auto& s) -> auto& { return s.accel.embree_robust; }, true));
    t.push_back(choice_row(
        {Setting::EmbreeQuality, "--embree-quality", kTraversal, "candela:embree_quality",
         Scope::Render, "Embree build quality: " + enum_choices(kEmbreeQualities, kCommas)},
        [](auto& s) -> auto& { return s.accel.quality; }, kEmbreeQualities));
}

/// The sample sequence (seed, offset, sampler), light transport, the EXR and the run.
void add_sequence_transport_and_output_rows(std::vector<SettingRow>& t) {
    using S = const RenderSettings&;
    t.push_back(number_row<int>({Setting::Seed, "--seed", kSampling, "candela:seed", Scope::Samples,
                                 "Random seed (0 to 2^31-1)"},
                                SettingType::Index, member(&RenderSettings::seed), 0, kMaxIndex));
    // Its range depends on the sampler's reach, checked with the sampler's other options.
    t.push_back(number_row<int>({Setting::SampleOffset, "--sample-offset", kSampling,
                                 "candela:sample_offset", Scope::Render,
                                 "First sample index (renders of disjoint ranges merge exactly)"},
                                SettingType::Index, member(&RenderSettings::sample_offset), 0, 0));
    t.push_back(choice_row({Setting::Sampler, "--sampler", kSampling, "candela:sampler",
                            Scope::Samples, enum_choices(kSamplerKinds)},
                           member(&RenderSettings::sampler), kSamplerKinds));
    t.back().command_line_default = [](RenderSettings& s) { s.sampler = SamplerKind::Sobol; };
    t.push_back(choice_row({Setting::LightSampler, "--light-sampler", kTransport,
                            "candela:light_sampler", Scope::Samples,
                            "Light choice for next-event estimation: " +
                                enum_choices(kLightSamplerKinds, kSemicolons)},
                           member(&RenderSettings::light_sampler), kLightSamplerKinds));
    t.push_back(choice_row({Setting::Integrator, "--integrator", kTransport, "candela:integrator",
                            Scope::Samples, enum_choices(kIntegratorKinds)},
                           member(&RenderSettings::integrator), kIntegratorKinds));
    t.push_back(choice_row({Setting::LightPaths, "--light-paths", kTransport, "candela:light_paths",
                            Scope::Samples, enum_choices(kLightPaths, kSemicolons)},
                           member(&RenderSettings::light_paths), kLightPaths));
    t.push_back(bool_row({Setting::Mis, "--no-mis", kTransport, "candela:mis", Scope::Samples,
                          "Disable multiple importance sampling"},
                         SettingType::Flag, member(&RenderSettings::mis), false));
    t.push_back(number_row<int>({Setting::RrDepth, "--rr-depth", kTransport, "candela:rr_depth",
                                 Scope::Samples,
                                 "Russian roulette starts after this many scattering events"},
                                SettingType::Int, member(&RenderSettings::rr_min_depth), 0, -1));
    t.push_back(custom_row(
        {Setting::Aov, "--aov", kExr, "candela:aov", Scope::Render,
         "EXR auxiliary channels: all, none, or a list of albedo,normal,depth,variance"},
        [](S s) { return s.aovs.str(); }, [](S s) { return s.aovs.str(); }));
    t.push_back(number_row<int>({Setting::PassSpp, "--pass-spp", kCheckpoints, "candela:pass_spp",
                                 Scope::Render,
                                 "Samples per pixel per pass (the granularity of interrupts and "
                                 "checkpoints); 0 = automatic"},
                                SettingType::Int, member(&RenderSettings::pass_spp), 0, -1));
    t.push_back(choice_row({Setting::Progress, "--progress", kRunning, nullptr, Scope::Runtime,
                            enum_choices(kProgressModes)},
                           member(&RenderSettings::progress), kProgressModes));
}

std::vector<SettingRow> make_table() {
    std::vector<SettingRow> t;
    add_course_and_adaptive_rows(t);
    add_budget_and_traversal_rows(t);
    add_sequence_transport_and_output_rows(t);
    for (std::size_t i = 0; i < t.size(); ++i)
        CANDELA_CHECK(t[i].id == Setting(i), "setting table: row " + std::to_string(i) +
                                                 " is out of the order of enum Setting");
    CANDELA_CHECK(t.size() == std::size_t(Setting::Count), "setting table: a row is missing");
    return t;
}

} // namespace

const std::vector<SettingRow>& setting_table() {
    static const std::vector<SettingRow> table = make_table();
    return table;
}

const SettingRow& setting_row(Setting id) {
    return setting_table()[std::size_t(id)];
}

const char* setting_key(Setting id) {
    return setting_row(id).exr_key;
}

const SettingRow* find_setting(const std::string& flag) {
    if (flag.empty()) return nullptr;
    for (const SettingRow& r : setting_table())
        if (r.flag == flag) return &r;
    return nullptr;
}

RenderSettings command_line_settings() {
    RenderSettings s;
    for (const SettingRow& r : setting_table())
        if (r.command_line_default) r.command_line_default(s);
    return s;
}

std::vector<Attribute> setting_attributes(const RenderSettings& s) {
    std::vector<Attribute> out;
    for (const SettingRow& r : setting_table())
        if (r.exr_key) out.push_back(r.attribute(s));
    return out;
}

std::vector<const char*> merge_equal_keys() {
    std::vector<const char*> keys;
    for (const SettingRow& r : setting_table())
        if (r.exr_key && r.merge_equal) keys.push_back(r.exr_key);
    return keys;
}

} // namespace candela
