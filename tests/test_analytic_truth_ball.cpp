// The ball lens's analytic truth (harness/reference/analytic_truth_ball.cpp): its meridional map agrees with the
// independent trace of tests/ball_lens.hpp; the Monte Carlo reference agrees with the truth per receiver bin
// within its own standard error (floor past the paraxial focus: the map folds into a ring caustic), and
// the same statistic rejects a truth with a slightly wrong index; it declines Fresnel and tilted light.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include <caustics/reference/analytic_truth.hpp>
#include "ball_lens.hpp"
#include "sine_truth_support.hpp"

namespace caustics {
namespace {

using test_support::TracedScene;

test_support::BallLens lens_setup(int bins) {
    test_support::BallLens b;
    b.bins = bins;
    return b;   // radius 0.5, ior 1.5, floor 1.0 below the centre: past the paraxial focus at 0.75
}

TEST(BallLensTruth, MeridionalMapMatchesAnIndependentTrace) {
    const test_support::BallLens independent = lens_setup(32);
    BallLens lens;
    lens.radius = independent.radius;
    lens.ior = independent.ior;
    lens.depth = independent.distance;
    for (double h = 0.001; h < 0.4999; h += 0.0037) {
        const BallLens::Ray ray = lens.trace(h);
        const double r = independent.landing_radius(h);
        if (!std::isfinite(r)) {
            EXPECT_FALSE(ray.ok) << "h " << h;
            continue;
        }
        ASSERT_TRUE(ray.ok) << "h " << h;
        EXPECT_NEAR(ray.landing, r, 1e-9 * std::max(1.0, std::fabs(r))) << "h " << h;
    }
}

TEST(BallLensTruth, BinsWithinTheReferenceStandardErrorAndWrongIorRejected) {
    const test_support::BallLens b = lens_setup(32);
    const TracedScene setup(b.scene());
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    EXPECT_EQ(truth.kind, "analytic:ball_lens");
    const auto [mn, mx] = std::minmax_element(truth.receiver.pixels.begin(), truth.receiver.pixels.end());
    EXPECT_GT(*mx, 3.0 * *mn + 1.0) << "the truth must have caustic structure for the test to mean something";

    const ReferenceResult ref = test_support::run_reference(setup, 4'000'000);
    ASSERT_GE(ref.replicas, 2);
    const test_support::BinTest t = test_support::bin_test(ref, truth.receiver);
    EXPECT_GT(t.compared, 32 * 32 / 2);
    EXPECT_LE(t.worst, t.threshold) << "a bin's reference differs from the truth beyond its standard error";

    test_support::BallLens wrong = b;
    wrong.ior = 1.47;
    const TracedScene wrong_setup(wrong.scene());
    const AnalyticTruth bad = analytic_truth(*wrong_setup.frame, *wrong_setup.chart);
    ASSERT_TRUE(bad.available) << bad.reason;
    const test_support::BinTest tb = test_support::bin_test(ref, bad.receiver);
    EXPECT_GT(tb.worst, t.threshold) << "a truth with ior 1.47 was not rejected";
    std::printf("ball lens: max |t| %.2f over %d bins (threshold %.2f), ior 1.47 truth: max |t| %.1f\n", t.worst,
                t.compared, t.threshold, tb.worst);
}

TEST(BallLensTruth, SaysWhyItDoesNotApply) {
    Scene fresnel = lens_setup(16).scene();
    fresnel.fresnel = true;
    const TracedScene a(fresnel);
    const AnalyticTruth ta = analytic_truth(*a.frame, *a.chart);
    EXPECT_FALSE(ta.available);
    EXPECT_NE(ta.reason.find("Fresnel"), std::string::npos) << ta.reason;
    Scene tilted = lens_setup(16).scene();
    tilted.lights[0].direction = glm::normalize(glm::dvec3(0.2, 0.0, -1.0));
    const TracedScene b(tilted);
    const AnalyticTruth tb = analytic_truth(*b.frame, *b.chart);
    EXPECT_FALSE(tb.available);
    EXPECT_NE(tb.reason.find("not vertical"), std::string::npos) << tb.reason;
}

}  // namespace
}  // namespace caustics
