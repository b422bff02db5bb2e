// Merging renders of one frame made with disjoint sample ranges: checks of their metadata, the
// sums.
#include "candela/render/merge.h"

#include "candela/render/adaptive.h"
#include "candela/render/exr_layout.h"
#include "candela/render/renderer.h"
#include "candela/render/setting_table.h"
#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>

namespace candela {

namespace {

/// What changes the image besides the render settings: the scene and its camera. Inputs must
/// agree on all of these and on the settings of merge_equal_keys() to be parts of one render.
const char* const kSceneDefiningKeys[] = {
    exr::kScene, exr::kLensRadius, exr::kFocalDistance, exr::kCamera,           exr::kCameraFile,
    exr::kEnv,   exr::kHfovDeg,    exr::kWorldToCamera, exr::kWorldToCameraStd,
};

/// Every key the inputs must agree on: the scene's, then the settings' in the table's order.
std::vector<const char*> image_defining_keys() {
    std::vector<const char*> keys(std::begin(kSceneDefiningKeys), std::end(kSceneDefiningKeys));
    for (const char* key : merge_equal_keys())
        keys.push_back(key);
    return keys;
}

/// An image-defining setting of an input, as text. A file written before the noise threshold
/// had a key of its own kept the relative sampler's threshold in adaptive_tol: such a file is
/// read as a newer one spells the same render (threshold in noise_threshold, adaptive_tol 0
/// unless cs184), so parts rendered before and after the change still merge.
std::string setting_text(const ImageData& img, const std::string& key) {
    const char* threshold = setting_key(Setting::NoiseThreshold);
    const char* tol = setting_key(Setting::AdaptiveTol);
    const bool legacy = img.attribute(threshold) == nullptr;
    if (!legacy || (key != tol && key != threshold)) return img.meta(key);
    // The sampler that reads a noise threshold is the one whose threshold went to adaptive_tol.
    const auto kind = find_enum(kAdaptiveKinds, img.meta(setting_key(Setting::Adaptive)));
    RenderSettings stored;
    if (kind) stored.adaptive = *kind;
    const bool relative = kind && make_pass_policy(stored)->reads_noise_threshold();
    if (key == threshold) return relative ? img.meta(tol) : "0";
    return relative ? "0" : img.meta(tol);
}

/// Attributes of the first input that the merged image keeps (besides the recomputed ones).
bool kept_attribute(const std::string& name) {
    if (name.rfind(exr::kKeyPrefix, 0) == 0) return true;
    return name == exr::kSoftware || name == exr::kWorldToCameraStd ||
           name == exr::kWorldToNdcStd || name == exr::kWorldToCamera || name == exr::kWorldToNdc;
}

enum class Role { Mean, Alpha, Depth, Variance, Samples };

Role role_of(const std::string& ch, const std::string& name) {
    if (ch == exr::kAlpha) return Role::Alpha;
    if (ch == exr::kDepth) return Role::Depth;
    if (ch == exr::kSamples) return Role::Samples;
    for (const char* v : exr::kVariance)
        if (ch == v) return Role::Variance;
    for (const auto* group : {&exr::kRgb, &exr::kAlbedo, &exr::kNormal})
        for (const char* m : *group)
            if (ch == m) return Role::Mean;
    throw Error(ErrorKind::Usage, SourceLoc{name},
                "cannot merge: unknown channel '" + ch + "' (not a candela render?)");
}

std::uint64_t parse_u64(const std::string& text, const std::string& key, const std::string& name) {
    std::size_t used = 0;
    unsigned long long v = 0;
    try {
        v = std::stoull(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (text.empty() || used != text.size() || text[0] == '-')
        throw Error(ErrorKind::Usage, SourceLoc{name},
                    "cannot merge: metadata " + key + " = '" + text +
                        "' is not a non-negative integer");
    return v;
}

/// A count stored as an int or double attribute (or, in older files, as text).
std::uint64_t count_attribute(const ImageData& img, const std::string& key,
                              const std::string& name) {
    const Attribute* a = img.attribute(key);
    if (!a) return 0;
    if (a->type == Attribute::Type::Double) {
        if (!(a->d >= 0.0) || a->d != std::floor(a->d))
            throw Error(ErrorKind::Usage, SourceLoc{name},
                        "cannot merge: metadata " + key + " is not a non-negative integer");
        return std::uint64_t(a->d);
    }
    return parse_u64(a->str(), key, name);
}

double seconds_attribute(const ImageData& img, const std::string& key) {
    const Attribute* a = img.attribute(key);
    if (!a) return 0.0;
    char* end = nullptr;
    const std::string text = a->str();
    double v = std::strtod(text.c_str(), &end);
    return (end && *end == '\0' && std::isfinite(v)) ? v : 0.0;
}

/// Data window of an input in display-window coordinates.
struct Window {
    int x0, y0, x1, y1; ///< [x0, x1) x [y0, y1)
    bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
    bool overlaps(const Window& o) const {
        return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1;
    }
};

/// Refuses inputs that are not parts of one render: another frame, other channels or another
/// image-defining setting than the first input's.
void check_same_render(const std::vector<ImageData>& images,
                       const std::vector<std::string>& names) {
    const ImageData& a = images[0];
    for (std::size_t i = 1; i < images.size(); ++i) {
        const ImageData& b = images[i];
        if (b.display_width() != a.display_width() || b.display_height() != a.display_height())
            throw Error(ErrorKind::Usage, SourceLoc{names[i]},
                        "cannot merge: its frame " + std::to_string(b.display_width()) + "x" +
                            std::to_string(b.display_height()) + " differs from " + names[0] +
                            " (" + std::to_string(a.display_width()) + "x" +
                            std::to_string(a.display_height()) + ")");
        if (b.channel_names != a.channel_names)
            throw Error(ErrorKind::Usage, SourceLoc{names[i]},
                        "cannot merge: its channels differ "
                        "from " +
                            names[0] + " (render both with the same --aov)");
        for (const char* key : image_defining_keys())
            if (setting_text(b, key) != setting_text(a, key))
                throw Error(ErrorKind::Usage, SourceLoc{names[i]},
                            std::string("cannot merge: ") + key + " is '" + setting_text(b, key) +
                                "' but '" + setting_text(a, key) + "' in " + names[0]);
    }
}

/// The sample range of each input. Inputs that share pixels must hold disjoint sample ranges of
/// them; inputs of disjoint regions (-p) are tiles of one frame and may use the same range.
std::vector<SampleRange> disjoint_sample_ranges(const std::vector<ImageData>& images,
                                                const std::vector<std::string>& names,
                                                const std::vector<Window>& windows) {
    const std::size_t count = images.size();
    std::vector<SampleRange> ranges;
    for (std::size_t i = 0; i < count; ++i)
        ranges.push_back(sample_range_of(images[i], names[i]));
    for (std::size_t i = 0; i < count; ++i)
        for (std::size_t j = i + 1; j < count; ++j) {
            if (!windows[i].overlaps(windows[j])) continue;
            const std::size_t p = ranges[i].first <= ranges[j].first ? i : j;
            const std::size_t q = p == i ? j : i;
            if (ranges[q].first < ranges[p].used_last)
                throw Error(ErrorKind::Usage, SourceLoc{names[q]},
                            "cannot merge: its sample indices [" + std::to_string(ranges[q].first) +
                                ", " + std::to_string(ranges[q].used_last) + ") overlap those " +
                                names[p] + " used [" + std::to_string(ranges[p].first) + ", " +
                                std::to_string(ranges[p].used_last) +
                                ") on shared pixels; render the parts with disjoint "
                                "--sample-offset ranges (under the default relative sampler a "
                                "pixel may take up to " +
                                std::to_string(kRelativeMaxOversampling) +
                                " x -s samples: offsets that far apart) or disjoint -p regions");
        }
    return ranges;
}

/// How each channel of the inputs merges.
struct ChannelLayout {
    std::vector<Role> roles;
    int samples = -1;         ///< the samples channel
    std::vector<int> mean_of; ///< for a variance channel, the radiance channel it belongs to
};

ChannelLayout channel_layout(const ImageData& a, const std::string& name) {
    ChannelLayout l;
    const int nc = a.channels();
    for (const auto& ch : a.channel_names)
        l.roles.push_back(role_of(ch, name));
    l.samples = a.channel_index(exr::kSamples);
    if (l.samples < 0)
        throw Error(ErrorKind::Usage, SourceLoc{name},
                    "cannot merge: no '" + std::string(exr::kSamples) +
                        "' channel (not a candela render?)");
    l.mean_of.assign(static_cast<std::size_t>(nc), -1);
    const std::size_t prefix = std::strlen(exr::kVariancePrefix);
    for (int c = 0; c < nc; ++c)
        if (l.roles[c] == Role::Variance) {
            l.mean_of[c] = a.channel_index(a.channel_names[c].substr(prefix));
            if (l.mean_of[c] < 0)
                throw Error(ErrorKind::Usage, SourceLoc{name},
                            "cannot merge: " + a.channel_names[c] + " without its colour");
        }
    return l;
}

/// The bounding box of the inputs' data windows: the merged data window.
Window bounding_box(const std::vector<Window>& windows) {
    Window box = windows[0];
    for (const Window& w : windows) {
        box.x0 = std::min(box.x0, w.x0);
        box.y0 = std::min(box.y0, w.y0);
        box.x1 = std::max(box.x1, w.x1);
        box.y1 = std::max(box.y1, w.y1);
    }
    return box;
}

/// Per-channel sums of one merged pixel, reused from pixel to pixel.
struct PixelSums {
    std::vector<double> s1, s2;
};

/// Merges the pixels `px[k]` of the inputs `inputs[k]` covering one pixel into `o`.
void merge_pixel(const std::vector<const float*>& px, const std::vector<std::size_t>& inputs,
                 const ChannelLayout& layout, const std::vector<std::string>& names,
                 PixelSums& sums, float* o) {
    const int nc = int(layout.roles.size());
    const std::vector<Role>& roles = layout.roles;
    std::vector<double>& s1 = sums.s1;
    std::vector<double>& s2 = sums.s2;
    std::fill(s1.begin(), s1.end(), 0.0);
    std::fill(s2.begin(), s2.end(), 0.0);
    double n_total = 0.0, hits_total = 0.0;
    float nearest = std::numeric_limits<float>::infinity();
    for (std::size_t k = 0; k < px.size(); ++k) {
        const float* p = px[k];
        const double n = p[layout.samples];
        if (!(n >= 0.0) || n != std::floor(n))
            throw Error(ErrorKind::Usage, SourceLoc{names[inputs[k]]},
                        "cannot merge: a '" + std::string(exr::kSamples) +
                            "' value is not a non-negative integer");
        n_total += n;
        if (n == 0.0) continue;
        for (int c = 0; c < nc; ++c) {
            switch (roles[c]) {
            case Role::Mean:
                s1[c] += double(p[c]) * n;
                break;
            case Role::Alpha:
                // A = hits / n was rounded once to float; n < 2^24 makes the product within
                // 1/2 of the integer hit count, so rounding recovers it.
                hits_total += std::nearbyint(double(p[c]) * n);
                break;
            case Role::Depth:
                nearest = std::min(nearest, p[c]);
                break;
            case Role::Variance: {
                // Sum of squares from the variance of the mean v = (S2 - S1^2/n)/(n-1)/n.
                const double m = p[layout.mean_of[c]];
                const double var = n >= 2.0 ? double(p[c]) * n * (n - 1.0) : 0.0;
                s2[c] += var + m * m * n;
                break;
            }
            case Role::Samples:
                break;
            }
        }
    }
    for (int c = 0; c < nc; ++c) {
        switch (roles[c]) {
        case Role::Mean:
            o[c] = n_total > 0.0 ? float(s1[c] / n_total) : 0.f;
            break;
        case Role::Alpha:
            // As Film::coverage computes it, so the value is bit-identical.
            o[c] = n_total > 0.0 ? float(hits_total / n_total) : 0.f;
            break;
        case Role::Depth:
            o[c] = nearest;
            break;
        case Role::Samples:
            o[c] = float(n_total);
            break;
        case Role::Variance: {
            if (n_total < 2.0) {
                o[c] = 0.f;
                break;
            }
            const double S1 = s1[layout.mean_of[c]];
            const double var = (s2[c] - S1 * S1 / n_total) / (n_total - 1.0);
            o[c] = float(std::max(0.0, var) / n_total);
            break;
        }
        }
    }
}

/// Fills the pixels of `out` (its data window `box`) from the inputs covering each of them.
void merge_pixels(const std::vector<ImageData>& images, const std::vector<std::string>& names,
                  const std::vector<Window>& windows, const ChannelLayout& layout,
                  const Window& box, ImageData& out) {
    const int nc = int(layout.roles.size());
    const std::size_t count = images.size();
    out.pixels.assign(std::size_t(out.width) * out.height * std::size_t(nc), 0.f);
    PixelSums sums{std::vector<double>(static_cast<std::size_t>(nc), 0.0),
                   std::vector<double>(static_cast<std::size_t>(nc), 0.0)};
    std::vector<std::size_t> covering;
    std::vector<const float*> px;
    covering.reserve(count);
    px.reserve(count);
    for (int gy = box.y0; gy < box.y1; ++gy)
        for (int gx = box.x0; gx < box.x1; ++gx) {
            float* o = &out.pixels[(std::size_t(gy - box.y0) * out.width + (gx - box.x0)) *
                                   std::size_t(nc)];
            covering.clear();
            px.clear();
            for (std::size_t i = 0; i < count; ++i)
                if (windows[i].contains(gx, gy)) {
                    const ImageData& img = images[i];
                    covering.push_back(i);
                    px.push_back(&img.pixels[(std::size_t(gy - img.y) * img.width + (gx - img.x)) *
                                             std::size_t(nc)]);
                }
            if (covering.empty()) {
                // Outside every input: no samples, nothing seen.
                for (int c = 0; c < nc; ++c)
                    o[c] = layout.roles[c] == Role::Depth ? std::numeric_limits<float>::infinity()
                                                          : 0.f;
                continue;
            }
            if (covering.size() == 1) {
                // One input: its values, bit for bit.
                std::copy(px[0], px[0] + nc, o);
                continue;
            }
            merge_pixel(px, covering, layout, names, sums, o);
        }
}

/// The merged image's attributes: the first input's, with the combined counts, the union of
/// the sample ranges and the list of merged ranges.
void merge_attributes(const std::vector<ImageData>& images, const std::vector<std::string>& names,
                      const std::vector<SampleRange>& ranges, ImageData& out) {
    for (const Attribute& kv : images[0].attributes)
        if (kept_attribute(kv.name) && kv.name != exr::kCommandLine &&
            kv.name != exr::kSessionCommands)
            out.attributes.push_back(kv);
    // What made each part, in an order that can be run.
    std::string commands;
    for (const ImageData& img : images)
        for (const char* key : {exr::kPartCommands, exr::kCommandLine}) {
            const std::string c = img.meta(key);
            if (!c.empty()) commands += (commands.empty() ? "" : "\n") + c;
        }
    if (!commands.empty()) out.set({exr::kPartCommands, commands});
    // The distinct sample ranges, sorted; candela:spp is the length of their nominal union, and
    // the merged ranges are the indices the parts used (an adaptive part may go past its -s).
    std::vector<SampleRange> distinct = ranges;
    std::sort(distinct.begin(), distinct.end(), [](const SampleRange& x, const SampleRange& y) {
        return x.first != y.first ? x.first < y.first : x.used_last < y.used_last;
    });
    distinct.erase(std::unique(distinct.begin(), distinct.end(),
                               [](const SampleRange& x, const SampleRange& y) {
                                   return x.first == y.first && x.last == y.last &&
                                          x.used_last == y.used_last;
                               }),
                   distinct.end());
    std::uint64_t spp = 0, covered_to = 0;
    std::string merged;
    for (std::size_t k = 0; k < distinct.size(); ++k) {
        const SampleRange& r = distinct[k];
        const std::uint64_t from = std::max(r.first, covered_to);
        if (r.last > from) spp += r.last - from;
        covered_to = std::max(covered_to, r.last);
        merged +=
            (k ? " [" : "[") + std::to_string(r.first) + "," + std::to_string(r.used_last) + ")";
    }
    std::uint64_t samples = 0, dropped = 0, sessions = 0;
    double seconds = 0.0;
    bool interrupted = false;
    for (std::size_t i = 0; i < images.size(); ++i) {
        const ImageData& img = images[i];
        samples += count_attribute(img, exr::kSamplesTaken, names[i]);
        dropped += count_attribute(img, exr::kNonfiniteDropped, names[i]);
        sessions += std::max<std::uint64_t>(1, count_attribute(img, exr::kSessions, names[i]));
        seconds += seconds_attribute(img, exr::kRenderSeconds);
        interrupted = interrupted || img.meta(exr::kInterrupted) == "1";
    }
    std::uint64_t used_last = 0;
    for (const SampleRange& r : ranges)
        used_last = std::max(used_last, r.used_last);
    out.set({setting_key(Setting::SampleOffset), int(distinct.front().first)});
    out.set({exr::kSampleEnd, int(used_last)});
    out.set({setting_key(Setting::Spp), int(spp)});
    out.set({exr::kSamplesTaken, double(samples)});
    out.set({exr::kNonfiniteDropped, double(dropped)});
    out.set({exr::kRenderSeconds, seconds});
    out.set({exr::kSessions, int(sessions)});
    out.set({exr::kInterrupted, interrupted ? 1 : 0});
    out.set({exr::kMergedRanges, merged});
    out.set({exr::kMergedInputs, int(images.size())});
}

} // namespace

SampleRange sample_range_of(const ImageData& img, const std::string& name) {
    const std::string offset_key = setting_key(Setting::SampleOffset);
    const std::string spp_key = setting_key(Setting::Spp);
    const std::string off = img.meta(offset_key), spp = img.meta(spp_key);
    if (off.empty() || spp.empty())
        throw Error(ErrorKind::Usage, SourceLoc{name},
                    "cannot merge: no " + offset_key + " / " + spp_key +
                        " metadata (not a candela render?)");
    SampleRange r;
    r.first = parse_u64(off, offset_key, name);
    r.last = r.first + parse_u64(spp, spp_key, name);
    const std::string end = img.meta(exr::kSampleEnd);
    r.used_last = end.empty() ? r.last : parse_u64(end, exr::kSampleEnd, name);
    if (r.used_last < r.first)
        throw Error(ErrorKind::Usage, SourceLoc{name},
                    std::string("cannot merge: metadata ") + exr::kSampleEnd + " lies before " +
                        offset_key);
    return r;
}

ImageData merge_images(const std::vector<ImageData>& images,
                       const std::vector<std::string>& names) {
    CANDELA_CHECK(images.size() == names.size(), "merge_images: one name per image expected");
    if (images.size() < 2) throw Error(ErrorKind::Usage, "give at least two renders to merge");
    std::vector<Window> windows;
    for (const ImageData& img : images)
        windows.push_back({img.x, img.y, img.x + img.width, img.y + img.height});
    check_same_render(images, names);
    const std::vector<SampleRange> ranges = disjoint_sample_ranges(images, names, windows);
    const ImageData& a = images[0];
    const ChannelLayout layout = channel_layout(a, names[0]);

    const Window box = bounding_box(windows);
    ImageData out;
    out.x = box.x0;
    out.y = box.y0;
    out.width = box.x1 - box.x0;
    out.height = box.y1 - box.y0;
    out.full_width = a.display_width();
    out.full_height = a.display_height();
    out.channel_names = a.channel_names;
    merge_pixels(images, names, windows, layout, box, out);
    merge_attributes(images, names, ranges, out);
    return out;
}

ImageData merge_exr_files(const std::vector<std::string>& inputs, const std::string& output,
                          const std::string& command_line) {
    std::vector<ImageData> images;
    images.reserve(inputs.size());
    for (const auto& path : inputs)
        images.push_back(read_image(path));
    ImageData out = merge_images(images, inputs);
    if (!command_line.empty()) out.set({exr::kCommandLine, command_line});
    write_exr(output, out);
    return out;
}

} // namespace candela
