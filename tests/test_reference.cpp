// Reference light tracer tests (issue 2, "Tests"): closed forms (refracting sine surface, ball lens)
// within the reference's own standard error, flux conservation, Embree watertightness and determinism
// across thread counts (the cache: test_reference_cache.cpp).
//
// Tolerances: every Monte Carlo comparison is a z-test against the reference's per-bin standard error,
// Sidak-corrected over the number of bins compared so that the whole test has a false-alarm rate of
// kFamilyAlpha. The threshold follows from the photon count through the standard error; it is never a
// hand-picked percentage.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <caustics/reference/analytic_truth.hpp>
#include "ball_lens.hpp"
#include "reference_support.hpp"
#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>
#include <caustics/util/statistics.hpp>

namespace fs = std::filesystem;
using namespace caustics;
using namespace caustics::test_support;

namespace {

constexpr double kFamilyAlpha = 1e-3;


// Two-sided z threshold for `tests` simultaneous comparisons (Sidak): per-test alpha
// 1 - (1 - kFamilyAlpha)^(1/tests), inverted by bisection on erfc.
double sidak_z(int tests) {
    const double alpha = 1.0 - std::pow(1.0 - kFamilyAlpha, 1.0 / std::max(1, tests));
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// A closed triangle mesh of the unit sphere: an icosahedron subdivided `levels` times, CCW outside.
TriangleMesh icosphere(int levels, double radius) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (auto& p : v) p = glm::normalize(p);
    std::vector<glm::uvec3> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<unsigned, unsigned>, unsigned> mid;
        auto midpoint = [&](unsigned a, unsigned b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back(glm::normalize(v[a] + v[b]));
            const unsigned id = static_cast<unsigned>(v.size() - 1);
            mid.emplace(key, id);
            return id;
        };
        std::vector<glm::uvec3> next;
        for (const auto& tri : f) {
            const unsigned a = midpoint(tri.x, tri.y), b = midpoint(tri.y, tri.z), c = midpoint(tri.z, tri.x);
            next.insert(next.end(), {{tri.x, a, c}, {tri.y, b, a}, {tri.z, c, b}, {a, b, c}});
        }
        f = std::move(next);
    }
    TriangleMesh m;
    for (const auto& p : v) m.positions.emplace_back(glm::vec3(p * radius));
    m.triangles = f;
    return m;
}

}  // namespace

// ---------------------------------------------------------------- closed forms

// Sine surface, normal incidence, floor above the first focus: each receiver column (averaged over y)
// against the exact Snell mapping (harness/analytic_truth; its own tests: test_analytic_truth.cpp).
TEST(ReferenceClosedForm, SineSurfaceMatchesExactSnellMapping) {
    constexpr int kBinsX = 128, kBinsY = 8;
    TracedScene setup(sine_test_scene(kBinsX, kBinsY));
    const Object& water = setup.scene.objects.at(static_cast<std::size_t>(find_object(setup.scene, "water")));
    ASSERT_EQ(water.heightfield.direction, glm::dvec2(1.0, 0.0));

    // Above the first focus the mapping must be monotonic (no folds): check it, so the scene stays a
    // fold-free validation case.
    SinePlane plane;
    plane.amplitude = water.heightfield.amplitude;
    plane.k = 2.0 * std::numbers::pi / water.heightfield.wavelength;
    plane.offset = water.heightfield.phase;
    plane.ior = water.material.ior;
    plane.floor_z = setup.scene.objects.at(static_cast<std::size_t>(find_object(setup.scene, "floor"))).center.z;
    for (double x0 = -0.6; x0 < 0.6; x0 += 1e-4) ASSERT_GT(plane.trace(x0 + 1e-4).landing, plane.trace(x0).landing);

    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    const ReferenceResult ref = setup.run(3'000'000);
    std::vector<double> closed(kBinsX, 0.0);
    for (int j = 0; j < kBinsY; ++j)
        for (int i = 0; i < kBinsX; ++i) closed[static_cast<std::size_t>(i)] += truth.receiver.at(i, j) / kBinsY;

    // Standard errors from the reference's replicas: Student t with replicas - 1 degrees of freedom.
    const double z = student_t_critical(sidak_level(kFamilyAlpha, kBinsX), ref.replicas > 1 ? ref.replicas - 1.0 : 1e9);
    int worst = -1;
    double worst_z = 0.0;
    for (int i = 0; i < kBinsX; ++i) {
        double mean = 0.0, var = 0.0;
        for (int j = 0; j < kBinsY; ++j) {
            mean += ref.receiver.at(i, j) / kBinsY;
            var += std::pow(ref.receiver_stderr.at(i, j) / kBinsY, 2);
        }
        const double se = std::sqrt(var);
        ASSERT_GT(se, 0.0) << "column " << i;
        const double zi = std::abs(mean - closed[static_cast<std::size_t>(i)]) / se;
        if (zi > worst_z) worst_z = zi, worst = i;
        EXPECT_LE(zi, z) << "column " << i << ": reference " << mean << " +- " << se << ", closed form "
                         << closed[static_cast<std::size_t>(i)];
    }
    // The closed form has real structure (the caustic bands), so matching it is not trivial.
    const auto [mn, mx] = std::minmax_element(closed.begin(), closed.end());
    EXPECT_GT(*mx / *mn, 1.5);
    RecordProperty("worst_column", worst);
    RecordProperty("worst_z", std::to_string(worst_z) + " (threshold " + std::to_string(z) + ")");
}

// Ball lens: glass sphere (radius R, ior n), parallel light along -z, receiver plane beyond the paraxial
// focus F0 = n R / (2 (n - 1)) from the centre. The meridional ray of height h is traced through the
// sphere exactly; E(r) = E0 h / (r |dr/dh|) summed over preimages, here integrated over each receiver
// bin, then bins are pooled into annuli.
TEST(ReferenceClosedForm, BallLensRadialProfile) {
    const test_support::BallLens lens;   // R 0.5, n 1.5, floor 1.0 below the centre
    const double R = lens.radius;
    ASSERT_GT(lens.distance, lens.paraxial_focus());
    Scene s = lens.scene();
    TracedScene setup(std::move(s));
    const ReferenceResult ref = setup.run(4'000'000);

    // Radial flux density: 2 pi h dh of source area per unit h, mapped to |r|.
    constexpr int kFine = 40000;
    const double r_max = 1.5;
    auto abs_map = [&](double h) { return std::min(std::abs(lens.landing_radius(h)), 1e3); };
    std::vector<double> ring_flux = bin_average_1d(abs_map, [](double h) { return 2.0 * std::numbers::pi * h; }, 0.0,
                                                   R * (1.0 - 1e-9), 4'000'000, 0.0, r_max, kFine);
    std::vector<double> e_fine(kFine);
    const double dr = r_max / kFine;
    for (int i = 0; i < kFine; ++i) {
        const double a = std::numbers::pi * (std::pow((i + 1) * dr, 2) - std::pow(i * dr, 2));
        e_fine[static_cast<std::size_t>(i)] = ring_flux[static_cast<std::size_t>(i)] / a;   // E0 = 1
    }
    auto e_at = [&](double r) {
        const int i = static_cast<int>(r / dr);
        return i < kFine ? e_fine[static_cast<std::size_t>(i)] : 0.0;
    };
    // Where |r(h)| folds (dr/dh = 0), E has an integrable singularity: the caustic.
    const std::vector<double> folds = lens.folds(1e-4, r_max);

    // Expected bin values: 16 x 16 sub-samples of the fine radial profile.
    const ReceiverChart& chart = *setup.chart;
    constexpr int kSub = 16;
    constexpr double kAnnulus = 0.04;
    const int annuli = static_cast<int>(0.9 / kAnnulus);
    std::vector<double> ref_sum(annuli, 0.0), ref_var(annuli, 0.0), exp_sum(annuli, 0.0), area_sum(annuli, 0.0);
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) {
            double expected = 0.0;
            for (int b = 0; b < kSub; ++b)
                for (int a = 0; a < kSub; ++a) {
                    const glm::dvec3 p = chart.point((i + (a + 0.5) / kSub) / chart.width(),
                                                     (j + (b + 0.5) / kSub) / chart.height());
                    expected += e_at(std::hypot(p.x, p.y)) / (kSub * kSub);
                }
            const glm::dvec3 c = chart.point((i + 0.5) / chart.width(), (j + 0.5) / chart.height());
            const int ring = static_cast<int>(std::hypot(c.x, c.y) / kAnnulus);
            if (ring >= annuli) continue;
            const double area = chart.bin_area(i, j);
            ref_sum[ring] += ref.receiver.at(i, j) * area;
            ref_var[ring] += std::pow(ref.receiver_stderr.at(i, j) * area, 2);
            exp_sum[ring] += expected * area;
            area_sum[ring] += area;
        }
    // Compare annuli away from the caustic: skip the innermost ring (bins straddling the axis, where the
    // profile is steepest) and any ring within one annulus width of a fold of r(h).
    std::vector<int> compared;
    for (int ring = 1; ring < annuli; ++ring) {
        const double r0 = ring * kAnnulus, r1 = (ring + 1) * kAnnulus;
        bool near_fold = false;
        for (double f : folds) near_fold |= f > r0 - kAnnulus && f < r1 + kAnnulus;
        if (!near_fold && exp_sum[ring] > 0.0) compared.push_back(ring);
    }
    ASSERT_GE(compared.size(), 8u) << "too few annuli away from the caustic";
    const double z = sidak_z(static_cast<int>(compared.size()));
    for (int ring : compared) {
        const double mean = ref_sum[ring] / area_sum[ring];
        const double se = std::sqrt(ref_var[ring]) / area_sum[ring];
        const double expected = exp_sum[ring] / area_sum[ring];
        ASSERT_GT(se, 0.0);
        EXPECT_LE(std::abs(mean - expected) / se, z)
            << "annulus [" << ring * kAnnulus << ", " << (ring + 1) * kAnnulus << "): reference " << mean << " +- "
            << se << ", closed form " << expected;
    }
}

// ---------------------------------------------------------------- flux conservation

namespace {
void expect_conserved(const FluxLedger& l, const char* what) {
    EXPECT_GT(l.emitted, 0.0) << what;
    EXPECT_NEAR(l.accounted(), l.emitted, 1e-3 * l.emitted) << what;
    for (double v : {l.deposited_receiver, l.deposited_other, l.direct, l.escaped, l.absorbed, l.truncated})
        EXPECT_GE(v, 0.0) << what;
}
}  // namespace

TEST(ReferenceFlux, FlatWaterConservesAndGivesE0) {
    Scene s = sine_test_scene(16, 16);
    s.objects.at(static_cast<std::size_t>(find_object(s, "water"))).heightfield.generator = HeightGenerator::Flat;
    TracedScene setup(std::move(s));
    constexpr std::uint64_t kPhotons = 400'000;
    const ReferenceResult ref = setup.run(kPhotons);
    expect_conserved(ref.ledger, "flat water");
    ASSERT_GT(ref.ledger.deposited_receiver, 0.0);
    // Normal incidence through a flat interface changes nothing: E_c = E0 = 1 on the whole floor. The
    // number of photons landing on the floor is binomial, so the receiver's flux is E0 * area within
    // the binomial standard deviation (z = 5, a single comparison).
    const double w0 = ref.ledger.emitted / kPhotons;
    const double p = ref.ledger.deposited_receiver / ref.ledger.emitted;
    const double sd = w0 * std::sqrt(kPhotons * p * (1.0 - p));
    EXPECT_NEAR(ref.ledger.deposited_receiver, 1.0 * setup.chart->total_area(), 5.0 * sd);
    double mean = 0.0, var = 0.0;
    const double bins = static_cast<double>(ref.receiver.pixels.size());
    for (std::size_t i = 0; i < ref.receiver.pixels.size(); ++i) {
        mean += ref.receiver.pixels[i] / bins;
        var += std::pow(ref.receiver_stderr.pixels[i] / bins, 2);
    }
    EXPECT_NEAR(mean, 1.0, 5.0 * std::sqrt(var));
    EXPECT_GT(ref.noise_nrmse, 0.0);
}

TEST(ReferenceFlux, SineSurfaceConserves) {
    TracedScene setup(sine_test_scene(32, 32));
    const ReferenceResult ref = setup.run(400'000);
    expect_conserved(ref.ledger, "sine");
    EXPECT_GT(ref.ledger.deposited_receiver, 0.0);
    EXPECT_GT(ref.ledger.escaped, 0.0);   // water beyond the 1 m floor refracts into the open volume
}

TEST(ReferenceFlux, SphereConservesWithFresnel) {
    Scene s = load_scene(scene_path("sphere.json"));
    s.receiver.width = s.receiver.height = 32;
    TracedScene plain(s);
    const ReferenceResult a = plain.run(300'000);
    expect_conserved(a.ledger, "sphere");
    EXPECT_GT(a.ledger.deposited_receiver, 0.0);
    s.fresnel = true;
    TracedScene fresnel(s);
    const ReferenceResult b = fresnel.run(300'000);
    expect_conserved(b.ledger, "sphere with Fresnel");
    // Fresnel reflection sends part of the light away from the floor.
    EXPECT_LT(b.ledger.deposited_receiver, a.ledger.deposited_receiver);
}

TEST(ReferenceFlux, AbsorptionFollowsBeerLambert) {
    Scene s = sine_test_scene(16, 16);
    Object& water = s.objects.at(static_cast<std::size_t>(find_object(s, "water")));
    water.heightfield.generator = HeightGenerator::Flat;
    water.material.absorption = 0.5;
    // A floor wider than the water patch: every photon through the water lands on it. (A photon that
    // left through the open water volume would travel an infinite absorbing segment and lose all.)
    Object& floor = s.objects.at(static_cast<std::size_t>(find_object(s, "floor")));
    floor.u *= 1.4;
    floor.v *= 1.4;
    const double depth = -floor.center.z;
    TracedScene setup(std::move(s));
    const ReferenceResult ref = setup.run(400'000);
    expect_conserved(ref.ledger, "absorbing water");
    EXPECT_GT(ref.ledger.absorbed, 0.0);
    // Straight down through 0.4 m of water: every photon that reaches the floor keeps exp(-Ka d) of its
    // flux, and nothing else is absorbed.
    EXPECT_NEAR(ref.ledger.deposited_receiver / (ref.ledger.deposited_receiver + ref.ledger.absorbed),
                std::exp(-0.5 * depth), 1e-7);   // the floor's z is stored as a float
}

// ---------------------------------------------------------------- ray tracer

TEST(RayTracer, IcosphereIsWatertight) {
    Scene s;
    s.name = "icosphere";
    Object ball;
    ball.name = "ball";
    ball.shape = ShapeType::Mesh;
    ball.material.type = MaterialType::Dielectric;
    ball.mesh = icosphere(5, 1.0);
    s.objects = {ball};
    s.receiver.object_index = 0;
    const FrameGeometry frame = build_frame_geometry(s, 0);
    const RayTracer tracer(frame);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    constexpr int kRays = 1'000'000;
    int misses = 0, inward = 0;
    for (int r = 0; r < kRays; ++r) {
        glm::dvec3 o, d;
        do o = {uni(rng), uni(rng), uni(rng)}; while (glm::length(o) > 0.9);
        do d = {uni(rng), uni(rng), uni(rng)}; while (glm::length(d) > 1.0 || glm::length(d) < 1e-3);
        d = glm::normalize(d);
        const Hit hit = tracer.intersect(o, d);
        if (!hit.valid) {
            ++misses;
            continue;
        }
        // Seen from inside, every hit is a back face: the outward normal points along the ray.
        if (glm::dot(hit.geometric_normal, d) <= 0.0) ++inward;
    }
    EXPECT_LT(static_cast<double>(misses) / kRays, 2e-5) << misses << " misses";
    EXPECT_EQ(inward, 0) << "geometric normals must point outward (CCW seen from outside)";
}

TEST(RayTracer, NormalsAndSphereHitsFromInsideAndOutside) {
    Scene s = load_scene(scene_path("sphere.json"));
    TracedScene setup(s);
    const int ball = find_object(setup.scene, "ball");
    const glm::dvec3 c = setup.scene.objects.at(static_cast<std::size_t>(ball)).center;
    const double r = setup.scene.objects.at(static_cast<std::size_t>(ball)).radius;
    // From above: the top of the ball, outward normal up, exact distance.
    Hit hit = setup.tracer->intersect(c + glm::dvec3(0, 0, 2), {0, 0, -1});
    ASSERT_TRUE(hit.valid);
    EXPECT_EQ(hit.object, ball);
    EXPECT_NEAR(hit.t, 2.0 - r, 1e-9);
    EXPECT_NEAR(hit.geometric_normal.z, 1.0, 1e-9);
    // From the centre: the far side, outward normal along the ray.
    hit = setup.tracer->intersect(c, {0, 0, -1});
    ASSERT_TRUE(hit.valid);
    EXPECT_NEAR(hit.t, r, 1e-9);
    EXPECT_NEAR(hit.geometric_normal.z, -1.0, 1e-9);
    // The floor plane: its normal is u x v = +z, whichever side the ray comes from.
    hit = setup.tracer->intersect({1.5, 1.5, 1.0}, {0, 0, -1});
    ASSERT_TRUE(hit.valid);
    EXPECT_NEAR(hit.geometric_normal.z, 1.0, 1e-12);
    EXPECT_NEAR(hit.position.z, 0.0, 1e-6);   // triangle hits carry Embree's float distance
    hit = setup.tracer->intersect({1.5, 1.5, -1.0}, {0, 0, 1});
    ASSERT_TRUE(hit.valid);
    EXPECT_NEAR(hit.geometric_normal.z, 1.0, 1e-12);
    EXPECT_TRUE(setup.tracer->occluded({1.5, 1.5, 1.0}, {0, 0, -1}, 0.0, 2.0));
    EXPECT_FALSE(setup.tracer->occluded({1.5, 1.5, 1.0}, {0, 0, -1}, 0.0, 0.5));
}

// ---------------------------------------------------------------- camera view

// The camera view and the receiver map estimate the same E_c: where the camera sees the floor, its
// flux-weighted mean must match the receiver map at the same points.
TEST(ReferenceCamera, CameraViewAgreesWithReceiverMap) {
    Scene s = load_scene(scene_path("sphere.json"));
    s.receiver.width = s.receiver.height = 64;
    s.camera.width = 128;
    s.camera.height = 96;
    TracedScene setup(std::move(s));
    const CameraGBuffer gbuffer = build_camera_gbuffer(*setup.tracer, setup.scene.camera);
    const ReferenceResult ref = setup.run(2'000'000, 0, &gbuffer);
    ASSERT_FALSE(ref.camera.empty());
    double cam = 0.0, rec = 0.0;
    int used = 0;
    for (int y = 0; y < gbuffer.height; ++y)
        for (int x = 0; x < gbuffer.width; ++x) {
            const std::size_t i = gbuffer.index(x, y);
            if (!gbuffer.covered[i] || gbuffer.object[i] != setup.scene.receiver.object_index) continue;
            const int bin = setup.chart->bin_of(glm::dvec3(gbuffer.position[i]));
            if (bin < 0) continue;
            cam += ref.camera.pixels[i];
            rec += ref.receiver.pixels[static_cast<std::size_t>(bin)];
            ++used;
        }
    ASSERT_GT(used, 1000);
    ASSERT_GT(rec, 0.0);
    // Pixel and bin footprints differ, so this is a 3 % sanity check of the footprint-area formula,
    // not a z-test.
    EXPECT_NEAR(cam / rec, 1.0, 0.03);
    EXPECT_GT(ref.noise_nrmse_camera, 0.0);
}

// ---------------------------------------------------------------- determinism and cache

TEST(ReferenceDeterminism, OneAndTwoThreadsGiveIdenticalBits) {
    Scene s = load_scene(scene_path("sphere.json"));
    s.receiver.width = s.receiver.height = 64;
    s.camera.width = 96;
    s.camera.height = 72;
    s.fresnel = true;   // exercises the per-photon random dimensions beyond emission
    TracedScene setup(std::move(s));
    const CameraGBuffer gbuffer = build_camera_gbuffer(*setup.tracer, setup.scene.camera);
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        return setup.run(300'000, threads, &gbuffer);
    };
    const ReferenceResult a = run(1), b = run(2);
    auto same = [](const Image& x, const Image& y) {
        return x.pixels.size() == y.pixels.size() &&
               std::memcmp(x.pixels.data(), y.pixels.data(), x.pixels.size() * sizeof(float)) == 0;
    };
    EXPECT_TRUE(same(a.receiver, b.receiver));
    EXPECT_TRUE(same(a.receiver_stderr, b.receiver_stderr));
    EXPECT_TRUE(same(a.camera, b.camera));
    EXPECT_TRUE(same(a.camera_stderr, b.camera_stderr));
    EXPECT_EQ(std::memcmp(&a.ledger, &b.ledger, sizeof(FluxLedger)), 0);
    EXPECT_EQ(a.noise_nrmse, b.noise_nrmse);
    // A different seed must change the result (the test can fail).
    ReferenceSettings other;
    other.photons = 300'000;
    other.seed = 2;
    other.camera_view = false;
    other.progress = false;
    const ReferenceResult c = compute_reference(*setup.tracer, *setup.chart, nullptr, other);
    EXPECT_FALSE(same(a.receiver, c.receiver));
}
