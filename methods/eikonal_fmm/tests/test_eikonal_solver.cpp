// eikonal_fmm's solver and transport (Mercier 2013, Sec. 3): closed-form checks of the eikonal solution and
// its curvature, the boundary treatment of Algorithm 2, the focus law along the axis of a Gaussian bump, the
// plane-wave start under oblique light and the transport's intensity along a spherical cap's axis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include <tbb/global_control.h>

#include <caustics/blocks/regime/first_focus.hpp>
#include "../eikonal_solver.hpp"
#include "../eikonal_transport.hpp"
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>
#include "volume_method_support.hpp"

using namespace caustics;

namespace {

// A height field over [x0, x0 + size]^2 with n x n cells from h(x, y) and its gradient.
HeightField make_field(double x0, double size, int n, std::function<double(double, double)> h,
                       std::function<glm::dvec2(double, double)> g) {
    HeightField hf;
    hf.nx = hf.ny = n + 1;
    hf.origin = glm::dvec2(x0);
    hf.spacing = glm::dvec2(size / n);
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double x = x0 + i * hf.spacing.x, y = x0 + j * hf.spacing.y;
            hf.height.push_back(static_cast<float>(h(x, y)));
            hf.gradient.push_back(glm::vec2(g(x, y)));
        }
    hf.exact_gradient = g;
    return hf;
}

// A cubic-cell volume with `n` cells across [x0, x0 + size] and depth cells below `top`.
VolumeShape make_shape(double x0, double size, int n, double top, double depth) {
    VolumeShape s;
    s.spacing = size / n;
    s.nx = s.ny = n;
    s.nz = static_cast<int>(std::ceil(depth / s.spacing));
    s.origin = glm::dvec3(x0, x0, top - s.nz * s.spacing);
    return s;
}

// The paper's solver (init_time = paper: the front leaves the whole interface at time 0), which the
// closed forms of the EikonalSolver tests below describe.
eikonal::Options options(eikonal::Solver solver, int order, eikonal::Boundary boundary = eikonal::Boundary::Paper) {
    eikonal::Options o;
    o.solver = solver;
    o.order = order;
    o.boundary = boundary;
    o.init_time = eikonal::InitTime::Paper;
    return o;
}

struct Variant {
    eikonal::Solver solver;
    int order;
    const char* name;
};
const Variant kVariants[] = {{eikonal::Solver::Fmm, 1, "fmm1"},
                             {eikonal::Solver::Fmm, 2, "fmm2"},
                             {eikonal::Solver::Sweep, 1, "sweep1"},
                             {eikonal::Solver::Sweep, 2, "sweep2"}};

// Spherical cap of radius r, apex at z = 0: converging fronts, exact distance r - |p - o|.
constexpr double kCapRadius = 1.0;
HeightField cap_field(int n) {
    const double r = kCapRadius;
    return make_field(
        -0.3, 0.6, n, [r](double x, double y) { return std::sqrt(r * r - x * x - y * y) - r; },
        [r](double x, double y) {
            const double s = std::sqrt(r * r - x * x - y * y);
            return glm::dvec2(-x / s, -y / s);
        });
}
double cap_distance(const glm::dvec3& p) { return kCapRadius - glm::length(p - glm::dvec3(0, 0, -kCapRadius)); }

}  // namespace

TEST(EikonalSolver, FlatInterfaceGivesExactDistanceAndZeroCurvature) {
    const HeightField hf = make_field(-0.5, 1.0, 64, [](double, double) { return 0.0; },
                                      [](double, double) { return glm::dvec2(0.0); });
    const VolumeShape shape = make_shape(-0.5, 1.0, 24, 0.1, 0.7);
    for (const Variant& v : kVariants)
        for (auto boundary : {eikonal::Boundary::None, eikonal::Boundary::Paper}) {
            eikonal::Stats stats;
            const VolumeD phi = eikonal::solve(hf, shape, options(v.solver, v.order, boundary), stats);
            VolumeF lap;
            laplacian(phi, lap);
            double err = 0.0, curv = 0.0;
            for (int k = 0; k < shape.nz; ++k)
                for (int j = 0; j < shape.ny; ++j)
                    for (int i = 0; i < shape.nx; ++i) {
                        const double z = shape.center(i, j, k).z;
                        if (z > 0.0) continue;
                        err = std::max(err, std::fabs(phi.at(i, j, k) + z));
                        curv = std::max(curv, std::fabs(static_cast<double>(lap.at(i, j, k))));
                    }
            EXPECT_LT(err, 1e-12) << v.name;
            EXPECT_LT(curv, 1e-8) << v.name;
            EXPECT_EQ(stats.not_converged, 0) << v.name;
        }
}

TEST(EikonalSolver, SphericalCapCurvatureIsMinusTwoOverR) {
    // Near the apex (depth s in [0.05, 0.3]) the Laplacian is -2 / (r - s).
    const HeightField hf = cap_field(384);
    const VolumeShape shape = make_shape(-0.3, 0.6, 48, 0.05, 0.45);
    for (const Variant& v : kVariants) {
        eikonal::Stats stats;
        const VolumeD phi = eikonal::solve(hf, shape, options(v.solver, v.order), stats);
        VolumeF lap;
        laplacian(phi, lap);
        double worst = 0.0;
        for (int k = 0; k < shape.nz; ++k)
            for (int j = shape.ny / 2 - 2; j <= shape.ny / 2 + 1; ++j)
                for (int i = shape.nx / 2 - 2; i <= shape.nx / 2 + 1; ++i) {
                    const glm::dvec3 p = shape.center(i, j, k);
                    const double s = cap_distance(p);
                    if (s < 0.05 || s > 0.3) continue;
                    const double expected = -2.0 / glm::length(p - glm::dvec3(0, 0, -kCapRadius));
                    worst = std::max(worst, std::fabs(lap.at(i, j, k) - expected) / std::fabs(expected));
                }
        std::printf("cap curvature %s: worst relative error %.4f (h = %.4f)\n", v.name, worst, shape.spacing);
        EXPECT_LT(worst, v.order == 1 ? 0.35 : 0.1) << v.name;
    }
}

TEST(EikonalSolver, ConvergenceOrderOnSmoothFront) {
    // Max error of phi over a central region the domain sides cannot influence (|x|, |y| <= 0.1,
    // depth s in [0, 0.3]), at h and h/2, compared at the same points: the coarse grid's cell centres.
    // Each is the common corner of eight fine cells, and the fine error there is their mean (the error
    // field is smooth, so this adds O(h^2) to an O(h) or O(h^2) error). Comparing the two grids' own
    // cell centres instead measured 0.68 for order 1: its error is largest at the region's deepest,
    // most oblique corner (|x| = |y| = 0.1, s = 0.3; not in the initialization band, where it is 20x
    // smaller), growing linearly with depth and obliqueness, and the coarse grid's outermost centres sit
    // at |x| = 0.084 while the fine grid's sit at 0.098, so the two maxima came from different points
    // (own centres at 64 -> 128 -> 256 give 1.01 and 0.96).
    auto solve_cap = [](int n, const eikonal::Options& o) {
        const HeightField hf = cap_field(512);
        eikonal::Stats stats;
        return eikonal::solve(hf, make_shape(-0.3, 0.6, n, 0.05, 0.4), o, stats);
    };
    auto in_region = [](const glm::dvec3& p) {
        const double s = cap_distance(p);
        return std::fabs(p.x) <= 0.1 && std::fabs(p.y) <= 0.1 && s >= 0.0 && s <= 0.3;
    };
    for (const Variant& v : kVariants) {
        const eikonal::Options o = options(v.solver, v.order, eikonal::Boundary::None);
        const VolumeD coarse = solve_cap(32, o), fine = solve_cap(64, o);
        const VolumeShape& cs = coarse.shape;
        const VolumeShape& fs = fine.shape;
        auto fine_error = [&](int i, int j, int k) { return fine.at(i, j, k) - cap_distance(fs.center(i, j, k)); };
        double e1 = 0.0, e2 = 0.0;
        for (int k = 0; k < cs.nz; ++k)
            for (int j = 0; j < cs.ny; ++j)
                for (int i = 0; i < cs.nx; ++i) {
                    const glm::dvec3 p = cs.center(i, j, k);
                    if (!in_region(p)) continue;
                    e1 = std::max(e1, std::fabs(coarse.at(i, j, k) - cap_distance(p)));
                    // Both grids share their top face: coarse layer k (counted from the top) covers fine
                    // layers 2k and 2k + 1 from the top.
                    const int kf = fs.nz - 2 * (cs.nz - k);
                    ASSERT_GE(kf, 0);
                    double mean = 0.0;
                    for (int c = 0; c < 8; ++c) mean += fine_error(2 * i + (c & 1), 2 * j + ((c >> 1) & 1), kf + (c >> 2));
                    e2 = std::max(e2, std::fabs(mean / 8.0));
                }
        const double order = std::log2(e1 / e2);
        std::printf("convergence %s: err(32) = %.3g err(64) = %.3g order = %.2f\n", v.name, e1, e2, order);
        if (v.order == 1) {
            EXPECT_GE(order, 0.8) << v.name;
            EXPECT_LE(order, 1.2) << v.name;
        } else {
            EXPECT_GT(order, 1.5) << v.name;
        }
    }
}

TEST(EikonalSolver, PaperBoundaryKeepsTiltedPlaneFlat) {
    // Mercier Fig. 3: a tilted plane touching the domain sides has zero curvature everywhere; without
    // boundary treatment the cells fed from outside the domain expand as eccentric circles.
    const double m = 0.4;
    const HeightField hf = make_field(-0.5, 1.0, 64, [m](double x, double) { return m * x; },
                                      [m](double, double) { return glm::dvec2(m, 0.0); });
    const VolumeShape shape = make_shape(-0.5, 1.0, 32, 0.5, 1.3);
    for (const Variant& v : kVariants) {
        double edge[2];
        for (int b = 0; b < 2; ++b) {
            eikonal::Stats stats;
            const VolumeD phi = eikonal::solve(
                hf, shape, options(v.solver, v.order, b == 0 ? eikonal::Boundary::Paper : eikonal::Boundary::None), stats);
            VolumeF lap;
            laplacian(phi, lap);
            // Curvature over the first four columns next to the x = -0.5 face, in the water.
            double worst = 0.0;
            for (int k = 0; k < shape.nz; ++k)
                for (int j = 0; j < shape.ny; ++j)
                    for (int i = 0; i < 4; ++i) {
                        const glm::dvec3 p = shape.center(i, j, k);
                        if (p.z > m * p.x - 2.5 * shape.spacing) continue;
                        worst = std::max(worst, std::fabs(static_cast<double>(lap.at(i, j, k))));
                    }
            edge[b] = worst;
        }
        std::printf("tilted plane %s: max |curvature| near the edge: paper %.3g, none %.3g\n", v.name, edge[0], edge[1]);
        EXPECT_LT(edge[0], 0.05) << v.name;   // uniform (zero) curvature with Algorithm 2
        EXPECT_GT(edge[1], 1.0) << v.name;    // visibly not without it
    }
}

TEST(EikonalSolver, GaussianFocusFollowsTwoOverRMinusS) {
    // gaussian.json: amplitude 0.04, sigma 0.1 -> apex radius R = sigma^2 / A = 0.25 m. Along the axis the
    // front is the parallel surface of the bump: Laplacian = -2 / (R - s) at depth s < R.
    HeightFieldDesc desc;
    desc.center = glm::dvec2(0.0);
    desc.size = glm::dvec2(2.0);
    desc.resolution = glm::ivec2(512);
    desc.generator = HeightGenerator::Gaussian;
    desc.amplitude = 0.04;
    desc.sigma = 0.1;
    const HeightField hf = generate_heightfield(desc, 0.0, 0, 30.0);
    const double R = desc.sigma * desc.sigma / desc.amplitude;
    const int n = 129;  // odd: a column of cell centres on the axis
    const double h = 1.0 / 128;
    VolumeShape shape;
    shape.spacing = h;
    shape.nx = shape.ny = n;
    shape.nz = static_cast<int>(std::ceil(0.55 / h));
    shape.origin = glm::dvec3(-0.5 * n * h, -0.5 * n * h, 0.05 - shape.nz * h);
    for (const Variant& v : kVariants) {
        eikonal::Stats stats;
        const VolumeD phi = eikonal::solve(hf, shape, options(v.solver, v.order), stats);
        VolumeF lap;
        laplacian(phi, lap);
        const int c = n / 2;
        // Relative error (first order: divided by h / (R - s), its expected size), and the depth where
        // the response becomes singular on the grid: |Laplacian| >= 1 / (2h), the value of a front whose
        // radius of curvature is four cells (2 / (R - s) at R - s = 4h).
        double worst = 0.0, onset = -1.0;
        for (int k = shape.nz - 1; k >= 0; --k) {
            const double s = desc.amplitude - shape.center(c, c, k).z;  // depth below the apex
            const double value = lap.at(c, c, k);
            if (s > 0.02 && s <= 0.8 * R) {
                const double rel = std::fabs(value + 2.0 / (R - s)) * (R - s) / 2.0;
                // First order: relative to h / (R - s); second order: plain relative error.
                worst = std::max(worst, v.order == 1 ? rel / (h / (R - s)) : rel);
            }
            if (onset < 0.0 && -value * h >= 0.5) onset = s;
        }
        std::printf("gaussian focus %s: worst relative error%s = %.3f (s <= 0.8R); singular onset at "
                    "s = %.4f, R = %.4f, (s - R) / h = %.2f\n", v.name, v.order == 1 ? " / (h/(R-s))" : "", worst, onset, R, (onset - R) / h);
        EXPECT_LT(worst, v.order == 1 ? 10.0 : 0.1) << v.name;
        EXPECT_GT(onset, 0.0) << v.name;
        // Second order: within two cells of R. First order reaches the threshold 2.2 cells past R: on the
        // axis the front's lateral slope changes sign, and its one-sided lateral differences (h / (R - s)
        // instead of 0) slow the front there, which smooths the focus into a ramp (|Laplacian| h = 0.48
        // at R, 0.51 at R + 2.2 h). The 7-point Laplacian of the exact distance (to the triangulated
        // bump) reaches it 0.9 cells before R. The threshold onset is a check at this h only: it moves
        // with h (h = 1/64: order 1 -0.1, order 2 -2.1 cells; h = 1/256: 6.9 and 3.9 cells, with a
        // 1024^2 height field). Even the exact distance drifts: the focus of a Gaussian bump is a cusp,
        // not a point, and its 7-point |Laplacian| h at s = R falls as h shrinks (0.68, 0.57, 0.46 at
        // h = 1/64, 1/128, 1/256 for the smooth bump, close to h^(1/3)), so it reaches 1/(2h) 0.8 cells
        // past R at h = 1/256.
        EXPECT_LE(std::fabs(onset - R), (v.order == 2 ? 2.0 : 3.0) * h) << v.name;
    }
}

TEST(EikonalSolver, SweepReachesTheFastMarchingSolution) {
    // First order, both solvers solve the same upwind equations (fronts under a height field move
    // down, so the layer-by-layer sweep loses nothing): fast marching exactly, the sweep up to its
    // stopping rule, which leaves each cell within 1e-7 h of its update; allow that per layer.
    const HeightField hf = make_field(
        -0.5, 1.0, 128, [](double x, double y) { return 0.03 * std::sin(9.0 * x + 1.0) * std::cos(7.0 * y); },
        [](double x, double y) {
            return glm::dvec2(0.27 * std::cos(9.0 * x + 1.0) * std::cos(7.0 * y), -0.21 * std::sin(9.0 * x + 1.0) * std::sin(7.0 * y));
        });
    const VolumeShape shape = make_shape(-0.5, 1.0, 40, 0.1, 0.8);
    eikonal::Stats fmm_stats, sweep_stats;
    const VolumeD fmm = eikonal::solve(hf, shape, options(eikonal::Solver::Fmm, 1), fmm_stats);
    const VolumeD sweep = eikonal::solve(hf, shape, options(eikonal::Solver::Sweep, 1), sweep_stats);
    double worst = 0.0;
    for (std::size_t c = 0; c < fmm.data.size(); ++c) worst = std::max(worst, std::fabs(fmm.data[c] - sweep.data[c]));
    std::printf("sweep vs fast marching (order 1): max |difference| = %.3g h\n", worst / shape.spacing);
    EXPECT_LE(worst, shape.nz * 1e-7 * shape.spacing);
    EXPECT_EQ(sweep_stats.not_converged, 0);
}

TEST(EikonalSolver, SameSolutionOnOneAndTwoThreads) {
    // Initialization, the side faces of Algorithm 2 and the passes over the grid run in parallel;
    // every cell's value must not depend on how the work was split.
    const HeightField hf = make_field(
        -0.5, 1.0, 96, [](double x, double y) { return 0.02 * std::sin(11.0 * x + 5.0 * y); },
        [](double x, double y) { return glm::dvec2(0.22, 0.1) * std::cos(11.0 * x + 5.0 * y); });
    const VolumeShape shape = make_shape(-0.5, 1.0, 32, 0.1, 0.6);
    for (const Variant& v : kVariants) {
        VolumeD phi[2];
        for (int threads : {1, 2}) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
            eikonal::Stats stats;
            phi[threads - 1] = eikonal::solve(hf, shape, options(v.solver, v.order), stats);
        }
        std::size_t differ = 0;
        for (std::size_t c = 0; c < phi[0].data.size(); ++c) differ += phi[0].data[c] != phi[1].data[c];
        EXPECT_EQ(differ, 0u) << v.name;
    }
}

// ---- The plane-wave start and the transport output ----

namespace {

eikonal::Options plane_wave(eikonal::Solver solver, int order, const glm::dvec3& light, double ior) {
    eikonal::Options o;
    o.solver = solver;
    o.order = order;
    o.init_time = eikonal::InitTime::PlaneWave;
    o.light = glm::normalize(light);
    o.ior = ior;
    return o;
}

// Light 30 degrees from the vertical, travelling towards +x (and a little +y).
const glm::dvec3 kOblique = glm::normalize(glm::dvec3(0.5, 0.1, -0.86));

}  // namespace

TEST(EikonalPlaneWave, FlatWaterReproducesTheRefractedArrivalTime) {
    // Flat water at oblique incidence: below the interface the arrival time of the refracted plane wave
    // is T = t . p (constant dropped) with t from Snell's law, t_xy = d_xy / n. The paper's start (every
    // interface point at time 0) gives -z instead, whatever the light and the index.
    const double n = 1.33;
    const HeightField hf = make_field(-0.5, 1.0, 64, [](double, double) { return 0.0; },
                                      [](double, double) { return glm::dvec2(0.0); });
    const VolumeShape shape = make_shape(-0.5, 1.0, 24, 0.1, 0.7);
    const glm::dvec3 d = kOblique;
    const glm::dvec2 txy = glm::dvec2(d) / n;
    const glm::dvec3 t(txy, -std::sqrt(1.0 - glm::dot(txy, txy)));
    for (const Variant& v : kVariants) {
        eikonal::Stats stats;
        const VolumeD T = eikonal::solve(hf, shape, plane_wave(v.solver, v.order, d, n), stats);
        double err = 0.0;
        for (int k = 0; k < shape.nz; ++k)
            for (int j = 0; j < shape.ny; ++j)
                for (int i = 0; i < shape.nx; ++i) {
                    const glm::dvec3 p = shape.center(i, j, k);
                    if (p.z > 0.0) continue;
                    err = std::max(err, std::fabs(T.at(i, j, k) - glm::dot(t, p)));
                }
        std::printf("flat oblique plane wave %s: max |T - t.p| = %.3g\n", v.name, err);
        EXPECT_LT(err, 1e-6) << v.name;  // float heights; the paper's start is off by 0.1 here
        EXPECT_EQ(stats.not_converged, 0) << v.name;
    }
    // The direction of grad T is Snell's, which also the helper gives.
    EXPECT_LT(glm::length(eikonal::refract_direction(d, glm::dvec3(0, 0, 1), n) - t), 1e-12);
}

TEST(EikonalPlaneWave, IndexOneLeavesTheIncidentPlaneWave) {
    // ior = 1 bends nothing: under any surface T = d . p, so the Laplacian vanishes (no caustic).
    const HeightField hf = make_field(
        -0.5, 1.0, 128, [](double x, double) { return 0.01 * std::sin(25.0 * x); },
        [](double x, double) { return glm::dvec2(0.25 * std::cos(25.0 * x), 0.0); });
    const VolumeShape shape = make_shape(-0.5, 1.0, 32, 0.1, 0.6);
    eikonal::Stats stats;
    const VolumeD T = eikonal::solve(hf, shape, plane_wave(eikonal::Solver::Fmm, 2, kOblique, 1.0), stats);
    double err = 0.0;
    for (int k = 0; k < shape.nz; ++k)
        for (int j = 0; j < shape.ny; ++j)
            for (int i = 0; i < shape.nx; ++i) {
                const glm::dvec3 p = shape.center(i, j, k);
                if (p.z > -0.03) continue;
                err = std::max(err, std::fabs(T.at(i, j, k) - glm::dot(kOblique, p)));
            }
    EXPECT_LT(err, 1e-6);
}

TEST(EikonalTransport, SphericalCapAxisIntensityMatchesTheClosedForm) {
    // A spherical cap of radius R refracts a normally incident plane wave into a front that converges
    // on the paraxial focus f = n R / (n - 1) below the apex; along the axis both principal curvatures
    // are -1 / (f - s), so the transport equation gives I(s) = E0 (f / (f - s))^2 exp(-Ka s) (on the
    // axis the ray is vertical, so this is also the irradiance on a horizontal receiver). The paper's
    // start focuses at R instead (infinite index).
    const double R = 0.25, n = 1.33, Ka = 0.5, f = n * R / (n - 1.0);
    const HeightField hf = make_field(
        -0.15, 0.3, 384, [R](double x, double y) { return std::sqrt(R * R - x * x - y * y) - R; },
        [R](double x, double y) {
            const double s = std::sqrt(R * R - x * x - y * y);
            return glm::dvec2(-x / s, -y / s);
        });
    const int cells = 65;  // odd: a column of cell centres on the axis
    VolumeShape shape;
    shape.spacing = 0.3 / cells;
    shape.nx = shape.ny = cells;
    shape.nz = static_cast<int>(std::ceil(0.6 / shape.spacing));
    shape.origin = glm::dvec3(-0.15, -0.15, 0.02 - shape.nz * shape.spacing);
    eikonal::TransportInput in;
    in.interface = &hf;
    in.ior = n;
    in.absorption = Ka;
    double worst[2] = {0.0, 0.0};
    for (int paper = 0; paper < 2; ++paper) {
        eikonal::Options o = plane_wave(eikonal::Solver::Fmm, 2, glm::dvec3(0, 0, -1), n);
        if (paper) o.init_time = eikonal::InitTime::Paper;
        eikonal::Stats stats;
        const VolumeD T = eikonal::solve(hf, shape, o, stats);
        VolumeF lap, E;
        laplacian(T, lap);
        eikonal::TransportStats ts;
        eikonal::transport(T, lap, in, E, ts);
        const int c = cells / 2;
        for (int k = shape.nz - 1; k >= 0; --k) {
            const double s = -shape.center(c, c, k).z;
            if (s < 0.05 || s > 0.5) continue;  // before the focus at 1.0 m (and the marginal rays' crossing)
            const double expected = std::pow(f / (f - s), 2) * std::exp(-Ka * s);
            worst[paper] = std::max(worst[paper], std::fabs(E.at(c, c, k) / expected - 1.0));
        }
        if (!paper) {
            EXPECT_EQ(ts.past_first_focus, 0);
        }
    }
    std::printf("spherical cap axis intensity: worst relative error %.4f (plane wave), %.4f (paper start)\n",
                worst[0], worst[1]);
    EXPECT_LT(worst[0], 0.03);
    EXPECT_GT(worst[1], 0.5);
}

TEST(EikonalTransport, CountsCellsPastTheFirstFocus) {
    // The same cap with its focus (1.0 m) inside the volume: the cells at and below it are counted.
    const double R = 0.25, n = 1.33;
    const HeightField hf = make_field(
        -0.15, 0.3, 256, [R](double x, double y) { return std::sqrt(R * R - x * x - y * y) - R; },
        [R](double x, double y) {
            const double s = std::sqrt(R * R - x * x - y * y);
            return glm::dvec2(-x / s, -y / s);
        });
    VolumeShape shape = make_shape(-0.15, 0.3, 33, 0.02, 1.3);
    eikonal::Stats stats;
    const VolumeD T = eikonal::solve(hf, shape, plane_wave(eikonal::Solver::Fmm, 2, glm::dvec3(0, 0, -1), n), stats);
    VolumeF lap, E;
    laplacian(T, lap);
    // The focus analysis: no later than the paraxial focus n R / (n - 1); the cap's steep corners (49
    // degrees) focus earlier (spherical aberration), at 0.5 m. Depths below the mean height.
    double mean = 0.0;
    for (float z : hf.height) mean += z;
    mean /= static_cast<double>(hf.height.size());
    const regime::FocusAnalysis fa = regime::analyze_focus(hf, glm::dvec3(0, 0, -1), n, mean);
    EXPECT_LT(fa.first_focus_depth + mean, n * R / (n - 1.0) + 0.01);
    EXPECT_GT(fa.first_focus_depth + mean, 0.4);
    eikonal::TransportInput in;
    in.interface = &hf;
    in.ior = n;
    in.first_focus_depth = fa.first_focus_depth;
    eikonal::TransportStats ts;
    eikonal::transport(T, lap, in, E, ts);
    // Every water cell deeper than the focus is counted, and holds the flat interface's irradiance.
    std::int64_t deeper = 0;
    for (int k = 0; k < shape.nz; ++k)
        for (int j = 0; j < shape.ny; ++j)
            for (int i = 0; i < shape.nx; ++i)
                if (mean - shape.center(i, j, k).z >= fa.first_focus_depth) {
                    ++deeper;
                    EXPECT_NEAR(E.at(i, j, k), 1.0, 1e-6);
                }
    EXPECT_GT(deeper, 0);
    EXPECT_EQ(ts.past_first_focus, deeper);
    for (float v : E.data) ASSERT_TRUE(std::isfinite(v));
}
