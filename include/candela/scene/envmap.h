#pragma once
// Latitude-longitude environment map (spec section 2.6) with importance sampling.
//
// Mapping (unit direction d, image of w x h texels, row 0 = zenith +Y):
//   theta = acos(d.y) in [0, pi], phi = atan2(-d.z, d.x) + pi in [0, 2 pi],
//   continuous pixel coordinates x = w phi / (2 pi), y = h theta / pi; texel (i, j) covers
//   [i, i+1) x [j, j+1) and its value sits at the centre (i + 1/2, j + 1/2).
//
// Radiance lookup: bilinear between texel centres, wrapping horizontally and clamping vertically
// (near the top only row 0 is used, near the bottom only row h-1). sample() returns the same
// bilinear value as eval() along its direction, so light sampling and BSDF sampling (MIS) see one
// function.
//
// Sampling: texel weights proportional to max-luminance(3x3 neighbourhood of (i, j)) *
// sin(theta at row centre); a row is chosen in proportion to its weight, then a column of that
// row in proportion to the texel's weight, then a uniform point inside the chosen texel. The
// neighbourhood maximum covers every texel that the bilinear lookup can reach from inside (i, j),
// so the density is positive wherever eval() is non-zero and pure light sampling is unbiased.
// Both choices are integer CDFs (sampling/unit_cdf.h) inverted by the 32-bit coordinates of the
// sampler's point, the row by u.y and the column by u.x; each realises its probability exactly,
// so texel (i, j) is chosen with probability texel_pmf(i, j) = P(row j) P(column i | row j), a
// multiple of 2^-46 that a double holds exactly, and pdf() divides by exactly that. The position
// inside the texel reuses the part of each coordinate inside its chosen range. Solid-angle
// density: texel_pmf(i, j) * w * h / (2 pi^2 sin(theta)).
#include "candela/math/sh9.h"
#include "candela/math/vec.h"
#include "candela/sampling/rng.h"
#include "candela/sampling/unit_cdf.h"

#include <optional>
#include <string>
#include <vector>

namespace candela {

/// A direction drawn from an EnvMap.
struct EnvSample {
    Vec3 wi;   ///< unit world direction toward the environment
    float pdf; ///< solid-angle density of wi (per steradian), > 0
    Rgb L;     ///< eval(wi): radiance arriving from direction wi
};

class EnvMap {
  public:
    /// Builds the map and its sampling table from `texels` (row-major, row 0 = top, size w*h,
    /// linear RGB radiance). `name` labels error messages. Throws Error(ErrorKind::Io) naming the
    /// texel when a value is negative or not finite, or when the size does not match.
    EnvMap(int width, int height, std::vector<Rgb> texels, std::string name = "<memory>");

    int width() const { return w_; }
    int height() const { return h_; }
    /// Texel in column i, row j (row 0 = top).
    const Rgb& texel(int i, int j) const { return texels_[static_cast<std::size_t>(j) * w_ + i]; }

    /// Radiance arriving from unit direction `dir` (bilinear lookup; see the file comment).
    Rgb eval(const Vec3& dir) const;
    /// eval(dir), with pdf(dir) in *pdf: the direction's pixel coordinates found once.
    Rgb eval(const Vec3& dir, float* pdf) const;
    /// Draws a direction from the importance-sampling density using the 32-bit coordinates of
    /// a uniform point of [0,1)^2. nullopt only for a direction at an exact pole (zero
    /// solid-angle Jacobian).
    std::optional<EnvSample> sample(Bits2 u) const;
    /// sample() of the point u of [0, 1)^2 (unit_point_to_bits).
    std::optional<EnvSample> sample(Vec2 u) const { return sample(unit_point_to_bits(u)); }
    /// Solid-angle density (per steradian) with which sample() produces unit direction `dir`.
    float pdf(const Vec3& dir) const;
    /// Probability with which sample() chooses texel (i, j), exact (0 outside the map).
    double texel_pmf(int i, int j) const;
    /// The row choice (by u.y) and each row's column choice (by u.x), for tests that count the
    /// values of u choosing each texel.
    const UnitCdf& row_table() const { return rows_; }
    const UnitCdf& column_table(int j) const { return columns_[static_cast<std::size_t>(j)]; }
    /// Integral of luminance over the sphere of directions (W/m^2-like units), computed from the
    /// texels as piecewise constant over their solid angles; used for light selection.
    float luminance_integral() const { return luminance_integral_; }
    /// The irradiance, as luminance, that an unoccluded surface with unit normal n receives from
    /// the map (the integral of luminance(L(w)) max(0, n . w) over the sphere), as the nine
    /// coefficients of its order-2 spherical-harmonic estimate (math/sh9.h), projected from the
    /// texels (each its centre's value over its solid angle). Used for light selection only: it
    /// is exact for a map without structure above order 2 (a constant map, one lit hemisphere)
    /// and smooth otherwise, and may dip below zero beside a dark region (light_irradiance()
    /// in light/light_sample.h evaluates it, clamped at 0).
    const Sh9& irradiance_sh() const { return irradiance_sh_; }

    /// Continuous pixel coordinates (x in [0, w], y in [0, h]) of unit direction `d`.
    Vec2 direction_to_xy(const Vec3& d) const;
    /// Unit direction at continuous pixel coordinates (x, y).
    Vec3 xy_to_direction(float x, float y) const;

  private:
    int w_ = 0, h_ = 0;
    std::vector<Rgb> texels_;
    // Sampling tables: rows, then the columns of each row.
    UnitCdf rows_;
    std::vector<UnitCdf> columns_;
    float luminance_integral_ = 0.f;
    Sh9 irradiance_sh_{};

    void build_sampling_table();
    /// eval() and pdf() at the direction's pixel coordinates xy = direction_to_xy(dir).
    Rgb eval_at(Vec2 xy) const;
    float pdf_at(const Vec3& dir, Vec2 xy) const;
};

} // namespace candela
