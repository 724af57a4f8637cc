// The geometric-optics regime of the wave_optics method: see regime.hpp.
#include "regime.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::wave_optics {

SurfaceStats surface_stats(const float* h, int nx, int ny, double dx, double dy, bool periodic, const glm::dvec3& light,
                           double ior) {
    const glm::dvec3 d = glm::normalize(light);
    const double cos_i = -d.z;
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i)) / ior;
    const double cos_t = std::sqrt(std::max(1e-12, 1.0 - sin_t * sin_t));
    const double c = ior * cos_t - cos_i;
    // The tilt frame: u along the light's horizontal direction, v across it.
    const glm::dvec2 dh(d.x, d.y);
    const glm::dvec2 u = glm::length(dh) > 1e-12 ? dh / glm::length(dh) : glm::dvec2(1.0, 0.0);
    const glm::dvec2 v(-u.y, u.x);
    const double mu2 = std::abs(c) / ior / (cos_t * cos_t * cos_t), mv2 = std::abs(c) / ior / cos_t;
    const double muv = std::sqrt(mu2 * mv2);
    const double ihx = 0.5 / dx, ihy = 0.5 / dy, ixx = 1.0 / (dx * dx), iyy = 1.0 / (dy * dy), ixy = 0.25 / (dx * dy);
    const int lo = periodic ? 0 : 1;
    const int hx = periodic ? nx : nx - 1, hy = periodic ? ny : ny - 1;
    std::vector<SurfaceStats> rows(static_cast<std::size_t>(std::max(ny, 0)));
    tbb::parallel_for(tbb::blocked_range<int>(lo, std::max(lo, hy), 16), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            const float* hm = h + static_cast<std::size_t>(j == 0 ? ny - 1 : j - 1) * nx;
            const float* h0 = h + static_cast<std::size_t>(j) * nx;
            const float* hp = h + static_cast<std::size_t>(j + 1 == ny ? 0 : j + 1) * nx;
            double e_min = 0.0, slope2 = 0.0, curvature = 0.0, deviation2 = 0.0;
            for (int i = lo; i < hx; ++i) {
                const int im = i == 0 ? nx - 1 : i - 1, ip = i + 1 == nx ? 0 : i + 1;
                const double gx = (h0[ip] - h0[im]) * ihx, gy = (hp[i] - hm[i]) * ihy;
                const double hxx = (static_cast<double>(h0[ip]) - 2.0 * h0[i] + h0[im]) * ixx;
                const double hyy = (static_cast<double>(hp[i]) - 2.0 * h0[i] + hm[i]) * iyy;
                const double hxy = (static_cast<double>(hp[ip]) - hp[im] - hm[ip] + hm[im]) * ixy;
                slope2 = std::max(slope2, gx * gx + gy * gy);
                // Snell with the vertex's normal (-gx, -gy, 1) / |.|: t = d / n + (cos_l / n - cos_tl) nrm.
                const double inv = 1.0 / std::sqrt(1.0 + gx * gx + gy * gy);
                const glm::dvec3 nrm(-gx * inv, -gy * inv, inv);
                const double cos_l = -glm::dot(d, nrm);
                const double k2 = 1.0 - (1.0 - cos_l * cos_l) / (ior * ior);
                if (cos_l > 0.0 && k2 >= 0.0) {
                    const double a = cos_l / ior - std::sqrt(k2);
                    const glm::dvec2 dev = a * glm::dvec2(nrm.x, nrm.y);   // t_xy - d_xy / n
                    deviation2 = std::max(deviation2, glm::dot(dev, dev));
                }
                // The square roots only where a bound says the extreme may change (exact either way).
                const double mean_h = std::abs(0.5 * (hxx + hyy));
                if (mean_h + 0.5 * std::abs(hxx - hyy) + std::abs(hxy) > curvature)
                    curvature = std::max(curvature, mean_h + std::sqrt(0.25 * (hxx - hyy) * (hxx - hyy) + hxy * hxy));
                // Hessian in the tilt frame, scaled by M^1/2 on both sides.
                const double huu = u.x * u.x * hxx + 2.0 * u.x * u.y * hxy + u.y * u.y * hyy;
                const double hvv = v.x * v.x * hxx + 2.0 * v.x * v.y * hxy + v.y * v.y * hyy;
                const double huv = u.x * v.x * hxx + (u.x * v.y + u.y * v.x) * hxy + u.y * v.y * hyy;
                const double a = mu2 * huu, b = mv2 * hvv, o = muv * huv;
                // Converging where the map's Jacobian 1 + z (c / n) eig falls: the sign of c decides which end.
                const double centre = c >= 0.0 ? 0.5 * (a + b) : -0.5 * (a + b);
                if (centre - (0.5 * std::abs(a - b) + std::abs(o)) < e_min)
                    e_min = std::min(e_min, centre - std::sqrt(0.25 * (a - b) * (a - b) + o * o));
            }
            rows[static_cast<std::size_t>(j)] = {e_min, std::sqrt(slope2), curvature, std::sqrt(deviation2)};
        }
    });
    SurfaceStats s;
    for (const SurfaceStats& r : rows) {
        s.e_min = std::min(s.e_min, r.e_min);
        s.slope = std::max(s.slope, r.slope);
        s.curvature = std::max(s.curvature, r.curvature);
        s.deviation = std::max(s.deviation, r.deviation);
    }
    return s;
}

SurfaceStats surface_stats(const HeightField& hf, const glm::dvec3& light, double ior) {
    if (hf.nx < 3 || hf.ny < 3) return {};
    return surface_stats(hf.height.data(), hf.nx, hf.ny, hf.spacing.x, hf.spacing.y, false, light, ior);
}

double auto_wavelength(double spacing, double deviation) {
    const auto at = [spacing](int k) { return 2.0 * spacing * std::exp2(-0.25 * k); };
    int k = 0;
    while (k < 4 * kMaxHalvings && at(k + 1) >= kSamplingMargin * 2.0 * spacing * deviation) ++k;
    return at(k);
}

double sampling_margin(double lambda, double spacing, double deviation) {
    return deviation > 0.0 ? lambda / (2.0 * spacing * deviation) : std::numeric_limits<double>::infinity();
}

Regime estimate_regime(const SurfaceStats& stats, const glm::dvec3& light, double ior, double lambda, double depth,
                       double period, double exact_focus) {
    const double inf = std::numeric_limits<double>::infinity();
    const double cos_i = -glm::normalize(light).z;
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i)) / ior;
    const double cos_t = std::sqrt(std::max(1e-12, 1.0 - sin_t * sin_t));
    const double c = ior * cos_t - cos_i;
    Regime r;
    r.depth = depth;
    // blocks/regime says "no focus" with 1e300.
    r.focus_depth = std::min(stats.e_min < 0.0 ? -1.0 / stats.e_min : inf,
                             exact_focus > 0.0 && exact_focus < 1e299 ? exact_focus : inf);
    r.length_scale = stats.curvature > 0.0 ? 2.0 * std::numbers::pi * stats.slope / stats.curvature : inf;
    r.rho = std::isfinite(r.focus_depth) ? depth / r.focus_depth : 0.0;
    const double z_eff = depth / (cos_t * cos_t * cos_t);
    r.blur = std::sqrt(2.0 * std::numbers::pi * lambda * std::max(z_eff, 0.0));
    if (r.rho >= 1.0)
        r.epsilon = inf;
    else if (r.rho > 0.0)
        r.epsilon = r.rho * r.blur / (r.length_scale * std::pow(1.0 - r.rho, 1.5));
    r.spread = z_eff * std::abs(c) / ior * stats.slope / (0.5 * period);
    return r;
}

std::string regime_violation(const Regime& r) {
    std::ostringstream s;
    s.precision(3);
    if (r.rho >= 1.0) {
        s << "the receiver reaches " << r.depth << " m below the water, past the first focus at " << r.focus_depth
          << " m (paraxial at the steepest converging curvature, or traced, the shallower): the refracted rays have crossed, and the coherent "
             "wave's interference fringes and fold diffraction converge to the geometric sum only weakly as the "
             "wavelength shrinks";
        return s.str();
    }
    if (r.epsilon > kMaxEpsilon) {
        s << "diffraction blur sqrt(2 pi lambda z) = " << r.blur << " m at depth " << r.depth << " m against caustic "
          << "features of " << r.length_scale << " m x (1 - z/z_f)^1.5 / (z/z_f), z/z_f = " << r.rho
          << " (first focus " << r.focus_depth << " m): eps = " << r.epsilon << " > " << kMaxEpsilon
          << " (a larger grid or a shorter wavelength lowers it as sqrt(lambda))";
        return s.str();
    }
    if (r.spread > 1.0) {
        s << "the refracted light spreads " << r.spread << " half-periods sideways at depth " << r.depth
          << " m: more than the band-limited transfer function keeps";
        return s.str();
    }
    return {};
}

}  // namespace caustics::wave_optics
