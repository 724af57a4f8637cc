#pragma once
// Randomly drawn hard cases for the conformance suite (tests/test_conformance.cpp): sine height fields lit
// in the sine's vertical plane at 0-40 deg, floors 0.2-1.5 m down both before and past the first focus,
// ior 1.0-1.8, absorption 0-0.5 /m; and, one case in five, a radial Gaussian bump lit straight down before
// its focus (where its closed form applies). Each has an exact closed form (harness/reference/analytic_truth).
//
// Case i of seed S depends on (S, i) alone, so that a ctest process of one case and a whole run agree.
// CAUSTICS_CONFORMANCE_SEED sets S (default kDefaultConformanceSeed) and CAUSTICS_CONFORMANCE_CASES the
// number of cases (default 12). Beside each scene the case carries the regime quantities the claims are
// stated in, computed here from the closed-form surface with its own 2-D Snell refraction, independently
// of the methods and of harness/blocks/regime (which works on the sampled height field).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/scene/scene.hpp>
#include "sine_truth_support.hpp"

namespace caustics::test_support {

constexpr std::uint64_t kDefaultConformanceSeed = 20261205;
constexpr int kDefaultConformanceCases = 12;

inline std::uint64_t conformance_seed() {
    const char* s = std::getenv("CAUSTICS_CONFORMANCE_SEED");
    return s && *s ? std::strtoull(s, nullptr, 10) : kDefaultConformanceSeed;
}

// CAUSTICS_CONFORMANCE_ONLY: a comma-separated list of case indices (0 to 100000) to judge instead of the
// first N, to replay or re-measure some cases of a draw. Empty when unset; false (with `error` naming the
// token) when a token is not such an index.
inline bool conformance_only_cases(std::vector<int>& out, std::string& error) {
    out.clear();
    const char* s = std::getenv("CAUSTICS_CONFORMANCE_ONLY");
    if (!s || !*s) return true;
    const std::string all(s);
    std::size_t begin = 0;
    while (begin <= all.size()) {
        const std::size_t comma = std::min(all.find(',', begin), all.size());
        const std::string token = all.substr(begin, comma - begin);
        char* end = nullptr;
        const long v = token.empty() ? -1 : std::strtol(token.c_str(), &end, 10);
        if (token.empty() || *end != '\0' || v < 0 || v > 100000) {
            error = "CAUSTICS_CONFORMANCE_ONLY=" + all + ": '" + token + "' is not a case index (0 to 100000, comma-separated)";
            return false;
        }
        out.push_back(static_cast<int>(v));
        begin = comma + 1;
    }
    return true;
}

inline int conformance_case_count() {
    const char* s = std::getenv("CAUSTICS_CONFORMANCE_CASES");
    const long n = s && *s ? std::strtol(s, nullptr, 10) : kDefaultConformanceCases;
    return static_cast<int>(std::clamp(n, 0L, 100000L));
}

// The quantities a claim's regime may name (RegimeBound::quantity), from the closed form.
struct IndependentRegime {
    double tilt_deg = 0.0;
    double depth = 0.0;                      // below the water's mean level [m]
    double first_focus = 1e300;              // below the mean level [m]; 1e300: none
    double ior = 1.0;
    double depth_over_first_focus() const { return first_focus < 1e299 ? depth / first_focus : 0.0; }
};

struct DrawnCase {
    std::string name, what;
    Scene scene;
    IndependentRegime regime;
};

namespace drawn_detail {

// splitmix64: a well-mixed stream from (seed, index, draw).
inline std::uint64_t mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

class Draws {
public:
    Draws(std::uint64_t seed, int index) : state_(mix(seed ^ mix(static_cast<std::uint64_t>(index) + 1))) {}
    double uniform(double lo, double hi) {
        state_ = mix(state_);
        return lo + (hi - lo) * static_cast<double>(state_ >> 11) * 0x1.0p-53;
    }
    double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }

private:
    std::uint64_t state_;
};

// 2-D Snell refraction from air into index n of the unit direction (ls, lz) at a surface of slope g:
// the refracted run per unit depth dx/(-dz), or NaN where the surface faces away from the light.
inline double refracted_run(double ls, double lz, double g, double n) {
    const double norm = std::sqrt(1.0 + g * g);
    const double ns = -g / norm, nz = 1.0 / norm;            // upward unit normal
    const double cos_i = -(ls * ns + lz * nz);
    if (cos_i <= 0.0) return NAN;
    const double eta = 1.0 / n, cos_t = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)));
    const double ts = eta * ls + (eta * cos_i - cos_t) * ns, tz = eta * lz + (eta * cos_i - cos_t) * nz;
    return ts / -tz;
}

// First focus below the mean level of a 1-D profile h(s) (and, with `radial`, of the surface of
// revolution it describes about s = 0): the smallest depth D > 0 where neighbouring rays cross,
// dX/ds = 1 + h' u + (h + D) u' = 0 with X = s + (h + D) u(s) the landing point of the ray entering at s,
// and for a surface of revolution also the sagittal crossing X = 0 (rays reaching the axis).
template <class Height, class Slope>
double first_focus(Height h, Slope slope, double ls, double lz, double n, double s_lo, double s_hi, bool radial) {
    const int samples = 20000;
    const double ds = (s_hi - s_lo) / samples, eps = 1e-3 * ds;
    double best = 1e300;
    for (int i = 0; i <= samples; ++i) {
        const double s = s_lo + i * ds;
        const double u = refracted_run(ls, lz, slope(s), n);
        const double du = (refracted_run(ls, lz, slope(s + eps), n) - refracted_run(ls, lz, slope(s - eps), n)) / (2 * eps);
        if (!std::isfinite(u) || !std::isfinite(du)) continue;
        if (du < 0.0) {
            const double D = -(1.0 + slope(s) * u) / du - h(s);
            if (D > 0.0) best = std::min(best, D);
        }
        if (radial && s > 0.0 && u < 0.0) {
            const double D = -s / u - h(s);
            if (D > 0.0) best = std::min(best, D);
        }
    }
    return best;
}

inline DrawnCase draw_sine(Draws& d, int index) {
    SineSetup c;
    c.tilt_deg = d.uniform(0.0, 40.0);
    const double depth = d.uniform(0.2, 1.5);
    c.floor_z = -depth;
    c.ior = d.uniform(1.0, 1.8);
    c.absorption = d.uniform(0.0, 0.5);
    c.wavelength = d.log_uniform(0.15, 0.5);
    const double k = 2.0 * kPi / c.wavelength;
    // The amplitude that puts the floor at a drawn multiple of the paraxial normal-incidence focus
    // n / ((n - 1) A k^2), so that cases before and past the first focus both occur; slopes stay below
    // 0.35 (no crest shadows another at 40 deg: tan 40 x 0.35 = 0.29 < 1).
    const double contrast = d.log_uniform(0.25, 4.0);
    const double a_contrast = c.ior > 1.0 + 1e-6 ? contrast * c.ior / ((c.ior - 1.0) * k * k * depth) : 1.0;
    c.amplitude = std::min({a_contrast, 0.35 / k, 0.03});
    c.cell = 0.002;
    c.bins_x = c.bins_y = 256;
    // The shipped scenes' margin (sine.json: 0.125 m beyond the floor), so that methods that taper a
    // non-periodic surface's border are not excluded by the case's construction.
    c = with_water_feeding_floor(c, 0.125);
    DrawnCase out;
    out.scene = make_sine_scene(c);
    out.scene.name = out.scene.path = "drawn_sine_" + std::to_string(index);
    const double t = c.tilt_deg * kPi / 180.0, ls = std::sin(t), lz = -std::cos(t);
    const double A = c.amplitude;
    // The drawn surface's phase: make_sine_scene's water starts at a trough of sin(k x).
    auto h = [=](double s) { return A * std::sin(k * s); };
    auto g = [=](double s) { return A * k * std::cos(k * s); };
    out.regime.tilt_deg = c.tilt_deg;
    out.regime.depth = depth;
    out.regime.ior = c.ior;
    out.regime.first_focus = first_focus(h, g, ls, lz, c.ior, 0.0, c.wavelength, false);
    char what[256];
    std::snprintf(what, sizeof what,
                  "sine A %.4g m, wavelength %.3g m, tilt %.1f deg, floor %.3g m (%.2f x first focus), ior %.3g, "
                  "absorption %.2f /m",
                  A, c.wavelength, c.tilt_deg, depth, out.regime.depth_over_first_focus(), c.ior, c.absorption);
    out.what = what;
    out.name = out.scene.name;
    return out;
}

inline DrawnCase draw_gaussian(Draws& d, int index) {
    const double ior = d.uniform(1.1, 1.8), A = d.uniform(0.01, 0.05), sigma = d.uniform(0.07, 0.15);
    auto h = [=](double r) { return A * std::exp(-0.5 * r * r / (sigma * sigma)); };
    auto g = [=](double r) { return -A * r / (sigma * sigma) * std::exp(-0.5 * r * r / (sigma * sigma)); };
    IndependentRegime reg;
    reg.ior = ior;
    reg.first_focus = first_focus(h, g, 0.0, -1.0, ior, 0.0, 5.0 * sigma, true);
    // Before the focus (where the closed form applies): 0.2 m to 0.85 of it, at most 1.5 m.
    const double hi = std::min(1.5, 0.85 * reg.first_focus);
    reg.depth = d.uniform(0.2, std::max(0.2, hi));
    WaterOverFloor w;
    w.ior = ior;
    w.generator = HeightGenerator::Gaussian;
    w.amplitude = A;
    w.floor_z = -reg.depth;
    w.water_size = {1.25, 1.25};
    w.water_resolution = 320;
    w.receiver_resolution = 256;
    DrawnCase out;
    out.scene = make_water_scene(w);
    out.scene.objects[0].heightfield.sigma = sigma;
    out.scene.name = out.scene.path = "drawn_gaussian_" + std::to_string(index);
    // The mean level of the bump's patch (the depth is measured from it, as the claims do).
    const double patch = 1.25, mean_height = A * 2.0 * kPi * sigma * sigma * std::pow(std::erf(patch / (2.0 * std::sqrt(2.0) * sigma)), 2) / (patch * patch);
    reg.depth += mean_height;
    reg.first_focus += mean_height;
    out.regime = reg;
    char what[256];
    std::snprintf(what, sizeof what, "gaussian A %.4g m, sigma %.3g m, floor %.3g m (%.2f x first focus), ior %.3g", A,
                  sigma, -w.floor_z, reg.depth_over_first_focus(), ior);
    out.what = what;
    out.name = out.scene.name;
    return out;
}

}  // namespace drawn_detail

// Case `index` of `seed`. A sine whose closed form is refused (a refracted ray meeting the surface again)
// is drawn again from the same stream.
inline DrawnCase drawn_case(std::uint64_t seed, int index) {
    drawn_detail::Draws d(seed, index);
    if (d.uniform(0.0, 1.0) < 0.2) return drawn_detail::draw_gaussian(d, index);
    for (int attempt = 0;; ++attempt) {
        DrawnCase c = drawn_detail::draw_sine(d, index);
        if (attempt >= 16) return c;
        TracedScene traced(c.scene);
        if (analytic_truth(*traced.frame, *traced.chart).available) return c;
    }
}

}  // namespace caustics::test_support
