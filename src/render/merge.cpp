#include "candela/render/merge.h"

#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace candela {

namespace {

/// Settings that change the image: inputs must agree on all of them to be parts of one render.
const char* const kImageDefiningKeys[] = {
    "candela:scene",     "candela:seed",          "candela:integrator", "candela:sampler",
    "candela:max_depth", "candela:light_samples", "candela:triangle",
};

enum class Role { Mean, Alpha, Variance, Samples };

Role role_of(const std::string& ch, const std::string& name) {
    if (ch == "A") return Role::Alpha;
    if (ch == "samples") return Role::Samples;
    if (ch == "variance.R" || ch == "variance.G" || ch == "variance.B") return Role::Variance;
    static const char* const means[] = {"R",        "G",   "B",   "albedo.R", "albedo.G",
                                        "albedo.B", "N.X", "N.Y", "N.Z",      "Z"};
    for (const char* m : means)
        if (ch == m) return Role::Mean;
    throw Error(ErrorKind::Usage, name + ": error: cannot merge: unknown channel '" + ch +
                                      "' (not a candela render?)");
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
        throw Error(ErrorKind::Usage, name + ": error: cannot merge: metadata " + key + " = '" +
                                          text + "' is not a non-negative integer");
    return v;
}

double parse_double_or_zero(const std::string& text) {
    char* end = nullptr;
    double v = std::strtod(text.c_str(), &end);
    return (end && *end == '\0' && std::isfinite(v)) ? v : 0.0;
}

std::string fmt_double(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

void set_meta(ImageData& img, const std::string& key, const std::string& value) {
    for (auto& kv : img.metadata)
        if (kv.first == key) {
            kv.second = value;
            return;
        }
    img.metadata.emplace_back(key, value);
}

} // namespace

SampleRange sample_range_of(const ImageData& img, const std::string& name) {
    const std::string off = img.meta("candela:sample_offset"), spp = img.meta("candela:spp");
    if (off.empty() || spp.empty())
        throw Error(ErrorKind::Usage, name + ": error: cannot merge: no candela:sample_offset / "
                                             "candela:spp metadata (not a candela render?)");
    SampleRange r;
    r.first = parse_u64(off, "candela:sample_offset", name);
    r.last = r.first + parse_u64(spp, "candela:spp", name);
    return r;
}

ImageData merge_images(const std::vector<ImageData>& images,
                       const std::vector<std::string>& names) {
    if (images.size() != names.size())
        throw Error(ErrorKind::Internal, "merge_images: one name per image expected");
    if (images.size() < 2)
        throw Error(ErrorKind::Usage, "candela merge: error: give at least two renders to merge");
    const ImageData& a = images[0];
    for (std::size_t i = 1; i < images.size(); ++i) {
        const ImageData& b = images[i];
        if (b.width != a.width || b.height != a.height)
            throw Error(ErrorKind::Usage,
                        names[i] + ": error: cannot merge: " + std::to_string(b.width) + "x" +
                            std::to_string(b.height) + " differs from " + names[0] + " (" +
                            std::to_string(a.width) + "x" + std::to_string(a.height) + ")");
        if (b.channel_names != a.channel_names)
            throw Error(ErrorKind::Usage, names[i] +
                                              ": error: cannot merge: its channels differ "
                                              "from " +
                                              names[0] + " (render both with the same --aov)");
        for (const char* key : kImageDefiningKeys)
            if (b.meta(key) != a.meta(key))
                throw Error(ErrorKind::Usage, names[i] + ": error: cannot merge: " + key + " is '" +
                                                  b.meta(key) + "' but '" + a.meta(key) + "' in " +
                                                  names[0]);
    }

    // Disjoint sample ranges: sort by first index, each must end before the next begins.
    std::vector<SampleRange> ranges;
    for (std::size_t i = 0; i < images.size(); ++i)
        ranges.push_back(sample_range_of(images[i], names[i]));
    std::vector<std::size_t> order(images.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y) { return ranges[x].first < ranges[y].first; });
    for (std::size_t k = 1; k < order.size(); ++k) {
        const SampleRange &p = ranges[order[k - 1]], &q = ranges[order[k]];
        if (q.first < p.last)
            throw Error(ErrorKind::Usage,
                        names[order[k]] + ": error: cannot merge: its samples [" +
                            std::to_string(q.first) + ", " + std::to_string(q.last) +
                            ") overlap those of " + names[order[k - 1]] + " [" +
                            std::to_string(p.first) + ", " + std::to_string(p.last) +
                            "); render the parts with disjoint --sample-offset ranges");
    }

    const int nc = a.channels();
    std::vector<Role> roles;
    for (const auto& ch : a.channel_names)
        roles.push_back(role_of(ch, names[0]));
    const int samples_c = a.channel_index("samples");
    if (samples_c < 0)
        throw Error(ErrorKind::Usage, names[0] + ": error: cannot merge: no 'samples' channel "
                                                 "(not a candela render?)");
    // For each variance channel, the radiance channel whose sums it needs.
    std::vector<int> mean_of(static_cast<std::size_t>(nc), -1);
    for (int c = 0; c < nc; ++c)
        if (roles[c] == Role::Variance) {
            mean_of[c] = a.channel_index(a.channel_names[c].substr(9)); // strip "variance."
            if (mean_of[c] < 0)
                throw Error(ErrorKind::Usage, names[0] + ": error: cannot merge: " +
                                                  a.channel_names[c] + " without its colour");
        }

    ImageData out;
    out.width = a.width;
    out.height = a.height;
    out.channel_names = a.channel_names;
    out.pixels.assign(a.pixels.size(), 0.f);
    const std::size_t pixels = std::size_t(a.width) * a.height;
    std::vector<double> s1(static_cast<std::size_t>(nc), 0.0), s2 = s1;
    for (std::size_t p = 0; p < pixels; ++p) {
        std::fill(s1.begin(), s1.end(), 0.0);
        std::fill(s2.begin(), s2.end(), 0.0);
        double n_total = 0.0;
        for (const ImageData& img : images) {
            const float* px = &img.pixels[p * std::size_t(nc)];
            const double n = px[samples_c];
            if (!(n >= 0.0) || n != std::floor(n))
                throw Error(ErrorKind::Usage, "candela merge: error: a 'samples' value is not a "
                                              "non-negative integer");
            n_total += n;
            if (n == 0.0) continue;
            for (int c = 0; c < nc; ++c) {
                if (roles[c] == Role::Mean) s1[c] += double(px[c]) * n;
                if (roles[c] == Role::Variance) {
                    // Sum of squares from the variance of the mean v = (S2 - S1^2/n)/(n-1)/n.
                    const double m = px[mean_of[c]];
                    const double var = n >= 2.0 ? double(px[c]) * n * (n - 1.0) : 0.0;
                    s2[c] += var + m * m * n;
                }
            }
        }
        float* o = &out.pixels[p * std::size_t(nc)];
        for (int c = 0; c < nc; ++c) {
            switch (roles[c]) {
            case Role::Mean:
                o[c] = n_total > 0.0 ? float(s1[c] / n_total) : 0.f;
                break;
            case Role::Alpha:
                o[c] = n_total > 0.0 ? 1.f : 0.f;
                break;
            case Role::Samples:
                o[c] = float(n_total);
                break;
            case Role::Variance: {
                if (n_total < 2.0) {
                    o[c] = 0.f;
                    break;
                }
                const double S1 = s1[mean_of[c]];
                const double var = (s2[c] - S1 * S1 / n_total) / (n_total - 1.0);
                o[c] = float(std::max(0.0, var) / n_total);
                break;
            }
            }
        }
    }

    // Metadata: the first input's candela keys, with the combined counts.
    for (const auto& kv : a.metadata)
        if (kv.first.rfind("candela:", 0) == 0) out.metadata.push_back(kv);
    std::uint64_t spp = 0, samples = 0, dropped = 0;
    double seconds = 0.0;
    bool interrupted = false;
    std::string merged;
    for (std::size_t k = 0; k < order.size(); ++k) {
        const ImageData& img = images[order[k]];
        const SampleRange& r = ranges[order[k]];
        spp += r.last - r.first;
        if (!img.meta("candela:samples").empty())
            samples += parse_u64(img.meta("candela:samples"), "candela:samples", names[order[k]]);
        if (!img.meta("candela:nonfinite_dropped").empty())
            dropped += parse_u64(img.meta("candela:nonfinite_dropped"), "candela:nonfinite_dropped",
                                 names[order[k]]);
        seconds += parse_double_or_zero(img.meta("candela:render_seconds"));
        interrupted = interrupted || img.meta("candela:interrupted") == "1";
        merged += (k ? " [" : "[") + std::to_string(r.first) + "," + std::to_string(r.last) + ")";
    }
    set_meta(out, "candela:sample_offset", std::to_string(ranges[order[0]].first));
    set_meta(out, "candela:spp", std::to_string(spp));
    set_meta(out, "candela:samples", std::to_string(samples));
    set_meta(out, "candela:nonfinite_dropped", std::to_string(dropped));
    set_meta(out, "candela:render_seconds", fmt_double(seconds));
    set_meta(out, "candela:interrupted", interrupted ? "1" : "0");
    set_meta(out, "candela:merged_ranges", merged);
    return out;
}

ImageData merge_exr_files(const std::vector<std::string>& inputs, const std::string& output) {
    std::vector<ImageData> images;
    images.reserve(inputs.size());
    for (const auto& path : inputs)
        images.push_back(read_image(path));
    ImageData out = merge_images(images, inputs);
    write_exr(output, out);
    return out;
}

} // namespace candela
