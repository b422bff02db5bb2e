#pragma once
// Every render setting declared once: one row per setting names its command-line flag, the
// RenderSettings field it fills, the command line's default, its EXR key, whether a resumed
// render may change it and whether `merge` requires the parts to agree on it, and how it reads
// as text. The option declarations, the range checks, the EXR attributes, the resume check, the
// merge check and --help's groups are all made from these rows (docs/development.md "Render
// settings"). The renderer reads the plain RenderSettings the rows fill, never the table.
#include "candela/io/image_io.h"
#include "candela/render/settings.h"

#include <climits>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace candela {

/// The render settings, in the table's order. (--help lists the options in the order
/// src/app/render/options.cpp declares them, the checkpoint in option_specs()' order.)
enum class Setting {
    Spp,
    LightSamples,
    Threads,
    MaxDepth,
    Accumulate,
    Hemisphere,
    Adaptive,
    AdaptiveBatch,
    NoiseThreshold,
    AdaptiveTol,
    TimeBudget,
    Accel,
    Triangle,
    EmbreeRobust,
    EmbreeQuality,
    Seed,
    SampleOffset,
    Sampler,
    LightSampler,
    Integrator,
    LightPaths,
    Mis,
    RrDepth,
    Aov,
    PassSpp,
    Progress,
    Count
};

/// The command line's defaults for a render that names no sampling flags: Owen-scrambled Sobol
/// points and the relative adaptive sampler, stopping at an estimated relative RMS error of 2 %
/// of the image or after the cost of kDefaultSpp uniform samples per pixel, whichever comes
/// first (docs/performance.md measures the choice). The rows of -s, --sampler and
/// --noise-threshold carry them; RenderSettings' own initializers are the plain engine values
/// the tests build on.
constexpr float kDefaultNoiseThreshold = 0.02f;
constexpr int kDefaultSpp = 1024;
/// First (uniform) batch and later passes of the default adaptive sampler, in samples per pixel.
constexpr int kDefaultAdaptiveBatch = 16;

/// Largest accepted -t.
constexpr int kMaxThreads = 4096;
/// Largest accepted -m.
constexpr int kMaxScatterDepth = 1 << 16;
/// Largest accepted -l.
constexpr int kMaxLightSamples = 65536;
/// Seeds and sample indices are written to the EXR as int attributes (typed,
/// docs/exr-metadata.md), so they stay below 2^31.
constexpr long long kMaxIndex = INT_MAX;

/// How a setting's value is held and given on the command line.
enum class SettingType {
    Int,     ///< int field, `-x N`
    Index,   ///< std::uint64_t seed or sample index, given as a whole number >= 0
    Seconds, ///< double field, `--x SECONDS`
    Flag,    ///< bool field, a flag without a value that sets it to `flag_value`
    Choice,  ///< enum field with an EnumTable of names
    Custom,  ///< parsed by the command line's own code (its value passes through RenderArgs)
};

/// One render setting.
struct SettingRow {
    Setting id;
    std::string names;   ///< CLI11's names, e.g. "-s,--spp"
    std::string flag;    ///< the long form, e.g. "--spp" (what RenderArgs::given records)
    std::string display; ///< as messages name it, e.g. "-s/--spp"
    std::string help;    ///< --help's text (for a choice, with the choices listed)
    const char* group;   ///< --help's group heading
    const char* exr_key; ///< its key in the EXR metadata; nullptr: not written
    /// May differ on --resume: it changes how or where the render runs, never its pixels.
    bool runtime;
    /// `merge` refuses parts that differ in it (it changes what a sample computes).
    bool merge_equal;
    SettingType type;
    /// Int: the accepted range, checked after parsing; with max < min only the minimum.
    /// Index: max is the largest accepted value (0: checked elsewhere).
    long long min = 0, max = -1;
    bool flag_value = true;           ///< Flag: the value the flag sets
    std::vector<std::string> choices; ///< Choice: the names, in the table's order
    /// Int, Index, Seconds, Flag: the field, as int*, std::uint64_t*, double*, bool*; empty
    /// for Choice and Custom rows.
    std::function<void*(RenderSettings&)> field;
    /// The value as text: numbers exactly, a choice by its name, a flag as 1 or 0.
    std::function<std::string(const RenderSettings&)> text;
    /// Choice: sets the value named, or returns false for a name that is none of the choices.
    std::function<bool(RenderSettings&, const std::string&)> set_choice;
    /// The EXR attribute (exr_key set): its value in the file.
    std::function<Attribute(const RenderSettings&)> attribute;
    /// The command line's default where it differs from RenderSettings' initializer; empty
    /// otherwise.
    std::function<void(RenderSettings&)> command_line_default;
};

/// Every render setting, one row each, indexed by Setting.
const std::vector<SettingRow>& setting_table();
/// The row of `id`.
const SettingRow& setting_row(Setting id);
/// The EXR key of `id` (nullptr for a setting the EXR does not record).
const char* setting_key(Setting id);
/// The row whose long flag is `flag` ("--spp"); nullptr when no setting has it.
const SettingRow* find_setting(const std::string& flag);

/// The settings a render on the command line starts from: RenderSettings' initializers with
/// each row's command-line default applied (the kDefaultSpp budget, the Owen-scrambled Sobol
/// sampler, the relative sampler's threshold and batch).
RenderSettings command_line_settings();

/// The EXR attributes of every setting that has a key.
std::vector<Attribute> setting_attributes(const RenderSettings& s);

/// The EXR keys of the settings whose parts `merge` requires to agree, in the table's order.
std::vector<const char*> merge_equal_keys();

} // namespace candela
