#pragma once
// Where the wave_optics method reproduces geometric optics, estimated from the surface, the light, the
// receiver depth and the wavelength (the accuracy_claim and health of the method).
//
// A wave leaving a phase screen focuses like the rays it carries only where diffraction cannot blur the
// structure the rays form. Along the light's tilt the refracted light's lateral offset grows as
// X = x + z (c / n) grad h / cos^3(theta_t) (across it, / cos(theta_t)), c = n cos(theta_t) - cos(theta_i), so
// the map x -> X first folds at the depth z_f = -1 / e_min, e_min the most negative eigenvalue of
// (c / n) M^1/2 Hess(h) M^1/2, M = diag(1 / cos^3, 1 / cos) (the paraxial first focus; the sine scenes'
// 0.64 m at normal incidence). Past it (rho = z / z_f >= 1) several rays reach each point: the coherent
// wave draws their interference fringes and Airy-type folds, which converge to the geometric sum only
// weakly as lambda -> 0, so nothing is claimed there. Before it, the stationary-phase approximation that
// links the wave to the rays holds while the diffraction blur sqrt(2 pi lambda z_eff) (z_eff = z /
// cos^3(theta_t)) is small against the caustic's features, whose size shrinks as (1 - rho)^1.5 / rho times
// the surface's length scale l = 2 pi max|grad h| / max|Hess h| (the period of a sine):
//   eps = rho sqrt(2 pi lambda z_eff) / (l (1 - rho)^1.5),
// the ratio of the cubic term of the phase to its quadratic term over the stationary zone (for a sine:
// the error grows as ~0.08 eps^2 times the flat baseline's, measured at normal incidence). The angular
// spectrum's band limit needs the light's lateral spread z (c / n) max|grad h| / cos^3 within half a
// period.
#include <limits>
#include <string>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>

namespace caustics::wave_optics {

struct Regime {
    double focus_depth = 0.0;    // z_f [m]; infinite when nothing converges
    double length_scale = 0.0;   // l [m]
    double depth = 0.0;          // the deepest receiver point below the mean level [m]
    double rho = 0.0;            // depth / z_f
    double blur = 0.0;           // sqrt(2 pi lambda z_eff) [m]
    double epsilon = 0.0;        // see above (infinite at or past the focus)
    double spread = 0.0;         // lateral spread of the light at `depth` over half the period
};

// The claim (accuracy_claim): nrmse <= kClaimError where eps <= kMaxEpsilon, the receiver lies at most
// kMaxFocusFraction of the way to the first focus (blocks/regime), at most kMaxDepthOverFeature feature
// lengths down, the light spreads at most one half-period sideways, the field is sampled at
// kSamplingMargin x its Nyquist rate and the light reaching the receiver enters the surface (not the FFT
// window's border around a non-tiling one). Measured on 200 drawn cases at the default grid 512 with the
// automatic wavelength (seed 20261205): up to 0.4 of the way the worst was 0.004, from 0.4 to 0.9 0.048 where
// eps <= 2; with Stam's two grid spacings, 9 of 46 cases from 0.4 to 0.6 exceeded 0.10. The depth bound: 6
// feature lengths until the cases from 6 to 8.74 measured <= 0.048 on four seeds of 200 (0.079 at 7.69 is
// outside by eps).
constexpr double kMaxEpsilon = 2.0;
constexpr double kMaxFocusFraction = 0.9, kMaxDepthOverFeature = 8.5;
constexpr double kClaimError = 0.10;

// The surface's part: the most negative focusing eigenvalue e_min [1/m] (z_f = -1 / e_min), max |grad h|
// and max |Hess h| (largest principal curvature) [1/m], by central differences on a height grid
// (periodic: wrapped; else the interior), rows in parallel, reduced in a fixed order.
// deviation: the largest |t_xy - t0_xy| between the exact refracted direction t at a vertex (Snell with the
// vertex's own normal) and the flat surface's t0: the refracted field's largest transverse spatial frequency
// relative to its carrier is deviation / lambda, conserved as the wave propagates (auto_wavelength).
struct SurfaceStats {
    double e_min = 0.0, slope = 0.0, curvature = 0.0, deviation = 0.0;
};
SurfaceStats surface_stats(const float* h, int nx, int ny, double dx, double dy, bool periodic, const glm::dvec3& light,
                           double ior);
SurfaceStats surface_stats(const HeightField& hf, const glm::dvec3& light, double ior);

// lambda: the longest wavelength in the water the method propagates; period: the shorter side of the
// FFT window.
// exact_focus: the first focus traced without the paraxial approximation (blocks/regime, below the mean
// level), used where it is shallower than the paraxial one: at steep slopes under oblique light the
// paraxial focus lies deeper, and eps, which grows as (1 - rho)^-1.5, was underestimated (a sine at 39 deg,
// ior 1.05, slopes 0.35: eps 0.68 from the paraxial focus, nrmse 0.12).
Regime estimate_regime(const SurfaceStats& stats, const glm::dvec3& light, double ior, double lambda, double depth,
                       double period, double exact_focus = std::numeric_limits<double>::infinity());

// The wavelength (in the water) the method propagates when none is set: the shortest of 2 dx / 2^(k / 4),
// k = 0 .. 4 kMaxHalvings, at which the refracted field is sampled at kSamplingMargin x its Nyquist rate
// (lambda >= kSamplingMargin * 2 dx * deviation, a phase step of at most pi / kSamplingMargin per cell), so
// that the diffraction blur sqrt(2 pi lambda z) is as small as the grid allows; 2 dx (k = 0) is Stam's
// choice after Moravec ("twice the grid spacing"), kept where the surface's slopes need it. Quarter
// octaves so that an animated surface changes the wavelength (and the propagators) rarely. The margin:
// `sine` at grid 512 (deviation 0.062) measures nrmse 0.0031, 0.0031 and 0.0030 at margins 1.29, 1.45 and
// 1.61, 0.017 at 1.13 and 0.37 at 0.97 (aliased).
constexpr int kMaxHalvings = 4;
constexpr double kSamplingMargin = 1.5;
double auto_wavelength(double spacing, double deviation);
// lambda / (2 dx deviation): how many times the refracted field's Nyquist rate the grid samples it at
// (infinite for a flat screen).
double sampling_margin(double lambda, double spacing, double deviation);

// Empty when inside, else the bound the frame passes with its numbers.
std::string regime_violation(const Regime& r);

}  // namespace caustics::wave_optics
