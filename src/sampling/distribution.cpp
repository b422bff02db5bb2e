// Piecewise-constant 1-D and 2-D distributions for importance sampling tabulated functions.
#include "candela/sampling/distribution.h"

#include "candela/util/check.h"
#include "candela/util/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace candela {

namespace {
// Largest float below 1: the upper end of every [0, 1) result.
constexpr float kOneMinusEpsilon = 0.99999994f;
} // namespace

Distribution1D::Distribution1D(const std::vector<float>& f) {
    build(f.data(), f.size());
}

Distribution1D::Distribution1D(const float* f, std::size_t n) {
    build(f, n);
}

void Distribution1D::build(const float* f, std::size_t n) {
    CANDELA_CHECK(n > 0, "Distribution1D: empty function table");
    func_.assign(f, f + n);
    cdf_.assign(n + 1, 0.f);
    double sum = 0.0;
    std::vector<double> acc(n + 1, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        CANDELA_CHECK(std::isfinite(f[i]) && f[i] >= 0.f,
                      "Distribution1D: value " + std::to_string(f[i]) + " at index " +
                          std::to_string(i) + " is negative or not finite");
        sum += static_cast<double>(f[i]);
        acc[i + 1] = sum;
    }
    fallback_ = !(sum > 0.0);
    if (fallback_) {
        integral_ = 0.f;
        std::fill(func_.begin(), func_.end(), 0.f);
        for (std::size_t i = 0; i <= n; ++i)
            cdf_[i] = static_cast<float>(static_cast<double>(i) / static_cast<double>(n));
    } else {
        integral_ = static_cast<float>(sum / static_cast<double>(n));
        for (std::size_t i = 0; i <= n; ++i)
            cdf_[i] = static_cast<float>(acc[i] / sum);
    }
    cdf_[n] = 1.f;
}

std::size_t Distribution1D::find_bucket(float u) const {
    // First cdf entry > u, minus one: cdf_[i] <= u < cdf_[i+1], so bucket i has positive mass.
    auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, (it - cdf_.begin()) - 1));
    i = std::min(i, func_.size() - 1);
    // u >= 1 (caller error) or rounding: step back over empty buckets at the end.
    while (i > 0 && cdf_[i + 1] <= cdf_[i])
        --i;
    return i;
}

float Distribution1D::pmf(std::size_t i) const {
    if (i >= func_.size()) return 0.f;
    return cdf_[i + 1] - cdf_[i] > 0.f
               ? (fallback_ ? 1.f / static_cast<float>(func_.size())
                            : func_[i] / (integral_ * static_cast<float>(func_.size())))
               : 0.f;
}

float Distribution1D::pdf(float x) const {
    if (!(x >= 0.f && x <= 1.f)) return 0.f;
    std::size_t n = func_.size();
    auto i = std::min(n - 1, static_cast<std::size_t>(x * static_cast<float>(n)));
    return fallback_ ? 1.f : func_[i] / integral_;
}

float Distribution1D::sample_continuous(float u, float* pdf, std::size_t* offset) const {
    std::size_t i = find_bucket(u);
    float width = cdf_[i + 1] - cdf_[i];
    float du = width > 0.f ? (u - cdf_[i]) / width : 0.f;
    du = std::clamp(du, 0.f, 1.f);
    float x = (static_cast<float>(i) + du) / static_cast<float>(func_.size());
    x = std::min(x, kOneMinusEpsilon);
    if (pdf) *pdf = fallback_ ? 1.f : func_[i] / integral_;
    if (offset) *offset = i;
    return x;
}

std::size_t Distribution1D::sample_discrete(float u, float* pmf_out, float* u_remapped) const {
    std::size_t i = find_bucket(u);
    float width = cdf_[i + 1] - cdf_[i];
    if (pmf_out) *pmf_out = pmf(i);
    if (u_remapped)
        *u_remapped = std::clamp(width > 0.f ? (u - cdf_[i]) / width : 0.f, 0.f, kOneMinusEpsilon);
    return i;
}

Distribution2D::Distribution2D(const std::vector<float>& f, std::size_t nu, std::size_t nv)
    : nu_(nu), nv_(nv) {
    CANDELA_CHECK(nu > 0 && nv > 0 && f.size() == nu * nv,
                  "Distribution2D: table of " + std::to_string(f.size()) +
                      " values does not match " + std::to_string(nu) + " x " + std::to_string(nv));
    conditional_.reserve(nv);
    std::vector<float> row_integrals(nv);
    for (std::size_t v = 0; v < nv; ++v) {
        conditional_.emplace_back(f.data() + v * nu, nu);
        row_integrals[v] = conditional_.back().integral();
    }
    marginal_ = Distribution1D(row_integrals);
}

Vec2 Distribution2D::sample_continuous(Vec2 u, float* pdf_out) const {
    float pdf_v = 0.f, pdf_u = 0.f;
    std::size_t v = 0;
    float y = marginal_.sample_continuous(u.y, &pdf_v, &v);
    float x = conditional_[v].sample_continuous(u.x, &pdf_u);
    if (pdf_out) *pdf_out = pdf_v * pdf_u;
    return {x, y};
}

float Distribution2D::pdf(Vec2 p) const {
    if (!(p.x >= 0.f && p.x <= 1.f && p.y >= 0.f && p.y <= 1.f)) return 0.f;
    auto v = std::min(nv_ - 1, static_cast<std::size_t>(p.y * static_cast<float>(nv_)));
    return marginal_.pdf(p.y) * conditional_[v].pdf(p.x);
}

} // namespace candela
