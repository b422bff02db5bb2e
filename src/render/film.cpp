// The film: per-pixel sums of radiance and auxiliary channels, merged by adding, stored in
// checkpoints.
#include "candela/render/film.h"
#include "candela/util/error.h"

#include <algorithm>
#include <istream>
#include <limits>
#include <ostream>
#include <sstream>

namespace candela {

AovSet AovSet::parse(const std::string& list) {
    AovSet a;
    if (list == "all") return all();
    if (list == "none" || list.empty()) return a;
    std::stringstream ss(list);
    std::string item;
    while (std::getline(ss, item, ',')) {
        if (item == "albedo")
            a.albedo = true;
        else if (item == "normal")
            a.normal = true;
        else if (item == "depth")
            a.depth = true;
        else if (item == "variance")
            a.variance = true;
        else
            throw Error(ErrorKind::Usage, "--aov: unknown channel '" + item +
                                              "' (expected albedo, normal, depth, variance, "
                                              "all or none)");
    }
    return a;
}

std::string AovSet::str() const {
    std::string s;
    auto add = [&](bool on, const char* n) {
        if (!on) return;
        if (!s.empty()) s += ",";
        s += n;
    };
    add(albedo, "albedo");
    add(normal, "normal");
    add(depth, "depth");
    add(variance, "variance");
    return s.empty() ? "none" : s;
}

Film::Film(int width, int height, AovSet aovs, bool lum_stats)
    : width_(width), height_(height), aovs_(aovs), lum_stats_(lum_stats) {
    std::size_t n = std::size_t(width) * std::size_t(height);
    sum_.assign(3 * n, 0.0);
    count_.assign(n, 0);
    dropped_.assign(n, 0);
    hits_.assign(n, 0);
    if (aovs.variance) sumsq_.assign(3 * n, 0.0);
    if (lum_stats) lum_.assign(2 * n, 0.0);
    if (aovs.albedo) albedo_.assign(3 * n, 0.f);
    if (aovs.normal) normal_.assign(3 * n, 0.f);
    if (aovs.depth) depth_.assign(n, std::numeric_limits<float>::infinity());
}

void Film::merge(const Film& o) {
    if (o.width_ != width_ || o.height_ != height_ || o.lum_stats_ != lum_stats_ ||
        o.aovs_.str() != aovs_.str())
        throw Error(ErrorKind::Usage, "cannot merge films of different size or channels");
    auto addv = [](auto& a, const auto& b) {
        for (std::size_t i = 0; i < a.size(); ++i)
            a[i] += b[i];
    };
    addv(sum_, o.sum_);
    addv(sumsq_, o.sumsq_);
    addv(lum_, o.lum_);
    addv(count_, o.count_);
    addv(dropped_, o.dropped_);
    addv(hits_, o.hits_);
    addv(albedo_, o.albedo_);
    addv(normal_, o.normal_);
    for (std::size_t i = 0; i < depth_.size(); ++i)
        depth_[i] = std::min(depth_[i], o.depth_[i]);
}

std::uint64_t Film::total_dropped() const {
    std::uint64_t n = 0;
    for (auto c : dropped_)
        n += c;
    return n;
}

std::uint64_t Film::total_samples() const {
    std::uint64_t n = 0;
    for (auto c : count_)
        n += c;
    return n;
}

Rgb Film::mean(int x, int y) const {
    std::size_t i = index(x, y);
    if (count_[i] == 0) return Rgb(0.f);
    double inv = 1.0 / count_[i];
    return Rgb(float(sum_[3 * i] * inv), float(sum_[3 * i + 1] * inv),
               float(sum_[3 * i + 2] * inv));
}

namespace {
constexpr double kLargestFloat = double(std::numeric_limits<float>::max());
} // namespace

Rgb Film::variance_of_mean(int x, int y) const {
    std::size_t i = index(x, y);
    double n = count_[i];
    if (n < 2 || sumsq_.empty()) return Rgb(0.f);
    Rgb v;
    for (int c = 0; c < 3; ++c) {
        double s1 = sum_[3 * i + c], s2 = sumsq_[3 * i + c];
        double var = (s2 - s1 * s1 / n) / (n - 1.0);
        // The sums are doubles; only the float written can overflow, for radiance above about
        // 1.8e19 (the square root of the largest float). Such a variance is written as the
        // largest float, a finite lower bound, rather than +inf, which tools turn into NaN.
        v[c] = float(std::min(std::max(0.0, var) / n, kLargestFloat));
    }
    return v;
}

void Film::lum_stats(int x, int y, double& mean, double& var, std::uint32_t& n) const {
    std::size_t i = index(x, y);
    n = count_[i];
    mean = var = 0.0;
    if (n == 0 || lum_.empty()) return;
    double s1 = lum_[2 * i], s2 = lum_[2 * i + 1];
    mean = s1 / n;
    var = n > 1 ? std::max(0.0, (s2 - s1 * s1 / n) / (n - 1.0)) : 0.0;
}

Rgb Film::mean_albedo(int x, int y) const {
    std::size_t i = index(x, y);
    if (count_[i] == 0 || albedo_.empty()) return Rgb(0.f);
    return Rgb(albedo_[3 * i], albedo_[3 * i + 1], albedo_[3 * i + 2]) / float(count_[i]);
}

Vec3 Film::mean_normal(int x, int y) const {
    std::size_t i = index(x, y);
    if (count_[i] == 0 || normal_.empty()) return Vec3(0.f);
    return Vec3(normal_[3 * i], normal_[3 * i + 1], normal_[3 * i + 2]) / float(count_[i]);
}

float Film::coverage(int x, int y) const {
    std::size_t i = index(x, y);
    if (count_[i] == 0) return 0.f;
    return float(double(hits_[i]) / double(count_[i]));
}

float Film::nearest_depth(int x, int y) const {
    std::size_t i = index(x, y);
    if (depth_.empty()) return std::numeric_limits<float>::infinity();
    return depth_[i];
}

namespace {

template <typename T> void put(std::ostream& out, const T& v) {
    out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <typename T> void put_vec(std::ostream& out, const std::vector<T>& v) {
    put(out, std::uint64_t(v.size()));
    out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}
template <typename T> void get(std::istream& in, T& v) {
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v))
        throw Error(ErrorKind::Io, "film data is truncated");
}
template <typename T> void get_vec(std::istream& in, std::vector<T>& v, std::size_t expected) {
    std::uint64_t n = 0;
    get(in, n);
    if (n != expected) throw Error(ErrorKind::Io, "film data has an inconsistent size");
    v.resize(n);
    if (!in.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * sizeof(T))))
        throw Error(ErrorKind::Io, "film data is truncated");
}

} // namespace

void Film::write(std::ostream& out) const {
    put(out, std::int32_t(width_));
    put(out, std::int32_t(height_));
    std::uint8_t flags =
        std::uint8_t((aovs_.albedo ? 1 : 0) | (aovs_.normal ? 2 : 0) | (aovs_.depth ? 4 : 0) |
                     (aovs_.variance ? 8 : 0) | (lum_stats_ ? 16 : 0));
    put(out, flags);
    put_vec(out, sum_);
    put_vec(out, sumsq_);
    put_vec(out, lum_);
    put_vec(out, count_);
    put_vec(out, dropped_);
    put_vec(out, hits_);
    put_vec(out, albedo_);
    put_vec(out, normal_);
    put_vec(out, depth_);
}

Film Film::read(std::istream& in) {
    std::int32_t w = 0, h = 0;
    std::uint8_t flags = 0;
    get(in, w);
    get(in, h);
    get(in, flags);
    // The same bound as the command line's pixel limit, so a corrupt header cannot make us
    // allocate an absurd film.
    if (w < 1 || h < 1 || (long long)w * h > (1ll << 28))
        throw Error(ErrorKind::Io, "film data has an invalid size");
    AovSet a;
    a.albedo = flags & 1;
    a.normal = flags & 2;
    a.depth = flags & 4;
    a.variance = flags & 8;
    Film f(w, h, a, (flags & 16) != 0);
    const std::size_t n = std::size_t(w) * std::size_t(h);
    get_vec(in, f.sum_, 3 * n);
    get_vec(in, f.sumsq_, a.variance ? 3 * n : 0);
    get_vec(in, f.lum_, (flags & 16) ? 2 * n : 0);
    get_vec(in, f.count_, n);
    get_vec(in, f.dropped_, n);
    get_vec(in, f.hits_, n);
    get_vec(in, f.albedo_, a.albedo ? 3 * n : 0);
    get_vec(in, f.normal_, a.normal ? 3 * n : 0);
    get_vec(in, f.depth_, a.depth ? n : 0);
    return f;
}

} // namespace candela
