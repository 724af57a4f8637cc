// Tests of the wave_optics method (Stam 1996): propagators, the surface table and the plugin.
#include <cmath>
#include <cstdio>
#include <complex>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../methods/wave_optics/wave_field_table.hpp"
#include "../methods/wave_optics/wave_propagator.hpp"
#include "errors.hpp"
#include "fft.hpp"
#include "frame.hpp"
#include "metrics.hpp"
#include "naive_dft.hpp"
#include "ray_tracer.hpp"
#include "receiver_chart.hpp"
#include "reference.hpp"
#include "registry.hpp"
#include "scene.hpp"
#include "water_scene.hpp"

namespace caustics {
namespace {

using test_support::naive_dft;
using wave_optics::IntensityTarget;
using wave_optics::Propagator;
using wave_optics::PropagationStats;
using wave_optics::WavePropagator;
using wave_optics::WaveSetup;
constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------------------------------
// Propagator

std::vector<float> random_surface(int n, double smooth_cells, unsigned seed) {
    // White noise smoothed by a periodic box filter, twice.
    std::mt19937 rng(seed);
    std::normal_distribution<double> g;
    std::vector<double> h(static_cast<std::size_t>(n) * n);
    for (double& v : h) v = g(rng);
    const int r = static_cast<int>(smooth_cells);
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<double> t(h.size(), 0.0);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                for (int d = -r; d <= r; ++d)
                    t[static_cast<std::size_t>(y) * n + x] += h[static_cast<std::size_t>(y) * n + (x + d + n) % n];
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                double s = 0.0;
                for (int d = -r; d <= r; ++d) s += t[static_cast<std::size_t>((y + d + n) % n) * n + x];
                h[static_cast<std::size_t>(y) * n + x] = s / ((2 * r + 1) * (2 * r + 1));
            }
    }
    return std::vector<float>(h.begin(), h.end());
}

double mean_of(const std::vector<float>& v) {
    double s = 0.0;
    for (float x : v) s += x;
    return s / v.size();
}

TEST(WavePropagator, FresnelConservesEnergyForAnySurface) {
    const int n = 128;
    for (unsigned seed : {1u, 2u, 3u}) {
        WaveSetup s;
        s.nx = s.ny = n;
        s.lx = s.ly = 2.0;
        s.wavelength = 2.0 * s.lx / n;
        s.propagator = Propagator::Fresnel;
        s.carrier_bins = {static_cast<int>(seed) * 3, -2};
        WavePropagator p(s, FftRigor::Estimate);
        const std::vector<float> h = random_surface(n, 1 + seed, seed);
        p.set_phase_screen(h.data(), 40.0f);   // several radians of phase
        for (double z : {0.05, 0.4, 3.0}) {
            std::vector<float> I(static_cast<std::size_t>(n) * n);
            IntensityTarget t{I.data(), 1.0f, true};
            p.propagate(z, &t, 1);
            EXPECT_NEAR(mean_of(I), 1.0, 1e-6) << "seed " << seed << " depth " << z;
        }
    }
}

TEST(WavePropagator, AngularSpectrumLosesExactlyTheRemovedComponents) {
    const int n = 64;
    const double L = 1.0, lambda = 2.0 * L / n;
    std::mt19937 rng(11);
    std::vector<float> h(static_cast<std::size_t>(n) * n);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (float& v : h) v = static_cast<float>(u(rng));   // rough: plenty of energy at high frequencies
    const float scale = 1.5f;
    for (glm::ivec2 carrier : {glm::ivec2(0, 0), glm::ivec2(7, -4)}) {
        WaveSetup s;
        s.nx = s.ny = n;
        s.lx = s.ly = L;
        s.wavelength = lambda;
        s.propagator = Propagator::AngularSpectrum;
        s.carrier_bins = carrier;
        WavePropagator p(s, FftRigor::Estimate);
        p.set_phase_screen(h.data(), scale);
        // The field's spectrum, independently: double precision, naive DFT.
        std::vector<std::complex<double>> field(h.size());
        for (std::size_t k = 0; k < h.size(); ++k) field[k] = std::polar(1.0, double(scale * h[k]));
        const auto U = naive_dft(field, n, n, -1);
        const glm::dvec2 fc(carrier.x / L, carrier.y / L);
        const double kzc = std::sqrt(1.0 / (lambda * lambda) - glm::dot(fc, fc));
        const glm::dvec2 walk = fc / kzc;
        for (double z : {0.05, 0.3, 1.0}) {
            double total = 0.0, removed = 0.0, evanescent = 0.0, limited = 0.0;
            for (int iy = 0; iy < n; ++iy)
                for (int ix = 0; ix < n; ++ix) {
                    const double e = std::norm(U[static_cast<std::size_t>(iy) * n + ix]);
                    total += e;
                    const double fx = WavePropagator::signed_index(ix, n) / L + fc.x;
                    const double fy = WavePropagator::signed_index(iy, n) / L + fc.y;
                    const double kz2 = 1.0 / (lambda * lambda) - fx * fx - fy * fy;
                    if (kz2 <= 0.0) {
                        evanescent += e;
                        continue;
                    }
                    const double kz = std::sqrt(kz2);
                    // Matsushima & Shimobaba: walk relative to the carrier within half a period.
                    if (z * std::abs(fx / kz - walk.x) > L / 2 || z * std::abs(fy / kz - walk.y) > L / 2) limited += e;
                }
            removed = evanescent + limited;
            std::vector<float> I(h.size());
            IntensityTarget t{I.data(), 1.0f, true};
            const PropagationStats st = p.propagate(z, &t, 1);
            const double expected = 1.0 - removed / total;
            EXPECT_NEAR(mean_of(I), expected, 1e-6) << "depth " << z;
            EXPECT_NEAR(st.lost_fraction(), removed / total, 1e-6);
            EXPECT_NEAR(st.evanescent_energy / st.total_energy, evanescent / total, 1e-6);
            EXPECT_GT(removed / total, 1e-3) << "the test surface must actually lose energy";
            if (z == 1.0) {
                EXPECT_GT(limited / total, 1e-3) << "the band limit must be active";
            }
        }
    }
}

TEST(WavePropagator, TalbotSelfImagingWithFresnel) {
    const int n = 64;
    const double L = 1.0, p_period = L / 4.0, lambda = 2.0 * L / n;
    const double talbot = 2.0 * p_period * p_period / lambda;
    WaveSetup s;
    s.nx = s.ny = n;
    s.lx = s.ly = L;
    s.wavelength = lambda;
    s.propagator = Propagator::Fresnel;
    WavePropagator prop(s, FftRigor::Estimate);
    std::vector<float> h(static_cast<std::size_t>(n) * n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            h[static_cast<std::size_t>(y) * n + x] = static_cast<float>(std::sin(2.0 * kPi * (x * L / n) / p_period));
    prop.set_phase_screen(h.data(), 0.3f);   // phase amplitude 0.3 rad
    auto intensity = [&](double z) {
        std::vector<float> I(h.size());
        IntensityTarget t{I.data(), 1.0f, true};
        prop.propagate(z, &t, 1);
        return I;
    };
    auto contrast = [](const std::vector<float>& I) {
        const auto [lo, hi] = std::minmax_element(I.begin(), I.end());
        return (*hi - *lo) / (*hi + *lo);
    };
    const std::vector<float> at_talbot = intensity(talbot);
    for (float v : at_talbot) ASSERT_NEAR(v, 1.0f, 2e-6f);
    const double quarter = contrast(intensity(talbot / 4.0));
    EXPECT_GT(quarter, 0.5);   // weak grating: contrast ~ 2 * 0.3 * 2 sin(pi/2) = 1.2, capped below 1
    for (int k = 1; k < 32; ++k) {
        const double z = talbot * k / 64.0;   // (0, talbot / 2)
        if (k == 8) continue;
        EXPECT_LT(contrast(intensity(z)), quarter + 1e-6) << "z / z_T = " << z / talbot;
    }
}

TEST(WavePropagator, CachedTransferFunctionsMatchAFreshPropagator) {
    // Depth changes back and forth: the second propagation to z1 uses the cached transfer function and
    // must give exactly what a new propagator (nothing cached) computes; a changed parameter (the
    // wavelength) builds a new propagator and a different result.
    const int n = 128;
    WaveSetup s;
    s.nx = s.ny = n;
    s.lx = s.ly = 2.0;
    s.wavelength = 2.0 * s.lx / n;
    s.carrier_bins = {3, -1};
    const std::vector<float> h = random_surface(n, 3, 5);
    auto intensity = [&](WavePropagator& p, double z) {
        std::vector<float> I(static_cast<std::size_t>(n) * n);
        IntensityTarget t{I.data(), 1.0f, true};
        p.propagate(z, &t, 1);
        return I;
    };
    WavePropagator p(s, FftRigor::Estimate);
    p.set_phase_screen(h.data(), 40.0f);
    const std::vector<float> first = intensity(p, 0.3);
    const std::vector<float> other = intensity(p, 0.5);
    const std::vector<float> again = intensity(p, 0.3);
    WavePropagator fresh(s, FftRigor::Estimate);
    fresh.set_phase_screen(h.data(), 40.0f);
    EXPECT_EQ(again, first);
    EXPECT_EQ(intensity(fresh, 0.3), first);
    EXPECT_EQ(intensity(fresh, 0.5), other);
    EXPECT_NE(first, other);
    s.wavelength *= 1.5;
    WavePropagator longer(s, FftRigor::Estimate);
    longer.set_phase_screen(h.data(), 40.0f);
    EXPECT_NE(intensity(longer, 0.3), first);
}

// A surface of grid (or a multiple of grid) cells puts every grid sample on a vertex: the copy path
// must equal the bilinear path bit for bit, tapered (edges that do not match) or not.
TEST(WaveFieldTable, OnVertexCopyEqualsBilinearResampling) {
    using wave_optics::WaveFieldTable;
    for (int step : {1, 2}) {
        for (bool periodic : {true, false}) {
            const int grid = 64, vertices = grid * step + 1;
            HeightField hf;
            hf.nx = hf.ny = vertices;
            hf.spacing = glm::dvec2(2.0 / (vertices - 1));
            hf.periodic = periodic;
            std::mt19937 rng(step * 2 + periodic);
            std::normal_distribution<float> g;
            hf.height.resize(static_cast<std::size_t>(vertices) * vertices);
            for (float& v : hf.height) v = 0.3f + 0.01f * g(rng);
            WaveFieldTable copy(grid, grid, false), bilinear(grid, grid, false);
            const auto& a = copy.resample(hf, 2.0, 2.0, WaveFieldTable::ResamplePath::Auto);
            const auto& b = bilinear.resample(hf, 2.0, 2.0, WaveFieldTable::ResamplePath::Bilinear);
            EXPECT_EQ(a.periodic, periodic);
            EXPECT_EQ(a.level, b.level);
            EXPECT_EQ(a.height, b.height) << "step " << step << " periodic " << periodic;
            // The copy really is the vertex grid: sample (i, j) is vertex (i step, j step), less the level.
            if (periodic) {
                EXPECT_EQ(a.height[5 * grid + 7], static_cast<float>(hf.z(7 * step, 5 * step) - static_cast<float>(a.level)))
                    << "step " << step;
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// The method on scenes

Scene water_scene(HeightGenerator gen, double amplitude, double floor_z, glm::dvec3 light_dir,
                  int receiver_res, double floor_size = 2.0) {
    WaterOverFloor d;
    d.name = "test_wave_optics";
    d.light_direction = light_dir;
    d.water_resolution = 256;
    d.generator = gen;
    d.amplitude = amplitude;
    d.floor_z = floor_z;
    d.floor_u = {floor_size, 0.0, 0.0};
    d.floor_v = {0.0, floor_size, 0.0};
    d.receiver_resolution = receiver_res;
    return make_water_scene(d);
}

std::unique_ptr<Method> make_method(const std::map<std::string, std::string>& overrides) {
    const MethodInfo& info = require_method("wave_optics");
    return info.create(ParamSet::resolve(info.name, info.params, overrides));
}

CausticOutput render_receiver(const Scene& scene, const std::map<std::string, std::string>& overrides) {
    auto m = make_method(overrides);
    EXPECT_TRUE(m->capabilities(scene).supported) << m->capabilities(scene).reason;
    m->prepare(scene);
    FrameGeometry frame = build_frame_geometry(scene, 0);
    ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    RenderRequest req;
    req.receiver = &chart;
    m->update(frame);
    return m->render(frame, req);
}

double image_mean(const Image& im) {
    double s = 0.0;
    for (float v : im.pixels) s += v;
    return s / im.pixels.size();
}

TEST(WaveOptics, IsRegisteredWithTheConventionalAxes) {
    const MethodInfo* info = find_method("wave_optics");
    ASSERT_NE(info, nullptr);
    EXPECT_TRUE(info->radiometric);
    bool grid = false, iterations = false;
    for (const ParamSpec& p : info->params) {
        grid |= p.name == "grid";
        iterations |= p.name == "iterations";
    }
    EXPECT_TRUE(grid && iterations);
}

TEST(WaveOptics, FlatSurfaceGivesExactlyUniformIrradiance) {
    for (const char* prop : {"angular_spectrum", "fresnel"}) {
        for (glm::dvec3 dir : {glm::dvec3(0, 0, -1), glm::dvec3(0.3, -0.2, -1)}) {
            const Scene scene = water_scene(HeightGenerator::Flat, 0.0, -0.4, dir, 64, 1.0);
            const CausticOutput out = render_receiver(scene, {{"grid", "128"}, {"propagator", prop}});
            const double expected = -glm::normalize(dir).z;   // E0 cos(theta_i), no Fresnel, no absorption
            for (float v : out.receiver.pixels) ASSERT_EQ(v, out.receiver.pixels.front()) << prop;
            EXPECT_NEAR(out.receiver.pixels.front(), expected, 1e-6) << prop;
        }
    }
}

TEST(WaveOptics, FresnelMeanIrradianceIsTheTransmittedIrradiance) {
    // The receiver covers one period of the surface with one bin per grid sample (bin centres half a
    // cell off the grid), so its mean is the grid's mean intensity: Parseval.
    const Scene scene = water_scene(HeightGenerator::Sine, 0.01, -0.4, {0, 0, -1}, 256, 2.0);
    const CausticOutput out = render_receiver(scene, {{"grid", "256"}, {"propagator", "fresnel"}});
    EXPECT_NEAR(image_mean(out.receiver), 1.0, 1e-6);
    EXPECT_EQ(out.health.get("sampling_violations"), 0);
    EXPECT_EQ(out.health.get("nonperiodic_surface"), 0);
    double lo = 1e9, hi = -1e9;
    for (float v : out.receiver.pixels) {
        lo = std::min<double>(lo, v);
        hi = std::max<double>(hi, v);
    }
    EXPECT_GT(hi - lo, 0.5) << "the sine surface should focus light";
}

TEST(WaveOptics, ObliqueLightReportsTheCarrierSnap) {
    const Scene scene = water_scene(HeightGenerator::Sine, 0.01, -0.4, {0.3, 0.1, -1}, 64, 1.0);
    const CausticOutput out = render_receiver(scene, {{"grid", "256"}});
    EXPECT_GT(out.health.get("carrier_error_urad"), 0);
    EXPECT_LT(out.health.get("carrier_error_urad"), 20000);   // half a lattice step at most: lambda / (2 L)
    EXPECT_EQ(out.health.get("not_covered"), 0);
}

TEST(WaveOptics, DepthSlicesMatchSingleDepthRenders) {
    // A tilted receiver: depths 0.2 .. 0.6 m. The 33-slice table lookup must match a horizontal
    // receiver rendered at one point's exact depth.
    Scene tilted = water_scene(HeightGenerator::Sine, 0.01, -0.4, {0, 0, -1}, 64, 1.0);
    tilted.objects[1].u = {1.0, 0.0, 0.4};   // z from -0.6 to -0.2 along x
    const CausticOutput slices = render_receiver(tilted, {{"grid", "256"}, {"depth_slices", "33"}});
    for (int i : {5, 20, 40}) {
        const double s = (i + 0.5) / 64.0;
        const double z = -0.4 + (s - 0.5) * 0.4;
        Scene flat = water_scene(HeightGenerator::Sine, 0.01, z, {0, 0, -1}, 64, 1.0);
        const CausticOutput one = render_receiver(flat, {{"grid", "256"}});
        // Same x; irradiance on the tilted plane has the extra cosine factor of its normal.
        const double cos_tilt = 1.0 / std::sqrt(1.0 + 0.4 * 0.4);
        for (int j : {0, 31}) {
            const double a = slices.receiver.at(i, j), b = one.receiver.at(i, j) * cos_tilt;
            EXPECT_NEAR(a, b, 0.03 * std::max(1.0, b)) << "bin " << i;
        }
    }
    EXPECT_EQ(slices.health.get("depth_mismatch"), 0);
}

TEST(WaveOptics, RepeatedFramesAndNewScenesMatchFreshMethods) {
    // Transfer functions are kept across frames; they depend on the parameters and depths only. A
    // repeated frame (cached) and a method prepared again on a changed scene (oblique light, another
    // receiver depth) must give exactly what new methods give.
    const Scene first = water_scene(HeightGenerator::Sine, 0.01, -0.4, {0, 0, -1}, 32, 1.0);
    const Scene second = water_scene(HeightGenerator::Sine, 0.01, -0.3, {0.2, 0.1, -1}, 32, 1.0);
    const std::map<std::string, std::string> params{{"grid", "256"}};
    auto render = [](Method& m, const Scene& scene) {
        m.prepare(scene);
        FrameGeometry frame = build_frame_geometry(scene, 0);
        ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
        RenderRequest req;
        req.receiver = &chart;
        m.update(frame);
        return m.render(frame, req).receiver.pixels;
    };
    auto reused = make_method(params);
    const std::vector<float> a1 = render(*reused, first);
    const std::vector<float> a2 = render(*reused, first);
    const std::vector<float> b = render(*reused, second);
    EXPECT_EQ(a2, a1);
    EXPECT_EQ(b, render(*make_method(params), second));
    EXPECT_NE(b, a1);
}

TEST(WaveOptics, BadInputIsRefused) {
    // A wavelength below two grid spacings: grid 256 over 2 m -> two spacings = 15.6 mm.
    const Scene scene = water_scene(HeightGenerator::Sine, 0.01, -0.4, {0, 0, -1}, 32, 1.0);
    auto m = make_method({{"grid", "256"}, {"wavelength", "0.01"}});
    try {
        m->prepare(scene);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.key(), "wavelength");
        EXPECT_NE(std::string(e.what()).find("two grid spacings"), std::string::npos);
    }
    // A grid FFTW plans slowly is refused with the nearest valid sizes.
    try {
        make_method({{"grid", "1031"}});
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.key(), "grid");
        EXPECT_NE(std::string(e.what()).find("1029"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("1050"), std::string::npos) << e.what();
    }
    EXPECT_THROW(make_method({{"iterations", "2"}}), InputError);
    // Not a water scene: a point light.
    Scene point = scene;
    point.lights.front().type = LightType::Point;
    EXPECT_FALSE(make_method({})->capabilities(point).supported);
}

TEST(WaveOptics, GeometricLimitOnSineScene) {
    // scenes/sine.json: as the wavelength shrinks (grid fixed), the error against the ray-optics
    // reference falls.
    const std::string path = std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json";
    Scene scene = load_scene(path);
    FrameGeometry frame = build_frame_geometry(scene, 0);
    RayTracer tracer(frame);
    ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    ReferenceSettings rs;
    rs.photons = 4'000'000;
    rs.camera_view = false;
    rs.progress = false;
    const ReferenceResult ref = load_or_compute_reference(frame, tracer, chart, nullptr, rs, default_cache_dir());
    const double spacing = 2.0 / 1024;
    std::vector<double> errors;
    for (double factor : {16.0, 8.0, 4.0, 2.0}) {
        char text[64];
        std::snprintf(text, sizeof text, "%.17g", factor * spacing);
        auto m = make_method({{"grid", "1024"}, {"wavelength", text}});
        m->prepare(scene);
        RenderRequest req;
        req.receiver = &chart;
        const CausticOutput out = m->render(frame, req);
        const ErrorMetrics e = compare_images(out.receiver, ref.receiver, false);
        errors.push_back(e.nrmse);
        std::printf("wavelength %5.1f grid spacings: nrmse %.4f (reference noise %.4f)\n", factor, e.nrmse,
                    ref.noise_nrmse);
    }
    for (std::size_t k = 1; k < errors.size(); ++k) EXPECT_LT(errors[k], errors[k - 1]);
}

}  // namespace
}  // namespace caustics
