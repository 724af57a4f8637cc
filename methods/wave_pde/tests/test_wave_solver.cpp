// wave_pde's solver (Mercier 2013, Sec. 4): leapfrog energy conservation, the damping band's reflection, the
// sides (mirror, periodic) against the extended domain, thread-count independence, the accumulation window
// and narrow band, and the Courant bound refused through the plugin interface.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <tbb/task_arena.h>

#include "../wave_solver.hpp"
#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>
#include <caustics/blocks/volume/volume_lookup.hpp>
#include "volume_method_support.hpp"

using namespace caustics;

namespace {

VolumeShape cube(int n) {
    VolumeShape s;
    s.nx = s.ny = s.nz = n;
    s.spacing = 1.0;
    return s;
}

std::vector<float> gaussian_pulse(const VolumeShape& s, double width) {
    std::vector<float> u(s.size());
    const glm::dvec3 c = 0.5 * glm::dvec3(s.nx - 1, s.ny - 1, s.nz - 1);
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) {
                const glm::dvec3 d = glm::dvec3(i, j, k) - c;
                u[s.index(i, j, k)] = static_cast<float>(std::exp(-glm::dot(d, d) / (2.0 * width * width)));
            }
    return u;
}

}  // namespace

TEST(WaveSolver, EnergyConservedWithoutDampingAtCourant057) {
    // For each kind of side face: the pulse reaches the faces many times in 10 000 steps.
    const VolumeShape s = cube(20);
    for (const wave::Sides sides : {wave::Sides::Zero, wave::Sides::Mirror, wave::Sides::Periodic}) {
        wave::Settings settings;
        settings.courant = 0.57;
        settings.sponge = 0;
        settings.narrow_band = false;
        settings.sides = sides;
        wave::Simulation sim(s, settings);
        sim.set_initial(gaussian_pulse(s, 2.0));
        sim.step(nullptr);
        const double e0 = sim.energy();
        double worst = 0.0;
        for (int n = 1; n < 10000; ++n) {
            const double m = sim.step(nullptr);
            ASSERT_TRUE(std::isfinite(m));
            if (n % 500 == 0) worst = std::max(worst, std::fabs(sim.energy() - e0) / e0);
        }
        worst = std::max(worst, std::fabs(sim.energy() - e0) / e0);
        std::printf("energy drift over 10000 steps at courant 0.57, sides %d: %.3g (float storage)\n",
                    static_cast<int>(sides), worst);
        EXPECT_GT(e0, 0.0);
        EXPECT_LT(worst, 1e-3) << static_cast<int>(sides);
    }
}

TEST(WaveSolver, SpongeReflectsLessThanOnePercent) {
    // A Gaussian pulse in a 24^3 box: (A) the box with a 12-cell damping band, (B) a domain large enough
    // that nothing comes back from its boundary within the measured time. Reflected energy = energy of
    // A - B inside the box, relative to the initial energy.
    const int box = 24, band = 12, big = 96;
    wave::Settings sa;
    sa.courant = 0.5;
    sa.sponge = band;
    wave::Settings sb = sa;
    sb.sponge = 0;
    const VolumeShape shape_a = cube(box + 2 * band), shape_b = cube(big);
    wave::Simulation a(shape_a, sa), b(shape_b, sb);
    a.set_initial(gaussian_pulse(shape_a, 2.0));
    b.set_initial(gaussian_pulse(shape_b, 2.0));
    const double e0 = a.energy();
    const glm::ivec3 lo(band), hi(band + box), offset((big - box - 2 * band) / 2);
    double worst = 0.0;
    for (int n = 1; n <= 140; ++n) {
        a.step(nullptr);
        b.step(nullptr);
        if (n >= 80 && n % 10 == 0) worst = std::max(worst, a.difference_energy(b, lo, hi, offset) / e0);
    }
    std::printf("sponge reflection (energy in the box, t = 40..70): %.4g\n", worst);
    EXPECT_LT(worst, 0.01);
}

namespace {

// A horizontal Gaussian sheet exp(-d^2 / 2) at height `z0` (cells): the smooth interface initial state.
std::vector<float> sheet(const VolumeShape& s, double z0) {
    std::vector<float> u(s.size(), 0.0f);
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) {
                const double d = k - z0 + 0.3 * std::sin(0.7 * i) * std::cos(0.4 * j);
                if (std::fabs(d) < 3.0) u[s.index(i, j, k)] = static_cast<float>(std::exp(-0.5 * d * d));
            }
    return u;
}

struct SolverRun {
    std::vector<float> accumulated, field;
    std::int64_t cells_updated = 0;
};

SolverRun run_solver(const VolumeShape& s, const wave::Settings& settings, const std::vector<float>& initial, int steps) {
    wave::Simulation sim(s, settings);
    sim.set_initial(initial);
    SolverRun r;
    r.accumulated.assign(s.size(), 0.0f);
    for (int n = 0; n < steps; ++n) sim.step(&r.accumulated);
    sim.flush(&r.accumulated);
    r.field = sim.current();
    r.cells_updated = sim.cells_updated();
    return r;
}

}  // namespace

TEST(WaveSolver, ResultDoesNotDependOnThreadCount) {
    VolumeShape s = cube(40);
    s.nx = 37;  // rows not a multiple of any vector width
    wave::Settings settings;
    settings.sponge = 8;
    for (const bool clamp : {false, true}) {
        settings.clamp_negative = clamp;
        const std::vector<float> init = sheet(s, 27.0);
        SolverRun one, two;
        tbb::task_arena(1).execute([&] { one = run_solver(s, settings, init, 90); });
        tbb::task_arena(2).execute([&] { two = run_solver(s, settings, init, 90); });
        EXPECT_EQ(one.accumulated, two.accumulated) << "clamp " << clamp;
        EXPECT_EQ(one.field, two.field) << "clamp " << clamp;
        EXPECT_EQ(one.cells_updated, two.cells_updated) << "clamp " << clamp;
        // The narrow band skipped work: the sheet had not reached every row yet.
        EXPECT_LT(one.cells_updated, 90LL * static_cast<std::int64_t>(s.size()));
    }
}

TEST(WaveSolver, MirrorAndPeriodicSidesEqualTheExtendedDomain) {
    // A box with mirror (periodic) x and y faces must evolve exactly as the middle of a box three times
    // as wide whose initial field is the box's mirrored (tiled) copies, until the wider box's own
    // faces are felt: the stencil reaches one cell further each step, and they are `box` cells away.
    const int box = 16, nz = 24, steps = box - 1;
    for (const wave::Sides sides : {wave::Sides::Mirror, wave::Sides::Periodic}) {
        VolumeShape small = cube(box), wide = cube(3 * box);
        small.nz = wide.nz = nz;
        // An asymmetric sheet, so a wrong image (mirror for periodic or the reverse) would show.
        auto field = [](double i, double j, int k) {
            const double d = k - 16.0 + 1.5 * std::sin(0.9 * i + 0.3) * std::cos(0.5 * j) + 0.08 * i;
            return std::fabs(d) < 3.0 ? std::exp(-0.5 * d * d) : 0.0;
        };
        // The small box's index of a wide-box index: mirrored or wrapped.
        auto image = [&](int i) {
            const int t = i - box;  // -box .. 2 box - 1
            if (sides == wave::Sides::Periodic) return (t % box + box) % box;
            return t < 0 ? -1 - t : t >= box ? 2 * box - 1 - t : t;
        };
        std::vector<float> a(small.size()), b(wide.size());
        for (int k = 0; k < nz; ++k)
            for (int j = 0; j < box; ++j)
                for (int i = 0; i < box; ++i) a[small.index(i, j, k)] = static_cast<float>(field(i, j, k));
        for (int k = 0; k < nz; ++k)
            for (int j = 0; j < 3 * box; ++j)
                for (int i = 0; i < 3 * box; ++i) b[wide.index(i, j, k)] = a[small.index(image(i), image(j), k)];
        wave::Settings sa;
        sa.sponge = 4;
        sa.sides = sides;
        wave::Settings sb = sa;
        sb.sides = wave::Sides::Zero;
        sb.sponge = 0;  // no band on the wide box's faces: its z faces must match the small box's
        sa.sponge = 0;
        const SolverRun ra = run_solver(small, sa, a, steps), rb = run_solver(wide, sb, b, steps);
        double worst = 0.0, scale = 0.0;
        for (int k = 0; k < nz; ++k)
            for (int j = 0; j < box; ++j)
                for (int i = 0; i < box; ++i) {
                    const double va = ra.accumulated[small.index(i, j, k)];
                    const double vb = rb.accumulated[wide.index(i + box, j + box, k)];
                    worst = std::max(worst, std::fabs(va - vb));
                    scale = std::max(scale, std::fabs(vb));
                }
        std::printf("sides %d vs the extended domain: max |dC| %.3g of %.3g\n", static_cast<int>(sides), worst, scale);
        EXPECT_GT(scale, 1.0);
        EXPECT_LT(worst, 1e-5 * scale) << static_cast<int>(sides);  // float round-off only
    }
}

TEST(WaveSolver, SidesDoNotDependOnThreadCount) {
    // Periodic faces read the opposite face's rows, which another tile owns.
    VolumeShape s = cube(40);
    s.nx = 37;
    for (const wave::Sides sides : {wave::Sides::Mirror, wave::Sides::Periodic}) {
        wave::Settings settings;
        settings.sponge = 8;
        settings.sides = sides;
        const std::vector<float> init = sheet(s, 27.0);
        SolverRun one, two;
        tbb::task_arena(1).execute([&] { one = run_solver(s, settings, init, 90); });
        tbb::task_arena(2).execute([&] { two = run_solver(s, settings, init, 90); });
        EXPECT_EQ(one.accumulated, two.accumulated) << static_cast<int>(sides);
        EXPECT_EQ(one.field, two.field) << static_cast<int>(sides);
    }
}

TEST(WaveSolver, AccumulatesEveryLevelOnce) {
    // The solver adds levels in pairs; with flush() the sum is phi^0 + ... + phi^{N-1} for odd and even N.
    const VolumeShape s = cube(20);
    wave::Settings settings;
    settings.sponge = 5;
    const std::vector<float> init = sheet(s, 12.0);
    for (const int steps : {1, 7, 8}) {
        wave::Simulation sim(s, settings);
        sim.set_initial(init);
        std::vector<float> paired(s.size(), 0.0f);
        std::vector<double> direct(s.size(), 0.0);
        for (int n = 0; n < steps; ++n) {
            for (std::size_t c = 0; c < s.size(); ++c) direct[c] += sim.current()[c];
            sim.step(&paired);
        }
        sim.flush(&paired);
        sim.flush(&paired);  // a second flush adds nothing
        double worst = 0.0;
        for (std::size_t c = 0; c < s.size(); ++c) worst = std::max(worst, std::fabs(paired[c] - direct[c]));
        EXPECT_LT(worst, 1e-5) << steps << " steps";
    }
}

TEST(WaveSolver, WindowKeepsEachLayersSumUpToItsStop) {
    // A front moving down: layer k sums phi^n while k <= top(n). The window zeroes the layers above
    // top(n) + 4; that disturbance moves no faster than the front, so the sums match a run without it.
    const VolumeShape s = cube(40);
    wave::Settings settings;
    settings.sponge = 8;
    const std::vector<float> init = sheet(s, 30.0);
    auto top = [](int n) { return static_cast<int>(std::floor(30.0 - 0.5 * n + 6.0)); };
    wave::Simulation whole(s, settings), window(s, settings);
    whole.set_initial(init);
    window.set_initial(init);
    std::vector<double> direct(s.size(), 0.0);
    std::vector<float> windowed(s.size(), 0.0f);
    const std::size_t layer = static_cast<std::size_t>(s.nx) * s.ny;
    for (int n = 0; top(n) >= 8; ++n) {
        for (std::size_t c = 0; c < static_cast<std::size_t>(top(n) + 1) * layer; ++c) direct[c] += whole.current()[c];
        whole.step(nullptr);
        window.step(&windowed, top(n));
    }
    window.flush(&windowed);
    double worst = 0.0, scale = 0.0;
    for (std::size_t c = 8 * layer; c < s.size(); ++c) {
        worst = std::max(worst, std::fabs(windowed[c] - direct[c]));
        scale = std::max(scale, std::fabs(direct[c]));
    }
    std::printf("window vs whole domain: max |dC| %.3g of max |C| %.3g\n", worst, scale);
    EXPECT_GT(scale, 1.0);
    EXPECT_LT(worst, 1e-3 * scale);
    EXPECT_LT(window.cells_updated(), whole.cells_updated());
}

TEST(WaveSolver, NarrowBandMatchesFullUpdate) {
    const VolumeShape s = cube(32);
    wave::Settings band;
    band.sponge = 8;
    wave::Settings full = band;
    full.narrow_band = false;
    const std::vector<float> init = sheet(s, 22.0);
    const SolverRun a = run_solver(s, band, init, 120), b = run_solver(s, full, init, 120);
    double worst = 0.0, scale = 0.0;
    for (std::size_t c = 0; c < s.size(); ++c) {
        worst = std::max(worst, std::fabs(double(a.accumulated[c]) - b.accumulated[c]));
        scale = std::max(scale, std::fabs(double(b.accumulated[c])));
    }
    std::printf("narrow band vs full update: max |dC| %.3g of max |C| %.3g\n", worst, scale);
    EXPECT_LT(worst, 1e-5 * scale);  // only rows below the 1e-7 band threshold were dropped
    EXPECT_LT(a.cells_updated, b.cells_updated);
}

TEST(WaveSolver, ConvergedSumIsHarmonicOutsideTheBand) {
    // Summing the scheme over all steps (phi -> 0): courant^2 L(C) = -s phi^0, s = sigma dt. Where the
    // band does not damp the initial sheet, the fully converged texture C is harmonic: it carries no
    // caustic. This is why wave_pde stops when the direct front has crossed the volume (stop=arrival).
    const VolumeShape s = cube(24);
    wave::Settings settings;
    settings.sponge = 6;
    wave::Simulation sim(s, settings);
    const std::vector<float> init = sheet(s, 13.0);
    sim.set_initial(init);
    std::vector<float> c(s.size(), 0.0f);
    int steps = 0;
    // Until every |phi| < 1e-5: the dropped remainder of the sum is of that order.
    while (sim.step(&c) > 1e-5 && steps < 200000) ++steps;
    sim.flush(&c);
    ASSERT_LT(steps, 200000);
    double worst = 0.0, scale = 0.0;
    const double lam = settings.courant * settings.courant;
    auto at = [&](int i, int j, int k) -> double {
        return (i < 0 || j < 0 || k < 0 || i >= s.nx || j >= s.ny || k >= s.nz) ? 0.0 : c[s.index(i, j, k)];
    };
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) {
                const int d = std::max({6 - i, i - (s.nx - 7), 6 - j, j - (s.ny - 7), 6 - k, k - (s.nz - 7), 0});
                const double m = d / 6.0, sdt = settings.sponge_strength * settings.courant * m * m;
                const double lap = at(i - 1, j, k) + at(i + 1, j, k) + at(i, j - 1, k) + at(i, j + 1, k) +
                                   at(i, j, k - 1) + at(i, j, k + 1) - 6.0 * at(i, j, k);
                worst = std::max(worst, std::fabs(lam * lap + sdt * init[s.index(i, j, k)]));
                scale = std::max(scale, sdt * init[s.index(i, j, k)]);
            }
    std::printf("converged after %d steps: max |courant^2 L(C) + s phi0| = %.3g (max s phi0 %.3g)\n", steps, worst, scale);
    EXPECT_GT(scale, 0.1);
    EXPECT_LT(worst, 1e-3 * scale);
}

TEST(WaveMethod, CourantAboveBoundIsRefused) {
    const MethodInfo* info = find_method("wave_pde");
    ASSERT_NE(info, nullptr);
    EXPECT_NO_THROW(ParamSet::resolve(info->name, info->params, {{"courant", "0.57"}}));
    try {
        ParamSet::resolve(info->name, info->params, {{"courant", "0.6"}});
        FAIL() << "courant 0.6 accepted";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("courant"), std::string::npos) << msg;
        EXPECT_NE(msg.find("0.577350269"), std::string::npos) << msg;
    }
    // The command line maps it to exit 2.
    const std::string binary = CAUSTICS_BINARY;
    const std::string scene = std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json";
    if (!std::filesystem::exists(binary) || !std::filesystem::exists(scene)) GTEST_SKIP() << "no CLI or sine.json";
    const std::string out = (std::filesystem::temp_directory_path() / "wave_pde_courant_test").string();
    const std::string cmd = "'" + binary + "' render '" + scene + "' --method wave_pde --set courant=0.6 --no-reference --out '" +
                            out + "' > /dev/null 2>&1";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
}
