#pragma once
// The film stores per-pixel *sums*, never averages: films of the same frame rendered with
// disjoint sample ranges merge by adding, which adaptive sampling, checkpoints and distributed
// rendering rely on. Means and variances are derived when the image is written. The pixel filter
// is a one-pixel box: a sample counts for the pixel it lands in and for no other, so every
// pixel's estimate is its own samples' mean (docs/rendering.md, "Film and output").
//
// Coverage and depth: a sample whose camera ray hits a surface counts as a hit; alpha is the
// pixel's fraction of hits, and depth is the *nearest* hit distance over the pixel's samples
// (+inf where none hit). A minimum, unlike a float sum, is the same in any order, so depth
// merges, resumes and reduces across processes exactly.
#include "candela/math/vec.h"
#include "candela/util/check.h"

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace candela {

/// Which auxiliary channels a film accumulates (and the EXR carries). Unrequested channels cost
/// neither memory nor time.
struct AovSet {
    bool albedo = false;   ///< first-hit albedo
    bool normal = false;   ///< first-hit shading normal
    bool depth = false;    ///< first-hit distance along the camera ray
    bool variance = false; ///< per-pixel variance of the mean (needs sums of squares)
    static AovSet all() { return {true, true, true, true}; }
    static AovSet parse(const std::string& list); ///< "all", "none" or "albedo,normal,..."
    std::string str() const;
};

/// One camera sample's contribution to its pixel.
struct FilmSample {
    Rgb L;
    Rgb albedo;
    Vec3 normal;
    float depth = 0.f;
    bool hit = false; ///< the camera ray hit a surface (alpha is the fraction of hits)
};

class Film {
  public:
    Film() = default;
    /// A film of width x height pixels; `lum_stats` adds luminance sums for adaptive sampling.
    Film(int width, int height, AovSet aovs, bool lum_stats);

    int width() const { return width_; }
    int height() const { return height_; }
    const AovSet& aovs() const { return aovs_; }
    std::size_t pixel_count() const { return count_.size(); }

    /// Adds one finite sample to pixel (x, y), row 0 at the top. Not thread-safe for the same
    /// pixel; the renderer gives each pixel to one thread at a time.
    void add(int x, int y, const FilmSample& s) {
        const std::size_t i = index(x, y);
        PixelSums p = load(i);
        accumulate(p, s);
        store(i, p);
    }
    /// Adds `count` samples to pixel (x, y) in order, sample(k) giving the k-th: the sums of
    /// add() for each finite one and of add_dropped() for each whose radiance is not finite,
    /// bit for bit, with the pixel's running sums kept in registers from sample to sample
    /// instead of stored and loaded back. Returns how many were dropped.
    template <typename SampleAt>
    std::uint32_t add_samples(int x, int y, int count, const SampleAt& sample) {
        const std::size_t i = index(x, y);
        PixelSums p = load(i);
        const std::uint32_t dropped_before = p.dropped;
        for (int k = 0; k < count; ++k) {
            const FilmSample& s = sample(k);
            if (is_finite(s.L))
                accumulate(p, s);
            else
                ++p.dropped;
        }
        store(i, p);
        return p.dropped - dropped_before;
    }
    /// Counts a sample whose radiance was not finite: it is dropped, but the attempt is counted
    /// so the sample index sequence stays the same.
    void add_dropped(int x, int y) { ++dropped_[index(x, y)]; }

    /// Adds another film of the same size and channels (disjoint sample ranges).
    void merge(const Film& other);

    std::uint32_t count(int x, int y) const { return count_[index(x, y)]; }
    std::uint32_t dropped(int x, int y) const { return dropped_[index(x, y)]; }
    /// Samples whose camera ray hit a surface.
    std::uint32_t hits(int x, int y) const { return hits_[index(x, y)]; }
    /// Fraction of the pixel's finite samples that hit a surface (0 without samples).
    float coverage(int x, int y) const;
    std::uint64_t total_dropped() const;
    std::uint64_t total_samples() const;
    Rgb mean(int x, int y) const;
    /// Variance of the pixel mean, per channel (0 with fewer than two samples).
    Rgb variance_of_mean(int x, int y) const;
    /// Luminance mean and sample variance (needs lum_stats); n-1 denominator.
    void lum_stats(int x, int y, double& mean, double& var, std::uint32_t& n) const;
    Rgb mean_albedo(int x, int y) const;
    Vec3 mean_normal(int x, int y) const;
    /// Nearest hit distance along the camera rays over the pixel's samples; +inf where no
    /// sample hit a surface.
    float nearest_depth(int x, int y) const;

    /// The raw sums, for tests that compare films exactly.
    const std::vector<double>& raw_sum() const { return sum_; }

    /// How two films' values of one array combine: added, or the smaller kept (depth).
    enum class Combine { Sum, Min };
    /// Calls f(v, combine) on every per-pixel array (std::vector<double>,
    /// std::vector<std::uint32_t> or std::vector<float>; empty when the channel is off), always
    /// in the same order, so two films of the same size and channels can be reduced
    /// element-wise across processes.
    template <typename F> void for_each_sum(F&& f) {
        f(sum_, Combine::Sum);
        f(sumsq_, Combine::Sum);
        f(lum_, Combine::Sum);
        f(count_, Combine::Sum);
        f(dropped_, Combine::Sum);
        f(hits_, Combine::Sum);
        f(albedo_, Combine::Sum);
        f(normal_, Combine::Sum);
        f(depth_, Combine::Min);
    }

    /// Binary serialisation of every sum (checkpoints). read() throws Error(Io) on a short or
    /// inconsistent stream.
    void write(std::ostream& out) const;
    static Film read(std::istream& in);

  private:
    /// One pixel's sums, as add() updates them (the channels that are off stay unused).
    struct PixelSums {
        double sum[3], sumsq[3], lum[2];
        float albedo[3], normal[3], depth;
        std::uint32_t count, dropped, hits;
    };
    PixelSums load(std::size_t i) const {
        PixelSums p{};
        for (int c = 0; c < 3; ++c) {
            p.sum[c] = sum_[3 * i + c];
            if (aovs_.variance) p.sumsq[c] = sumsq_[3 * i + c];
            if (aovs_.albedo) p.albedo[c] = albedo_[3 * i + c];
            if (aovs_.normal) p.normal[c] = normal_[3 * i + c];
        }
        if (lum_stats_) {
            p.lum[0] = lum_[2 * i];
            p.lum[1] = lum_[2 * i + 1];
        }
        if (aovs_.depth) p.depth = depth_[i];
        p.count = count_[i];
        p.dropped = dropped_[i];
        p.hits = hits_[i];
        return p;
    }
    void store(std::size_t i, const PixelSums& p) {
        for (int c = 0; c < 3; ++c) {
            sum_[3 * i + c] = p.sum[c];
            if (aovs_.variance) sumsq_[3 * i + c] = p.sumsq[c];
            if (aovs_.albedo) albedo_[3 * i + c] = p.albedo[c];
            if (aovs_.normal) normal_[3 * i + c] = p.normal[c];
        }
        if (lum_stats_) {
            lum_[2 * i] = p.lum[0];
            lum_[2 * i + 1] = p.lum[1];
        }
        if (aovs_.depth) depth_[i] = p.depth;
        count_[i] = p.count;
        dropped_[i] = p.dropped;
        hits_[i] = p.hits;
    }
    /// One sample added to a pixel's sums: radiance in double, its squares, luminance moments,
    /// the first-hit channels, the nearest depth.
    void accumulate(PixelSums& p, const FilmSample& s) const {
        for (int c = 0; c < 3; ++c)
            p.sum[c] += s.L[c];
        ++p.count;
        if (aovs_.variance)
            for (int c = 0; c < 3; ++c)
                p.sumsq[c] += double(s.L[c]) * s.L[c];
        if (lum_stats_) {
            const double l = luminance(s.L);
            p.lum[0] += l;
            p.lum[1] += l * l;
        }
        if (aovs_.albedo)
            for (int c = 0; c < 3; ++c)
                p.albedo[c] += s.albedo[c];
        if (aovs_.normal)
            for (int c = 0; c < 3; ++c)
                p.normal[c] += s.normal[c];
        if (s.hit) {
            ++p.hits;
            if (aovs_.depth && s.depth < p.depth) p.depth = s.depth;
        }
    }

    std::size_t index(int x, int y) const {
        CANDELA_DCHECK(x >= 0 && x < width_ && y >= 0 && y < height_,
                       "film pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                           ") outside the image");
        return std::size_t(y) * width_ + x;
    }

    int width_ = 0, height_ = 0;
    AovSet aovs_;
    bool lum_stats_ = false;
    std::vector<double> sum_, sumsq_, lum_;
    std::vector<std::uint32_t> count_, dropped_, hits_;
    std::vector<float> albedo_, normal_, depth_;
};

} // namespace candela
