// The Gaussian bump's analytic truth (harness/reference/analytic_truth_radial.cpp): the Monte Carlo reference agrees
// with it per receiver bin within its own standard error (Fresnel and absorption on), and the same
// statistic rejects a truth with a slightly wrong index; on the axis it matches the paraxial closed form
// E(0) = E0 T / (1 - (n - 1) / n * A / sigma^2 * L)^2 (L the apex's depth above the floor); ior = 1 is
// flat; it declines oblique light and floors past the focus, saying why.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include "sine_truth_support.hpp"

using namespace caustics;
using namespace caustics::test_support;

namespace {

Scene gaussian_scene(int bins) {
    Scene s = load_scene(scene_path("gaussian.json"));
    s.receiver.width = s.receiver.height = bins;
    return s;
}

Object& water_of(Scene& s) { return s.objects[static_cast<std::size_t>(find_object(s, "water"))]; }

}  // namespace

TEST(GaussianTruth, BinsWithinTheReferenceStandardErrorAndWrongIorRejected) {
    Scene s = gaussian_scene(32);
    s.fresnel = true;
    water_of(s).material.absorption = 0.5;
    const TracedScene setup(s);
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    EXPECT_EQ(truth.kind, "analytic:gaussian");
    const auto [mn, mx] = std::minmax_element(truth.receiver.pixels.begin(), truth.receiver.pixels.end());
    EXPECT_GT(*mx / *mn, 1.5) << "the truth must have caustic structure for the test to mean something";

    const ReferenceResult ref = run_reference(setup, 4'000'000);
    ASSERT_GE(ref.replicas, 2);
    const BinTest t = bin_test(ref, truth.receiver);
    EXPECT_EQ(t.compared, 32 * 32);
    EXPECT_LE(t.worst, t.threshold) << "a bin's reference differs from the truth beyond its standard error";

    Scene wrong = s;
    water_of(wrong).material.ior = 1.30;
    const TracedScene wrong_setup(wrong);
    const AnalyticTruth bad = analytic_truth(*wrong_setup.frame, *wrong_setup.chart);
    ASSERT_TRUE(bad.available) << bad.reason;
    const BinTest tb = bin_test(ref, bad.receiver);
    EXPECT_GT(tb.worst, t.threshold) << "a truth with ior 1.30 was not rejected";
    std::printf("gaussian: max |t| %.2f over %d bins (threshold %.2f), ior 1.30 truth: max |t| %.1f\n", t.worst,
                t.compared, t.threshold, tb.worst);
}

TEST(GaussianTruth, AxisMatchesTheParaxialClosedForm) {
    // A small bump (A / sigma^2 small against 1 / L) keeps the paraxial form accurate to ~(r slope)^2.
    Scene s = gaussian_scene(65);   // an odd count: the centre bin is centred on the axis
    Object& w = water_of(s);
    w.heightfield.amplitude = 0.004;
    w.heightfield.sigma = 0.2;
    const TracedScene setup(s);
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    const double n = w.material.ior, kappa = 0.004 / (0.2 * 0.2);
    const double L = 0.004 - setup.scene.receiver_object().center.z;
    const double expected = 1.0 / std::pow(1.0 - (n - 1.0) / n * kappa * L, 2.0);
    // The centre bin averages E over +-0.5 bin (7.7 mm) where E falls by ~(r / sigma)^2: 1e-3 relative.
    EXPECT_NEAR(truth.receiver.at(32, 32) / expected, 1.0, 2e-3) << "E(0) " << truth.receiver.at(32, 32);
}

TEST(GaussianTruth, FlatAtIndexOneAndSaysWhyElsewhere) {
    Scene flat = gaussian_scene(32);
    water_of(flat).material.ior = 1.0;
    const TracedScene flat_setup(flat);
    const AnalyticTruth t1 = analytic_truth(*flat_setup.frame, *flat_setup.chart);
    ASSERT_TRUE(t1.available) << t1.reason;
    for (float v : t1.receiver.pixels) EXPECT_NEAR(v, 1.0, 1e-9);

    Scene deep = gaussian_scene(32);
    deep.objects[static_cast<std::size_t>(find_object(deep, "floor"))].center.z = -1.6;   // focus ~1.0 m
    const TracedScene deep_setup(deep);
    const AnalyticTruth td = analytic_truth(*deep_setup.frame, *deep_setup.chart);
    EXPECT_FALSE(td.available);
    EXPECT_NE(td.reason.find("first focus"), std::string::npos) << td.reason;

    Scene tilted = gaussian_scene(32);
    tilted.lights[0].direction = glm::normalize(glm::dvec3(0.3, 0.0, -1.0));
    const TracedScene tilted_setup(tilted);
    const AnalyticTruth tt = analytic_truth(*tilted_setup.frame, *tilted_setup.chart);
    EXPECT_FALSE(tt.available);
    EXPECT_NE(tt.reason.find("not vertical"), std::string::npos) << tt.reason;
}
