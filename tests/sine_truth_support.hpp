#pragma once
// Shared by the analytic-truth and baseline tests: a sine water surface over a 1 m floor built in code,
// its vertical-plane model, the Monte Carlo reference with replicas, and the per-column Student-t test
// (Sidak-corrected) that compares a reference with a truth.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <caustics/reference/analytic_truth.hpp>
#include "reference_support.hpp"
#include <caustics/util/statistics.hpp>
#include <caustics/scene/water_scene.hpp>

namespace caustics::test_support {

constexpr double kFamilyAlpha = 1e-3;
constexpr double kPi = std::numbers::pi;

// A sine water surface (direction +x) over a 1 m x 1 m floor at floor_z, light tilted towards +x.
struct SineSetup {
    double tilt_deg = 0.0, floor_z = -0.4, absorption = 0.0, ior = 1.33;
    bool fresnel = false;
    double amplitude = 0.01, wavelength = 0.25;
    HeightGenerator generator = HeightGenerator::Sine;
    double water_lo = -0.6, water_hi = 0.6;   // the water's x extent (y: +-0.6, beyond the floor)
    double floor_size = 1.0;
    double cell = 0.002;   // the mesh cell along the sine (sine.json: 2 mm); across it the mesh is exact
    int bins_x = 128, bins_y = 8;
};

// Flux on the receiver [W]: sum of E * true bin area.
inline double receiver_flux(const Image& e, const ReceiverChart& chart) {
    double total = 0.0;
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) total += e.at(i, j) * chart.bin_area(i, j);
    return total;
}

inline Scene make_sine_scene(const SineSetup& c) {
    WaterOverFloor d;
    const double t = c.tilt_deg * kPi / 180.0;
    d.light_direction = {std::sin(t), 0.0, -std::cos(t)};
    d.ior = c.ior;
    d.absorption = c.absorption;
    d.generator = c.generator;
    d.amplitude = c.amplitude;
    d.wavelength = c.wavelength;
    d.floor_z = c.floor_z;
    d.floor_u = {c.floor_size, 0.0, 0.0};
    d.floor_v = {0.0, 1.0, 0.0};
    Scene s = make_water_scene(d);
    HeightFieldDesc& hf = s.objects[0].heightfield;
    hf.center = {0.5 * (c.water_lo + c.water_hi), 0.0};
    hf.size = {c.water_hi - c.water_lo, 1.2};
    hf.resolution = {static_cast<int>(std::lround(hf.size.x / c.cell)), 8};
    s.receiver.width = c.bins_x;
    s.receiver.height = c.bins_y;
    s.fresnel = c.fresnel;
    return s;
}

// The sine of a set-up in its vertical plane (for geometry and closed forms).
inline SinePlane plane_of(const SineSetup& c) {
    SinePlane p;
    p.amplitude = c.amplitude;
    p.k = 2.0 * kPi / c.wavelength;
    p.ior = c.ior;
    p.absorption = c.absorption;
    p.fresnel = c.fresnel;
    p.light_s = std::sin(c.tilt_deg * kPi / 180.0);
    p.light_z = -std::cos(c.tilt_deg * kPi / 180.0);
    p.floor_z = c.floor_z;
    p.s_lo = c.water_lo;
    p.s_hi = c.water_hi;
    return p;
}

// Places the water over every source point whose refracted ray can land on the floor (plus a margin),
// so that few reference photons are wasted; the truth uses whatever extent the water has. The upstream
// edge is put at a trough: the height field is an open surface, so light passing under a higher edge
// would meet its back-facing underside from below (at grazing light, where slopes exceed cot t) and be
// totally reflected far downstream, an artefact of the open edge rather than of the sine.
inline SineSetup with_water_feeding_floor(SineSetup c, double margin = 0.05) {
    SinePlane p = plane_of(c);
    double lo = 1e9, hi = -1e9;
    for (int i = 0; i < 4096; ++i) {
        const double s = c.wavelength * i / 4096.0;
        const SinePlane::Strip st = p.trace(s);
        if (st.front) lo = std::min(lo, st.landing - s), hi = std::max(hi, st.landing - s);
    }
    const double lo_needed = -0.5 * c.floor_size - hi - margin;
    c.water_lo = c.wavelength * (std::floor((lo_needed + 0.25 * c.wavelength) / c.wavelength) - 0.25);   // sin = -1
    c.water_hi = 0.5 * c.floor_size - lo + margin;
    return c;
}

inline ReferenceResult run_reference(const TracedScene& setup, std::uint64_t photons) {
    ReferenceSettings settings;
    settings.photons = photons;
    settings.replicas = 16;
    settings.camera_view = false;
    settings.progress = false;
    return compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
}

inline std::vector<double> column_means(const Image& img) {
    std::vector<double> m(static_cast<std::size_t>(img.width), 0.0);
    for (int j = 0; j < img.height; ++j)
        for (int i = 0; i < img.width; ++i) m[static_cast<std::size_t>(i)] += img.at(i, j) / img.height;
    return m;
}

// The reference pooled over rows (the sine is 1-D): column means and their standard errors from the
// spread of the replicas' own column means (this keeps any correlation between bins of one replica;
// ReferenceResult::receiver_stderr pooled as independent bins where the replicas are not kept).
struct Columns {
    std::vector<double> mean, se;
    double dof = 0.0;
};
inline Columns reference_columns(const ReferenceResult& ref) {
    Columns c;
    c.mean = column_means(ref.receiver);
    const std::size_t r = ref.receiver_replicas.size();
    c.se.assign(c.mean.size(), 0.0);
    c.dof = static_cast<double>(ref.replicas - 1);
    const Image& se = ref.receiver_stderr;
    if (r >= 2) {
        for (const Image& rep : ref.receiver_replicas) {
            const std::vector<double> m = column_means(rep);
            for (std::size_t i = 0; i < m.size(); ++i) c.se[i] += std::pow(m[i] - c.mean[i], 2) / ((r - 1.0) * r);
        }
    } else {
        for (int j = 0; j < se.height; ++j)
            for (int i = 0; i < se.width; ++i) c.se[static_cast<std::size_t>(i)] += std::pow(se.at(i, j) / se.height, 2);
    }
    for (double& s : c.se) s = std::sqrt(s);
    return c;
}

struct ZTest {
    double worst = 0.0, threshold = 0.0;
    int column = -1, compared = 0;
};
// Columns unlit on both sides, and the one column `skip`, are not compared.
inline ZTest z_test(const Columns& ref, const std::vector<double>& truth, int skip = -1) {
    ZTest t;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (static_cast<int>(i) == skip || (ref.se[i] == 0.0 && truth[i] == 0.0 && ref.mean[i] == 0.0)) continue;
        ++t.compared;
        const double z = ref.se[i] > 0.0 ? std::fabs(ref.mean[i] - truth[i]) / ref.se[i] : 1e300;
        if (z > t.worst) t.worst = z, t.column = static_cast<int>(i);
    }
    t.threshold = student_t_critical(sidak_level(kFamilyAlpha, static_cast<std::size_t>(std::max(t.compared, 1))),
                                     ref.dof);
    return t;
}

// Per-bin Student-t of a reference against an expected map: the largest |ref - expected| / se over the bins
// with a positive standard error (`compared` of them), and the Sidak-corrected threshold at kFamilyAlpha.
struct BinTest {
    double worst = 0.0, threshold = 0.0;
    int compared = 0;
};
inline BinTest bin_test(const ReferenceResult& ref, const Image& expected) {
    BinTest t;
    for (std::size_t i = 0; i < expected.pixels.size(); ++i) {
        const double se = ref.receiver_stderr.pixels[i];
        if (se <= 0.0) continue;
        ++t.compared;
        t.worst = std::max(t.worst, std::fabs(ref.receiver.pixels[i] - expected.pixels[i]) / se);
    }
    t.threshold = student_t_critical(sidak_level(kFamilyAlpha, static_cast<std::size_t>(std::max(t.compared, 1))),
                                     ref.replicas - 1.0);
    return t;
}

inline AnalyticTruth truth_of(const SineSetup& c) {
    TracedScene setup(make_sine_scene(c));
    return analytic_truth(*setup.frame, *setup.chart);
}

// A test case: light tilted in the sine's plane, the water feeding the floor, a 0.25 mm mesh along the sine.
inline SineSetup sine_case(double tilt, double floor_z, double absorption, bool fresnel) {
    SineSetup c;
    c.cell = 0.00025;   // the comparison is about the truth; the 2 mm mesh's own effect: MeshDiscretisation
    c.tilt_deg = tilt;
    c.floor_z = floor_z;
    c.absorption = absorption;
    c.fresnel = fresnel;
    return with_water_feeding_floor(c);
}

}  // namespace caustics::test_support
