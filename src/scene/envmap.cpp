// The latitude-longitude environment map: lookup by direction and importance sampling of its
// texels.
#include "candela/scene/envmap.h"

#include "candela/util/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace candela {

namespace {

inline int wrap(int i, int n) {
    // The lookups are at most one period off (a neighbour across the seam): no division then.
    if (i < 0)
        i += n;
    else if (i >= n)
        i -= n;
    if (i < 0 || i >= n) {
        i %= n;
        if (i < 0) i += n;
    }
    return i;
}

} // namespace

EnvMap::EnvMap(int width, int height, std::vector<Rgb> texels, std::string name)
    : w_(width), h_(height), texels_(std::move(texels)) {
    if (w_ <= 0 || h_ <= 0 ||
        texels_.size() != static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_)) {
        std::ostringstream msg;
        msg << "environment map of " << w_ << "x" << h_ << " texels holds " << texels_.size()
            << " values";
        throw Error(ErrorKind::Io, SourceLoc{name}, msg.str());
    }
    for (int j = 0; j < h_; ++j)
        for (int i = 0; i < w_; ++i) {
            const Rgb& c = texel(i, j);
            if (!is_finite(c) || c.x < 0.f || c.y < 0.f || c.z < 0.f) {
                std::ostringstream msg;
                msg << "environment map pixel (" << i << ", " << j
                    << ") is negative or not finite: (" << c.x << ", " << c.y << ", " << c.z << ")";
                throw Error(ErrorKind::Io, SourceLoc{name}, msg.str());
            }
        }
    build_sampling_table();
}

void EnvMap::build_sampling_table() {
    const std::size_t n = static_cast<std::size_t>(w_) * h_;
    std::vector<float> lum(n);
    for (std::size_t k = 0; k < n; ++k)
        lum[k] = luminance(texels_[k]);

    // Weight of texel (i, j): the largest luminance the bilinear lookup can reach from inside
    // it (its 3x3 neighbourhood, wrapped in x and clamped in y) times sin(theta) at the row
    // centre. Luminance integral and its order-2 harmonics (irradiance_sh): texels piecewise
    // constant over their solid angles, each harmonic taken at the texel's centre.
    std::vector<double> weight(n);
    double lum_integral = 0.0;
    std::array<double, 9> sh{}; // the luminance's projection on sh9_basis()
    const double dphi = 2.0 * kPiD / w_;
    std::vector<float> col_cos(static_cast<std::size_t>(w_)), col_sin(col_cos.size());
    for (int i = 0; i < w_; ++i) {
        col_cos[std::size_t(i)] = static_cast<float>(std::cos(dphi * (i + 0.5)));
        col_sin[std::size_t(i)] = static_cast<float>(std::sin(dphi * (i + 0.5)));
    }
    for (int j = 0; j < h_; ++j) {
        const double theta0 = kPiD * j / h_;
        const double theta1 = kPiD * (j + 1) / h_;
        const float sin_c = static_cast<float>(std::sin(0.5 * (theta0 + theta1)));
        const float cos_c = static_cast<float>(std::cos(0.5 * (theta0 + theta1)));
        const double texel_solid_angle = dphi * (std::cos(theta0) - std::cos(theta1));
        for (int i = 0; i < w_; ++i) {
            float m = 0.f;
            for (int dj = -1; dj <= 1; ++dj) {
                int jj = std::clamp(j + dj, 0, h_ - 1);
                for (int di = -1; di <= 1; ++di)
                    m = std::max(m, lum[static_cast<std::size_t>(jj) * w_ + wrap(i + di, w_)]);
            }
            weight[static_cast<std::size_t>(j) * w_ + i] = m * sin_c;
            const double texel_lum = lum[static_cast<std::size_t>(j) * w_ + i] * texel_solid_angle;
            lum_integral += texel_lum;
            // The texel centre's direction, as xy_to_direction() gives it.
            const Vec3 d(-col_cos[std::size_t(i)] * sin_c, cos_c, col_sin[std::size_t(i)] * sin_c);
            const Sh9 y = sh9_basis(d);
            for (std::size_t c = 0; c < sh.size(); ++c)
                sh[c] += texel_lum * double(y[c]);
        }
    }
    luminance_integral_ = static_cast<float>(lum_integral);
    for (std::size_t c = 0; c < sh.size(); ++c)
        irradiance_sh_[c] = static_cast<float>(sh[c] * double(sh9_cosine_lobe(int(c))));

    // Rows in proportion to their summed weights, columns in proportion to the texel's weight
    // (a row of zero weight is never chosen; its columns are uniform).
    const auto w = static_cast<std::size_t>(w_);
    std::vector<double> row_weight(static_cast<std::size_t>(h_), 0.0);
    columns_.clear();
    columns_.reserve(static_cast<std::size_t>(h_));
    for (std::size_t j = 0; j < row_weight.size(); ++j) {
        const std::vector<double> row(weight.begin() + std::ptrdiff_t(j * w),
                                      weight.begin() + std::ptrdiff_t((j + 1) * w));
        for (double x : row)
            row_weight[j] += x;
        columns_.emplace_back(round_to_units(row));
    }
    rows_ = UnitCdf(round_to_units(row_weight));
}

double EnvMap::texel_pmf(int i, int j) const {
    if (i < 0 || i >= w_ || j < 0 || j >= h_) return 0.0;
    // A product of two multiples of 2^-23: 46 bits, exact in a double.
    return double(rows_.units(static_cast<std::size_t>(j))) *
           double(columns_[static_cast<std::size_t>(j)].units(static_cast<std::size_t>(i))) *
           0x1p-46;
}

Vec2 EnvMap::direction_to_xy(const Vec3& d) const {
    float theta = std::acos(std::clamp(d.y, -1.f, 1.f));
    float phi = std::atan2(-d.z, d.x) + kPi;
    return {static_cast<float>(w_) * phi * kInv2Pi, static_cast<float>(h_) * theta * kInvPi};
}

Vec3 EnvMap::xy_to_direction(float x, float y) const {
    float phi = 2.f * kPi * x / static_cast<float>(w_);
    float theta = kPi * y / static_cast<float>(h_);
    float sin_theta = std::sin(theta);
    // (cos(phi - pi) sin(theta), cos(theta), -sin(phi - pi) sin(theta))
    return {-std::cos(phi) * sin_theta, std::cos(theta), std::sin(phi) * sin_theta};
}

Rgb EnvMap::eval(const Vec3& dir) const {
    return eval_at(direction_to_xy(dir));
}

Rgb EnvMap::eval(const Vec3& dir, float* pdf_out) const {
    const Vec2 xy = direction_to_xy(dir);
    *pdf_out = pdf_at(dir, xy);
    return eval_at(xy);
}

Rgb EnvMap::eval_at(Vec2 xy) const {
    // Texel values sit at centres (i + 1/2, j + 1/2).
    float fx = xy.x - 0.5f, fy = xy.y - 0.5f;
    float x0f = std::floor(fx), y0f = std::floor(fy);
    float tx = fx - x0f, ty = fy - y0f;
    int x0 = wrap(static_cast<int>(x0f), w_), x1 = wrap(static_cast<int>(x0f) + 1, w_);
    int y0 = std::clamp(static_cast<int>(y0f), 0, h_ - 1);
    int y1 = std::clamp(static_cast<int>(y0f) + 1, 0, h_ - 1);
    Rgb top = texel(x0, y0) * (1.f - tx) + texel(x1, y0) * tx;
    Rgb bottom = texel(x0, y1) * (1.f - tx) + texel(x1, y1) * tx;
    return top * (1.f - ty) + bottom * ty;
}

std::optional<EnvSample> EnvMap::sample(Bits2 u) const {
    float fy = 0.f, fx = 0.f;
    const std::uint32_t j = rows_.sample(u.y, &fy);
    const std::uint32_t i = columns_[j].sample(u.x, &fx);
    Vec3 wi = xy_to_direction(static_cast<float>(i) + fx, static_cast<float>(j) + fy);
    // The reported density is pdf(wi) itself, so it equals what pdf() returns for the same
    // direction even when rounding moves wi across a texel border.
    float p = 0.f;
    const Rgb L = eval(wi, &p);
    if (!(p > 0.f)) return std::nullopt;
    return EnvSample{wi, p, L};
}

float EnvMap::pdf(const Vec3& dir) const {
    return pdf_at(dir, direction_to_xy(dir));
}

float EnvMap::pdf_at(const Vec3& dir, Vec2 xy) const {
    const float sin_theta = std::sqrt(dir.x * dir.x + dir.z * dir.z);
    if (!(sin_theta > 0.f)) return 0.f;
    if (!(xy.x >= 0.f && xy.y >= 0.f)) return 0.f; // not a direction (NaN)
    const int i = std::clamp(static_cast<int>(xy.x), 0, w_ - 1);
    const int j = std::clamp(static_cast<int>(xy.y), 0, h_ - 1);
    // Density on the pixel rectangle [0, w] x [0, h] is texel_pmf (the texel's area is 1);
    // dx dy = w h sin(theta) dtheta dphi / (2 pi^2), so per steradian it is
    // texel_pmf w h / (2 pi^2 sin(theta)).
    const double p = texel_pmf(i, j) * (double(w_) * double(h_)) / (2.0 * kPiD * kPiD);
    return static_cast<float>(p / double(sin_theta));
}

} // namespace candela
