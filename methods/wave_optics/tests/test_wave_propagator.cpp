// wave_optics' propagation (Stam 1996): the Fresnel and angular-spectrum propagators (energy, the removed
// band, Talbot self-imaging, cached transfer functions, fractional carriers), the surface table, and the
// refracted screen against the exact refraction of a sine.
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
#include <tbb/global_control.h>

#include "../refracted_screen.hpp"
#include "../regime.hpp"
#include "../wave_field_table.hpp"
#include "../wave_propagator.hpp"
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/blocks/fft/fft.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/run/metrics.hpp>
#include "naive_dft.hpp"
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/scene.hpp>
#include <caustics/scene/water_scene.hpp>

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
// must equal the bilinear path bit for bit. A surface whose edges do not match gets a border (its window is
// larger, so its samples are off the vertices) and takes the bilinear path either way.
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
            EXPECT_EQ(a.window.periodic, periodic);
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
// Oblique light and the geometric-optics limit

// The exact refraction of a 1-D sine h = A sin(k x) at x: unit refracted direction (x, z components).
glm::dvec2 exact_refracted(double A, double k, double x, glm::dvec2 d, double n) {
    const double g = A * k * std::cos(k * x);
    const glm::dvec2 nn = glm::dvec2(-g, 1.0) / std::sqrt(1.0 + g * g);
    const double ci = -glm::dot(d, nn);
    const double ct = std::sqrt(1.0 - (1.0 - ci * ci) / (n * n));
    return d / n + (ci / n - ct) * nn;
}

TEST(RefractedScreen, PhaseGradientIsTheExactRefractedWaveVectorAndDensityTheExactFlux) {
    // A sine along x lit 30 degrees off vertical: at each node X of the plane, the screen's phase gradient
    // (dP/dX = n t_x - d_x, the eikonal property) and flux density must be those of the exact ray that
    // crosses the plane at X, found independently by bisection of X(x_s) = x_s + h t_x / |t_z|.
    const double A = 0.01, L = 1.25, k = 2.0 * kPi / 0.25, n = 1.33;
    const int nx = 1024, ny = 4;
    const glm::dvec2 d(0.5, -std::sqrt(0.75));
    wave_optics::RefractionSetup rs;
    rs.nx = nx;
    rs.ny = ny;
    rs.lx = L;
    rs.ly = L * ny / nx;
    rs.light = glm::dvec3(d.x, 0.0, d.y);
    rs.ior = n;
    std::vector<float> h(static_cast<std::size_t>(nx) * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) h[static_cast<std::size_t>(j) * nx + i] = static_cast<float>(A * std::sin(k * i * L / nx));
    wave_optics::RefractedScreen screen;
    wave_optics::build_refracted_screen(h.data(), rs, screen);
    EXPECT_EQ(screen.folded_cells, 0);
    EXPECT_EQ(screen.unlit_cells, 0);
    auto crossing = [&](double xs) {
        const glm::dvec2 t = exact_refracted(A, k, xs, d, n);
        return xs + A * std::sin(k * xs) * t.x / -t.y;
    };
    const double dx = L / nx;
    double worst_gradient = 0.0, worst_density = 0.0, mean_density = 0.0;
    for (int i = 0; i < nx; ++i) mean_density += std::pow(screen.amplitude[static_cast<std::size_t>(i)], 2) / nx;
    for (int i = 1; i + 1 < nx; i += 7) {
        const double X = i * dx;
        double lo = X - 0.02, hi = X + 0.02;
        for (int it = 0; it < 80; ++it) ((crossing(0.5 * (lo + hi)) < X) ? lo : hi) = 0.5 * (lo + hi);
        const double xs = 0.5 * (lo + hi);
        const glm::dvec2 t = exact_refracted(A, k, xs, d, n);
        const double dPdX = (screen.path[static_cast<std::size_t>(i + 1)] - screen.path[static_cast<std::size_t>(i - 1)]) / (2.0 * dx);
        worst_gradient = std::max(worst_gradient, std::abs(dPdX - (n * t.x - d.x)));
        const double e = 1e-6;
        const double jac = (crossing(xs + e) - crossing(xs - e)) / (2.0 * e);
        const double density = (-d.y + d.x * A * k * std::cos(k * xs)) / (-d.y * jac);
        worst_density = std::max(worst_density, std::abs(std::pow(screen.amplitude[static_cast<std::size_t>(i)], 2) - density));
    }
    // The deflection n t_x - d_x varies by +-0.09 and the density by +-0.15 over the sine.
    EXPECT_LT(worst_gradient, 2e-4);
    EXPECT_LT(worst_density, 2e-3);
    EXPECT_NEAR(mean_density, 1.0, 1e-4);   // flux conservation
}

TEST(RefractedScreen, IndexOneIsExactlyFlat) {
    const int n = 64;
    wave_optics::RefractionSetup rs;
    rs.nx = rs.ny = n;
    rs.light = glm::normalize(glm::dvec3(0.4, -0.2, -1.0));
    rs.ior = 1.0;
    rs.fresnel = true;
    const std::vector<float> h = random_surface(n, 3, 7);
    std::vector<float> scaled(h.size());
    for (std::size_t k = 0; k < h.size(); ++k) scaled[k] = 0.05f * h[k];
    wave_optics::RefractedScreen screen;
    wave_optics::build_refracted_screen(scaled.data(), rs, screen);
    for (std::size_t k = 0; k < h.size(); ++k) {
        ASSERT_NEAR(screen.path[k], 0.0f, 1e-9f);
        ASSERT_NEAR(screen.amplitude[k], 1.0f, 1e-5f);
    }
}

TEST(WavePropagator, FractionalCarrierMatchesTheDoubledPeriod) {
    // A carrier half-way between lattice frequencies of period L is on the lattice of period 2L: the same
    // periodic field (tiled twice) must give the same intensity. A carrier snapped to the lattice of L
    // tilts the light and shifts the pattern.
    const int n = 128;
    std::vector<ComplexF> field(static_cast<std::size_t>(n) * n), doubled(static_cast<std::size_t>(4) * n * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double phase = 2.0 * std::sin(2.0 * kPi * i / n) + 1.5 * std::cos(2.0 * kPi * 2.0 * j / n + 0.3);
            const ComplexF v = std::polar(1.0f, static_cast<float>(phase));
            field[static_cast<std::size_t>(j) * n + i] = v;
            for (int b = 0; b < 2; ++b)
                for (int a = 0; a < 2; ++a) doubled[static_cast<std::size_t>(j + b * n) * 2 * n + i + a * n] = v;
        }
    for (Propagator prop : {Propagator::AngularSpectrum, Propagator::Fresnel}) {
        WaveSetup s;
        s.nx = s.ny = n;
        s.lx = s.ly = 1.0;
        s.wavelength = 2.0 / n;
        s.propagator = prop;
        s.carrier_bins = {20.5, -7.5};
        WavePropagator p(s, FftRigor::Estimate);
        WaveSetup s2 = s;
        s2.nx = s2.ny = 2 * n;
        s2.lx = s2.ly = 2.0;
        s2.carrier_bins = {41.0, -15.0};
        WavePropagator p2(s2, FftRigor::Estimate);
        p.set_field(field.data());
        p2.set_field(doubled.data());
        std::vector<float> a(static_cast<std::size_t>(n) * n), b(static_cast<std::size_t>(4) * n * n);
        IntensityTarget ta{a.data(), 1.0f, true}, tb{b.data(), 1.0f, true};
        p.propagate(0.2, &ta, 1);
        p2.propagate(0.2, &tb, 1);
        double worst = 0.0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                worst = std::max(worst, std::abs(static_cast<double>(a[static_cast<std::size_t>(j) * n + i]) -
                                                 b[static_cast<std::size_t>(j) * 2 * n + i]));
        EXPECT_LT(worst, 1e-4) << (prop == Propagator::Fresnel ? "fresnel" : "angular spectrum");
        const PropagationStats st = p.propagate(0.2, &ta, 1);
        EXPECT_LT(st.band_limited_energy, 1e-9 * st.total_energy);
    }
}

}  // namespace
}  // namespace caustics
