#pragma once
// Pearson chi-square goodness-of-fit test for samplers of directions on the unit sphere.
//
// The sphere is cut into theta_bins x phi_bins cells of equal solid angle, uniform in cos(theta) in
// [-1, 1] and phi in [0, 2 pi). Samples are histogrammed; the candidate pdf (solid-angle measure)
// is integrated over each cell with adaptive 2-D product-rule quadrature in (theta, phi) with the
// Jacobian sin(theta) (smooth at the poles). Cells whose expected count is below 5 are pooled,
// failed samples form one more cell whose expected count is n * (1 - integral of the pdf), and the
// p-value is the chi-square survival function, computed with the regularised upper incomplete gamma
// function (series / Lentz continued fraction, as in Press et al., "Numerical Recipes", 6.2).
//
// Peaked distributions (glossy lobes, small cones) put almost all mass into one or two cells and
// the test would then have no power. `zoom_view` wraps a sampler and its pdf with a bijection of
// the sphere that rotates a chosen axis to +z and magnifies its neighbourhood by scaling the
// stereographic projection; the wrapped pdf carries the exact Jacobian, so the test stays exact.
//
// Usage from tests/<stage>/x_test.cpp: #include "../support/chi2.h". Use an even theta_bins so that
// a hemisphere boundary falls on cell edges; pass sidak_significance(0.01, n_tests) as the
// significance when a file runs several tests. A jump of the pdf that crosses cells is integrated
// to ~1e-3 of the crossed cells' mass, so check pdf_integral against 1 with about that tolerance.
#include "candela/math/frame.h"
#include "candela/math/vec.h"
#include "candela/sampling/rng.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace candela::test {

struct Chi2Result {
    bool passed = false;
    double p_value = 0.0;
    double statistic = 0.0;
    int dof = 0;
    double pdf_integral = 0.0; ///< integral of the pdf over the sphere (solid angle)
    std::string message;       ///< human-readable summary or the reason for failure
};

using DirectionSampler = std::function<std::optional<Vec3>(Vec2 u, float uc)>;
using DirectionPdf = std::function<float(const Vec3& w)>;

/// Per-test significance that keeps the family-wise error rate at `alpha` over `n_tests`
/// independent tests (Sidak correction).
inline double sidak_significance(double alpha, int n_tests) {
    return 1.0 - std::pow(1.0 - alpha, 1.0 / static_cast<double>(std::max(1, n_tests)));
}

namespace detail {

/// Regularised lower incomplete gamma P(a, x) by its power series (valid for x < a + 1).
inline double gamma_p_series(double a, double x) {
    constexpr int kMaxIter = 100000; // the series needs O(sqrt(a)) terms; dof stays < 10^6
    constexpr double kEps = 1e-15;   // relative size of the last term, near double epsilon
    double ap = a, del = 1.0 / a, sum = del;
    for (int n = 0; n < kMaxIter; ++n) {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if (std::abs(del) < std::abs(sum) * kEps) break;
    }
    return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Regularised upper incomplete gamma Q(a, x) by the modified Lentz continued fraction
/// (valid for x >= a + 1).
inline double gamma_q_cf(double a, double x) {
    constexpr int kMaxIter = 100000; // converges in O(sqrt(a)) iterations for x >= a + 1
    constexpr double kEps = 1e-15;   // relative change of the convergent, near double epsilon
    constexpr double kTiny = 1e-300; // Lentz's guard against a zero denominator
    double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
    for (int i = 1; i < kMaxIter; ++i) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < kEps) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

} // namespace detail

/// Survival function of the chi-square distribution: P(X >= stat) for X ~ chi^2(dof).
inline double chi2_survival(double stat, int dof) {
    if (dof <= 0) return 1.0;
    if (stat <= 0.0) return 1.0;
    double a = 0.5 * dof, x = 0.5 * stat;
    if (x < a + 1.0) return std::max(0.0, 1.0 - detail::gamma_p_series(a, x));
    return detail::gamma_q_cf(a, x);
}

namespace detail {

/// Adaptive 2-D integral of pdf over a (cos theta, phi) cell, carried out in (theta, phi), with
/// a 3x3-point product rule whose outer nodes sit just inside the cell edges: a cell is split into
/// quadrants until the quadrant sum agrees with the parent's value. Near-edge nodes make a jump
/// anywhere inside a cell visible to the error estimate (interior-only Gauss nodes can miss a
/// jump lying close to a subdivision line), while a jump exactly on a cell edge (the horizon on an
/// even theta grid) is not mistaken for one.
class CellIntegrator {
  public:
    explicit CellIntegrator(const DirectionPdf& pdf) : pdf_(pdf) {}

    /// Integral over cos(theta) in [z0,z1], phi in [p0,p1] to absolute accuracy ~tol (or
    /// relative kFloatNoise).
    double integrate(double z0, double z1, double p0, double p1, double tol) {
        double t0 = std::acos(std::clamp(z1, -1.0, 1.0)), t1 = std::acos(std::clamp(z0, -1.0, 1.0));
        return recurse(t0, t1, p0, p1, rule(t0, t1, p0, p1), tol, 0);
    }

  private:
    // Depth cap: a cell cut by a discontinuity of the pdf (hemisphere or cone edge) would otherwise
    // refine forever; 2^8 subdivisions per axis leave a relative error of ~1e-3 in the cells the
    // edge crosses, below the Poisson noise sqrt(expected) of any cell with expected < 10^6.
    static constexpr int kMaxDepth = 8;
    // Relative accuracy a float-valued pdf supports (float ulps amplified by exp, normalize...);
    // 1e-5 of a cell's expected count is still negligible against its Poisson noise.
    static constexpr double kFloatNoise = 1e-5;

    /// Integrand in (theta, phi): pdf times the solid-angle Jacobian sin(theta). Integrating in
    /// theta rather than cos(theta) keeps the integrand smooth at the poles, where sqrt(1 - z^2)
    /// is not.
    double eval(double theta, double phi) {
        double st = std::sin(theta), ct = std::cos(theta);
        Vec3 w(static_cast<float>(st * std::cos(phi)), static_cast<float>(st * std::sin(phi)),
               static_cast<float>(ct));
        double f = static_cast<double>(pdf_(w));
        return std::isfinite(f) ? f * st : 0.0;
    }

    /// Relative inset of the outer nodes from the cell edges. A jump closer than this to an edge
    /// can go unnoticed, costing at most this fraction of the jump's cell strip.
    static constexpr double kEdgeInset = 1e-3;

    /// Symmetric 3-point rule on nodes {inset, 1/2, 1 - inset} (relative), weights chosen to be
    /// exact for cubics; the product rule on a rectangle.
    double rule(double t0, double t1, double p0, double p1) {
        constexpr double kHalfGap = 0.5 - kEdgeInset;
        constexpr double kW0 = 1.0 / (24.0 * kHalfGap * kHalfGap); // second moment = 1/12
        constexpr double kNodes[3] = {kEdgeInset, 0.5, 1.0 - kEdgeInset};
        constexpr double kWeights[3] = {kW0, 1.0 - 2.0 * kW0, kW0};
        double s = 0.0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                s += kWeights[i] * kWeights[j] *
                     eval(t0 + (t1 - t0) * kNodes[i], p0 + (p1 - p0) * kNodes[j]);
        return s * (t1 - t0) * (p1 - p0);
    }

    double recurse(double z0, double z1, double p0, double p1, double whole, double tol,
                   int depth) {
        double zm = 0.5 * (z0 + z1), pm = 0.5 * (p0 + p1);
        double q[4] = {rule(z0, zm, p0, pm), rule(z0, zm, pm, p1), rule(zm, z1, p0, pm),
                       rule(zm, z1, pm, p1)};
        double fine = q[0] + q[1] + q[2] + q[3];
        double bound = std::max(tol, kFloatNoise * std::abs(fine));
        if (depth >= kMaxDepth || std::abs(fine - whole) <= bound) return fine;
        return recurse(z0, zm, p0, pm, q[0], 0.25 * tol, depth + 1) +
               recurse(z0, zm, pm, p1, q[1], 0.25 * tol, depth + 1) +
               recurse(zm, z1, p0, pm, q[2], 0.25 * tol, depth + 1) +
               recurse(zm, z1, pm, p1, q[3], 0.25 * tol, depth + 1);
    }

    const DirectionPdf& pdf_;
};

} // namespace detail

/// Draws n_samples directions with `sample` (u, uc from PCG32 seeded with `seed`), histograms them
/// over theta_bins x phi_bins equal-solid-angle cells, integrates `pdf` (solid-angle density) per
/// cell, pools cells with expected count < 5, and runs Pearson's test. Passes when no hard error
/// occurred (non-unit or non-finite direction, samples where the pdf integrates to zero) and the
/// p-value is >= `significance`.
inline Chi2Result chi2_test(const std::function<std::optional<Vec3>(Vec2 u, float uc)>& sample,
                            const std::function<float(const Vec3& w)>& pdf, int n_samples,
                            int theta_bins, int phi_bins, std::uint64_t seed,
                            double significance = 0.01) {
    // A sampled direction must be unit to float precision after the sampler's own normalisation.
    constexpr double kUnitTolerance = 1e-3;
    // Pearson's approximation needs expected counts of at least ~5 per cell (Cochran's rule).
    constexpr double kMinExpected = 5.0;
    // Total absolute quadrature error budget, as a probability over the whole sphere: 1e-6 * n
    // is about one count in total for 10^6 samples, negligible against the Poisson noise.
    constexpr double kQuadratureTolerance = 1e-6;
    // Samples tolerated in a cell where the pdf integrates to 0, as a fraction of n: float rounding
    // can move a sample lying exactly on a cell edge (where the pdf jumps to 0) into the wrong
    // cell. More than this is a hard failure.
    constexpr double kStrayFraction = 1e-5;
    constexpr double kTwoPi = 6.283185307179586;

    Chi2Result res;
    const int n_cells = theta_bins * phi_bins;
    std::vector<double> observed(static_cast<std::size_t>(n_cells), 0.0);
    double n_failed = 0.0;

    Pcg32 rng(seed, hash_combine(seed, 0x63686932ULL));
    for (int i = 0; i < n_samples; ++i) {
        float u0 = rng.next_float(), u1 = rng.next_float(), uc = rng.next_float();
        std::optional<Vec3> w = sample(Vec2(u0, u1), uc);
        if (!w) {
            n_failed += 1.0;
            continue;
        }
        double len = std::sqrt(static_cast<double>(dot(*w, *w)));
        if (!is_finite(*w) || std::abs(len - 1.0) > kUnitTolerance) {
            std::ostringstream os;
            os << "sample " << i << " is not a unit direction: (" << w->x << ", " << w->y << ", "
               << w->z << "), |w| = " << len;
            res.message = os.str();
            return res;
        }
        double z = std::clamp(static_cast<double>(w->z) / len, -1.0, 1.0);
        double phi = std::atan2(static_cast<double>(w->y), static_cast<double>(w->x));
        if (phi < 0.0) phi += kTwoPi;
        int ti = std::clamp(static_cast<int>((z + 1.0) * 0.5 * theta_bins), 0, theta_bins - 1);
        int pi = std::clamp(static_cast<int>(phi / kTwoPi * phi_bins), 0, phi_bins - 1);
        observed[static_cast<std::size_t>(ti * phi_bins + pi)] += 1.0;
    }

    std::vector<double> expected(static_cast<std::size_t>(n_cells), 0.0);
    detail::CellIntegrator integrator(pdf);
    const double dz = 2.0 / theta_bins, dphi = kTwoPi / phi_bins;
    const double cell_tol = kQuadratureTolerance / n_cells;
    double integral = 0.0;
    for (int ti = 0; ti < theta_bins; ++ti)
        for (int pi = 0; pi < phi_bins; ++pi) {
            double z0 = -1.0 + ti * dz, p0 = pi * dphi;
            double p = integrator.integrate(z0, z0 + dz, p0, p0 + dphi, cell_tol);
            p = std::max(0.0, p);
            integral += p;
            expected[static_cast<std::size_t>(ti * phi_bins + pi)] = p * n_samples;
        }
    res.pdf_integral = integral;

    // Cells, plus the failure cell, as (expected, observed) pairs.
    std::vector<std::pair<double, double>> cells;
    double stray = 0.0; // samples in cells where the pdf integrates to 0
    cells.reserve(static_cast<std::size_t>(n_cells) + 1);
    for (int c = 0; c < n_cells; ++c) {
        auto ci = static_cast<std::size_t>(c);
        if (expected[ci] == 0.0 && observed[ci] > 0.0) {
            stray += observed[ci];
            if (observed[ci] <= kStrayFraction * n_samples) {
                // Rounding: a sample on a cell edge where the pdf jumps to 0 (pooled below).
                cells.emplace_back(0.0, observed[ci]);
                continue;
            }
            std::ostringstream os;
            os << observed[ci] << " samples in cell (" << c / phi_bins << ", " << c % phi_bins
               << ") where the pdf integrates to 0";
            res.message = os.str();
            return res;
        }
        cells.emplace_back(expected[ci], observed[ci]);
    }
    double expected_failed = std::max(0.0, 1.0 - integral) * n_samples;
    if (expected_failed > 0.0 || n_failed > 0.0) cells.emplace_back(expected_failed, n_failed);

    std::sort(cells.begin(), cells.end());
    double pooled_e = 0.0, pooled_o = 0.0, stat = 0.0;
    int n_bins = 0;
    std::vector<std::pair<double, double>> kept;
    for (const auto& [e, o] : cells) {
        if (e < kMinExpected) {
            pooled_e += e;
            pooled_o += o;
        } else {
            kept.emplace_back(e, o);
        }
    }
    if (pooled_e > 0.0 || pooled_o > 0.0) {
        if (pooled_e >= kMinExpected || kept.empty()) {
            kept.emplace_back(pooled_e, pooled_o);
        } else {
            // Too little pooled mass for its own cell: merge into the smallest kept cell.
            kept.front().first += pooled_e;
            kept.front().second += pooled_o;
        }
    }
    for (const auto& [e, o] : kept) {
        if (e <= 0.0) {
            if (o > 0.0) {
                res.message = "samples fall where the pdf has (almost) no mass";
                return res;
            }
            continue;
        }
        stat += (o - e) * (o - e) / e;
        ++n_bins;
    }
    res.statistic = stat;
    res.dof = std::max(0, n_bins - 1);
    res.p_value = chi2_survival(stat, res.dof);
    res.passed = res.dof > 0 && res.p_value >= significance;
    std::ostringstream os;
    os << "chi2 = " << stat << ", dof = " << res.dof << ", p = " << res.p_value << " (significance "
       << significance << "), pdf integral = " << integral << ", failed samples = " << n_failed
       << "/" << n_samples;
    if (stray > 0.0) os << ", samples where the pdf is 0 = " << stray;
    if (res.dof == 0) os << " [no degrees of freedom: use more samples or bins]";
    res.message = os.str();
    return res;
}

/// Deterministic integral of g (a function of direction, per unit solid angle) over the sphere
/// with the cells and the adaptive rule of chi2_test: theta_bins x phi_bins cells, absolute
/// tolerance ~tol in total (relative 1e-5 per cell at most). Smooth integrands are resolved to
/// ~1e-6 of their integral, jumps that cross cells to ~1e-3 of the crossed cells' share.
inline double integrate_sphere(const DirectionPdf& g, int theta_bins, int phi_bins, double tol) {
    constexpr double kTwoPi = 6.283185307179586;
    detail::CellIntegrator integrator(g);
    const double dz = 2.0 / theta_bins, dphi = kTwoPi / phi_bins;
    const double cell_tol = tol / (static_cast<double>(theta_bins) * phi_bins);
    double sum = 0.0;
    for (int ti = 0; ti < theta_bins; ++ti)
        for (int pi = 0; pi < phi_bins; ++pi) {
            const double z0 = -1.0 + ti * dz, p0 = pi * dphi;
            sum += integrator.integrate(z0, z0 + dz, p0, p0 + dphi, cell_tol);
        }
    return sum;
}

/// A bijection of the sphere: rotates `axis` to +z, then scales the stereographic coordinate
/// r = tan(theta/2) by `zoom` (> 1 magnifies the neighbourhood of `axis`).
struct ZoomView {
    Frame frame;
    double zoom = 1.0;

    ZoomView(const Vec3& axis, double zoom_) : frame(normalize(axis)), zoom(zoom_) {}

    /// Maps a direction w (world) to its zoomed image.
    Vec3 forward(const Vec3& w) const { return scale(frame.to_local(w), zoom); }
    /// Maps a zoomed direction back to the world direction.
    Vec3 inverse(const Vec3& wz) const { return frame.to_world(scale(wz, 1.0 / zoom)); }
    /// d(omega_world) / d(omega_zoomed) at the zoomed direction wz, so that
    /// pdf_zoomed(wz) = pdf(inverse(wz)) * jacobian(wz).
    double jacobian(const Vec3& wz) const {
        double rz = stereo_r(wz);
        double r = rz / zoom;
        constexpr double kFar = 1e100; // both radii huge: the ratio is at its limit zoom^2
        if (r > kFar) return zoom * zoom;
        double q = (1.0 + rz * rz) / (1.0 + r * r);
        return q * q / (zoom * zoom);
    }

  private:
    static double stereo_r(const Vec3& w) {
        double s = std::sqrt(static_cast<double>(w.x) * w.x + static_cast<double>(w.y) * w.y);
        double c = static_cast<double>(w.z);
        // tan(theta/2) = sin / (1 + cos), or (1 - cos) / sin: pick the well-conditioned one.
        if (c >= 0.0) return s / (1.0 + c);
        return s > 0.0 ? (1.0 - c) / s : std::numeric_limits<double>::infinity();
    }
    static Vec3 scale(const Vec3& w, double factor) {
        double r = stereo_r(w);
        if (!std::isfinite(r)) return Vec3(0.f, 0.f, -1.f);
        double rs = r * factor;
        double s = std::sqrt(static_cast<double>(w.x) * w.x + static_cast<double>(w.y) * w.y);
        double cx = s > 0.0 ? w.x / s : 1.0, cy = s > 0.0 ? w.y / s : 0.0;
        double d = 1.0 + rs * rs;
        double sin_t = 2.0 * rs / d, cos_t = (1.0 - rs * rs) / d;
        if (!std::isfinite(d)) {
            sin_t = 0.0;
            cos_t = -1.0;
        }
        return Vec3(static_cast<float>(sin_t * cx), static_cast<float>(sin_t * cy),
                    static_cast<float>(cos_t));
    }
};

/// A density (or any integrand per unit solid angle) seen through a ZoomView: integrating the
/// result over the sphere gives the integral of g, with the neighbourhood of `axis` magnified
/// for the quadrature.
inline DirectionPdf zoomed_density(DirectionPdf g, const Vec3& axis, double zoom) {
    ZoomView view(axis, zoom);
    return [view, g](const Vec3& wz) -> float {
        return static_cast<float>(static_cast<double>(g(view.inverse(wz))) * view.jacobian(wz));
    };
}

/// Wraps a sampler and its pdf with a ZoomView: the returned pair samples and evaluates the
/// zoomed distribution, which has the same chi-square statistics as the original.
inline std::pair<DirectionSampler, DirectionPdf>
zoom_view(DirectionSampler sample, DirectionPdf pdf, const Vec3& axis, double zoom) {
    ZoomView view(axis, zoom);
    DirectionSampler zs = [view, sample](Vec2 u, float uc) -> std::optional<Vec3> {
        std::optional<Vec3> w = sample(u, uc);
        if (!w) return std::nullopt;
        return view.forward(*w);
    };
    DirectionPdf zp = [view, pdf](const Vec3& wz) -> float {
        return static_cast<float>(static_cast<double>(pdf(view.inverse(wz))) * view.jacobian(wz));
    };
    return {zs, zp};
}

} // namespace candela::test
