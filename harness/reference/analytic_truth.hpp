#pragma once
// Analytic ground truth (docs/design.md section 5): where a scene has an exact closed form, its receiver map
// serves as the ground truth and the Monte Carlo reference is tested against it (tests/test_analytic_truth.cpp).
//
// Three closed forms: the ball lens (BallLens below) and the Gaussian bump before its first focus
// (RadialBump), both lit straight down, and the refracting 1-D sine surface h(s) = A sin(k s + phase +
// k speed t) lit by a directional light in the sine's vertical plane, at any tilt and depth (folds included): every ray stays
// in its vertical plane, so the receiver map is a 1-D profile along the sine times the water's extent
// across it. The profile is the exact Snell mapping s -> X(s) of fine source strips (a histogram of the
// mapped strips, each carrying the flux the beam sends through it), which converges to the bin average of
// E(X) = sum over preimages of (flux density at s) / |dX/ds|, the flux-conservation form of the caustic.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <caustics/frame/frame.hpp>
#include <caustics/util/image.hpp>
#include <caustics/frame/receiver_chart.hpp>

namespace caustics {

struct AnalyticTruth {
    bool available = false;
    std::string kind;      // "analytic:sine", "analytic:gaussian" or "analytic:ball_lens" when available
    std::string reason;    // why not, when !available
    Image receiver;        // exact bin-averaged caustic irradiance E_c [W/m^2], chart.width() x chart.height() x 1
};

// The exact receiver map of the scene frame where a closed form applies, else available = false with the
// reason. Applies to: one directional light; one `sine` height field of a non-dispersive dielectric and the
// receiver (a horizontal rectangle below the water whose u or v is parallel to the sine's direction, which
// runs along an edge of the water's rectangle); no medium; the light in the sine's vertical plane (any tilt).
// Or one `gaussian` height field lit straight down, the floor before the bump's first focus, the receiver
// seeing only light that entered through the water's rectangle. Or one dielectric sphere lit straight down
// over a horizontal floor, without Fresnel reflection (BallLens).
AnalyticTruth analytic_truth(const FrameGeometry& frame, const ReceiverChart& chart);

// A histogram of a 1-D mapping x -> X of source strips: each strip's flux is spread uniformly over its
// image interval [X_a, X_b], which is exact where the map is linear over the strip (fine strips).
class StripHistogram {
public:
    StripHistogram(double lo, double hi, int bins)
        : lo_(lo), bin_w_((hi - lo) / bins), bins_(bins), flux_(static_cast<std::size_t>(bins), 0.0) {}

    void add(double X_a, double X_b, double flux) {
        const double a = std::min(X_a, X_b), b = std::max(X_a, X_b);
        const double fa = (a - lo_) / bin_w_, fb = (b - lo_) / bin_w_;
        if (!(fb >= 0.0 && fa < bins_)) return;   // wholly outside (or NaN)
        if (b - a < 1e-15) {                       // a focus on the strip: all flux in one bin
            const int i = static_cast<int>(std::floor(fa));
            if (i >= 0 && i < bins_) flux_[static_cast<std::size_t>(i)] += flux;
            return;
        }
        const int i0 = std::max(0, static_cast<int>(std::floor(fa)));
        const int i1 = std::min(bins_ - 1, static_cast<int>(std::floor(fb)));
        if (i0 == i1) {
            const double overlap = std::min(fb, i0 + 1.0) - std::max(fa, static_cast<double>(i0));
            flux_[static_cast<std::size_t>(i0)] += flux * overlap / (fb - fa);
            return;
        }
        for (int i = i0; i <= i1; ++i) {
            const double overlap = std::min(fb, i + 1.0) - std::max(fa, static_cast<double>(i));
            if (overlap > 0.0) flux_[static_cast<std::size_t>(i)] += flux * overlap / (fb - fa);
        }
    }
    const std::vector<double>& flux() const { return flux_; }   // per bin; divide by the bin's measure
    double bin_width() const { return bin_w_; }

private:
    double lo_, bin_w_;
    int bins_;
    std::vector<double> flux_;
};

// Flux per each of `bins` equal intervals of [lo, hi] of a 1-D mapping x0 -> map(x0) of a source of
// density weight(x0) per unit x0 over [src_lo, src_hi], cut into `segments` equal strips (weight at the
// strip's midpoint). Divide by the interval length for the bin-averaged density.
template <class Map, class Weight>
std::vector<double> bin_average_1d(Map map, Weight weight, double src_lo, double src_hi, std::size_t segments,
                                   double lo, double hi, int bins) {
    StripHistogram histogram(lo, hi, bins);
    double x_prev = src_lo, X_prev = map(src_lo);
    for (std::size_t s = 1; s <= segments; ++s) {
        const double x = src_lo + (src_hi - src_lo) * static_cast<double>(s) / static_cast<double>(segments);
        const double X = map(x);
        histogram.add(X_prev, X, weight(0.5 * (x + x_prev)) * (x - x_prev));
        x_prev = x;
        X_prev = X;
    }
    return histogram.flux();
}

// The sine surface and its light in their common vertical plane: s along the sine's direction, z up.
struct SinePlane {
    double amplitude = 0.0, k = 1.0, offset = 0.0;  // h(s) = amplitude sin(k s + offset)
    double base = 0.0;                              // z of the mean surface
    double s_lo = 0.0, s_hi = 0.0;                  // the water's extent along s
    double ior = 1.33, absorption = 0.0;            // water index (air above: 1) and Beer-Lambert Ka [1/m]
    bool fresnel = false;                           // multiply by the unpolarised Fresnel transmittance
    double light_s = 0.0, light_z = -1.0;           // unit direction the light travels (light_z < 0)
    double irradiance = 1.0;                        // E0 on a plane perpendicular to the light [W/m^2]
    double floor_z = -1.0;                          // the receiver's height (below base - |amplitude|)

    double height(double s) const { return base + amplitude * std::sin(k * s + offset); }
    double slope(double s) const { return amplitude * k * std::cos(k * s + offset); }

    // The ray entering the water at s (shadowing by other crests aside).
    struct Strip {
        bool front = false;         // the light hits the upper side: d . n < 0
        bool tir = false;           // no transmitted ray (index below 1 only)
        double z = 0.0;             // surface height at s
        double density = 0.0;       // flux per unit s and unit width reaching the floor [W/m^2]:
                                    // E0 (d . -n_unnormalised) T_fresnel exp(-Ka L); 0 unless front
        double landing = 0.0;       // s where the refracted ray meets the floor
        double dir_s = 0.0, dir_z = -1.0;      // refracted direction (unit)
        double refl_s = 0.0, refl_z = 1.0;     // reflected direction (unit)
    };
    Strip trace(double s) const;

    // Whether the ray leaving the surface point at s along (dir_s, dir_z) meets the surface again inside
    // the water's extent; `below` says on which side of the surface it leaves (refracted: below).
    bool meets_surface_again(double s, double dir_s, double dir_z, bool below) const;
};

// The 1-D profile: flux per unit width landing in each of `bins` equal intervals of [lo, hi] along s
// (shadowed and back-facing strips carry none). False with `reason` when a refracted ray (or, with
// Fresnel, a reflected one) would meet the surface again, or the light is not transmitted downwards.
// segments = 0 chooses the default sampling (see analytic_truth.cpp for why it suffices).
bool sine_profile(const SinePlane& plane, double lo, double hi, int bins, std::size_t segments,
                  std::vector<double>& flux, std::string& reason);

// The default number of source strips for a profile with bins of width bin_w along s.
std::size_t sine_profile_segments(const SinePlane& plane, double bin_w);

// The Gaussian bump h(r) = base + A exp(-r^2 / (2 sigma^2)) lit straight down, in a vertical plane through
// its axis: r the distance from the axis (analytic_truth_radial.cpp).
struct RadialProfile;
struct RadialBump {
    double amplitude = 0.0, sigma = 0.1, base = 0.0;
    double ior = 1.33, absorption = 0.0;
    bool fresnel = false;
    double irradiance = 1.0;   // E0 [W/m^2], the light along -z
    double floor_z = -1.0;

    double height(double r) const { return base + amplitude * std::exp(-0.5 * r * r / (sigma * sigma)); }
    double slope(double r) const { return -amplitude * r / (sigma * sigma) * std::exp(-0.5 * r * r / (sigma * sigma)); }
    struct Ray {
        bool ok = false;       // transmitted downwards
        double landing = 0.0;  // radius R where the refracted ray meets the floor (signed: < 0 across the axis)
        double density = 0.0;  // flux per unit horizontal area at r that reaches the floor [W/m^2]
    };
    Ray trace(double r) const;
    // The map r -> R on [0, r_max]; false with the reason where it is not increasing (past the focus).
    bool profile(double r_max, RadialProfile& out, std::string& reason) const;
};
struct RadialProfile {
    std::vector<double> r, R, density;
    // E(R) = density(r) r / (R dR/dr) at the preimage r of R.
    double irradiance(double R) const;
};
// A dielectric sphere (ball lens) lit straight down over a horizontal floor, in a meridional plane: h the
// entry point's distance from the axis (analytic_truth_ball.cpp). Without Fresnel reflection (scene.fresnel
// false) every entering ray is refracted twice and nothing else: the closed form is exact.
struct BallLens {
    double radius = 0.5, ior = 1.5, absorption = 0.0;
    bool fresnel = false;      // multiply by both interfaces' transmittance (for tests of the map alone)
    double irradiance = 1.0;   // E0 [W/m^2], the light along -z
    double depth = 1.0;        // floor below the centre
    struct Ray {
        bool ok = false;             // reaches the floor
        double landing = 0.0;        // signed radius on the floor
        double transmittance = 1.0;  // Fresnel (if on) and absorption along the chord
    };
    Ray trace(double h) const;
    // Caustic irradiance per radial bin of width r_max / bins on the floor (the light through the ball;
    // the direct light around it is not caustic).
    std::vector<double> radial_irradiance(double r_max, int bins) const;
};

// Bin averages of a receiver map that depends on the horizontal offset P from `centre` only through
// f(P) (the radial truths): the mean of f over sub x sub sub-points per bin. NaN where f is.
template <class F>
Image bin_average_around(const ReceiverChart& chart, const glm::dvec2& centre, int sub, F f) {
    Image out(chart.width(), chart.height(), 1);
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) {
            double sum = 0.0;
            for (int b = 0; b < sub; ++b)
                for (int a = 0; a < sub; ++a) {
                    const double s = (i + (a + 0.5) / sub) / chart.width(), t = (j + (b + 0.5) / sub) / chart.height();
                    sum += f(glm::dvec2(chart.point(s, t)) - centre);
                }
            out.at(i, j) = static_cast<float>(sum / (sub * sub));
        }
    return out;
}

struct ObjectInstance;
AnalyticTruth ball_lens_truth(const FrameGeometry& frame, const ReceiverChart& chart, const ObjectInstance& ball);
AnalyticTruth radial_bump_truth(const FrameGeometry& frame, const ReceiverChart& chart, const ObjectInstance& water);

}  // namespace caustics
