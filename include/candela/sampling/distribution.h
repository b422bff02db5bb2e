#pragma once
// Piecewise-constant distributions for importance sampling tabulated functions (light selection,
// environment maps). Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed., A.4 and 13.6.7.
#include "candela/math/vec.h"

#include <cstddef>
#include <vector>

namespace candela {

/// Piecewise-constant density on [0, 1) with n equal buckets, proportional to non-negative
/// values f[i]; equivalently a discrete distribution over n indices with pmf f[i] / sum(f).
/// If every value is zero (or the input is empty of mass) the distribution falls back to uniform
/// and `is_uniform_fallback()` is true, so sampling never fails.
class Distribution1D {
  public:
    Distribution1D() = default;
    /// Throws candela::Error when `f` is empty or holds a negative or non-finite value.
    explicit Distribution1D(const std::vector<float>& f);
    Distribution1D(const float* f, std::size_t n);

    std::size_t size() const { return func_.size(); }
    /// Integral of the (non-fallback) piecewise-constant function over [0, 1]: sum(f) / n.
    /// 0 for the uniform fallback.
    float integral() const { return integral_; }
    bool is_uniform_fallback() const { return fallback_; }
    /// The value of bucket i as given (0 for the fallback).
    float func(std::size_t i) const { return func_[i]; }

    /// Samples x in [0, 1) by inverting the CDF with u in [0, 1). Returns x; `pdf` receives the
    /// density of x w.r.t. Lebesgue measure on [0, 1], `offset` the bucket index.
    float sample_continuous(float u, float* pdf = nullptr, std::size_t* offset = nullptr) const;
    /// Samples a bucket index with u in [0, 1). `pmf` receives its probability; `u_remapped`
    /// receives u rescaled to [0, 1) within the chosen bucket (reusable as a fresh uniform).
    std::size_t sample_discrete(float u, float* pmf = nullptr, float* u_remapped = nullptr) const;
    /// Probability of choosing bucket i (0 outside the range).
    float pmf(std::size_t i) const;
    /// Density of x in [0, 1] (0 outside).
    float pdf(float x) const;

  private:
    void build(const float* f, std::size_t n);
    std::size_t find_bucket(float u) const;

    std::vector<float> func_;
    std::vector<float> cdf_; // size n + 1, cdf_[0] = 0, cdf_[n] = 1
    float integral_ = 0.f;
    bool fallback_ = false;
};

/// Piecewise-constant density on [0, 1)^2 with nu x nv cells, proportional to f[v * nu + u]
/// (row v, column u): a marginal distribution over rows and a conditional per row.
class Distribution2D {
  public:
    Distribution2D() = default;
    /// Throws candela::Error when nu or nv is 0, the size does not match, or a value is negative
    /// or non-finite.
    Distribution2D(const std::vector<float>& f, std::size_t nu, std::size_t nv);

    std::size_t nu() const { return nu_; }
    std::size_t nv() const { return nv_; }
    bool is_uniform_fallback() const { return marginal_.is_uniform_fallback(); }
    /// Integral of f over [0, 1]^2 (0 for the uniform fallback).
    float integral() const { return marginal_.integral(); }

    /// Samples (x, y) in [0, 1)^2 with u in [0, 1)^2; x runs along a row (u index), y across
    /// rows. `pdf` receives the density w.r.t. area on [0, 1]^2.
    Vec2 sample_continuous(Vec2 u, float* pdf = nullptr) const;
    /// Density of (x, y) w.r.t. area on [0, 1]^2 (0 outside).
    float pdf(Vec2 p) const;

  private:
    std::size_t nu_ = 0, nv_ = 0;
    std::vector<Distribution1D> conditional_;
    Distribution1D marginal_;
};

} // namespace candela
