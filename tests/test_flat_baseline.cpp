// The no-caustic baseline (harness/baseline, docs/design.md section 6): what a flat interface would transmit
// equals the exact flat truth and the Monte Carlo reference of flat water, leaves the strip of width
// depth tan(theta_t) unlit on the side the refracted light moves away from, and exists only for
// directional light through one height-field interface (plane or height-field receivers).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/frame/baseline.hpp>
#include "sine_truth_support.hpp"

using namespace caustics;
using namespace caustics::test_support;

TEST(FlatInterfaceBaseline, AgreesWithTruthAndReferenceAndLeavesTheUnlitStrip) {
    // Flat water exactly over the floor, light 30 degrees towards +x, absorbing, with Fresnel: refracted
    // light leaves a strip of width depth tan(theta_t) unlit at the floor's upstream (-x) edge.
    SineSetup c = sine_case(30.0, -0.4, 0.5, true);
    c.water_lo = -0.5, c.water_hi = 0.5, c.bins_x = 256;
    c.amplitude = 0.0;   // the sine generator with A = 0: a flat interface with an analytic truth
    const TracedScene setup(make_sine_scene(c));
    const Image baseline = flat_interface_baseline(*setup.frame, *setup.chart);
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    ASSERT_EQ(baseline.width, c.bins_x);
    const double sin_t = 0.5 / 1.33, strip = 0.4 * sin_t / std::sqrt(1.0 - sin_t * sin_t);   // Snell's law
    const double bin_w = c.floor_size / c.bins_x;
    const std::vector<double> b = column_means(baseline), e = column_means(truth.receiver);
    double dark = 0.0;
    for (int i = 0; i < c.bins_x; ++i) {
        dark += (1.0 - b[static_cast<std::size_t>(i)] / b.back()) * bin_w;
        const double x0 = -0.5 + i * bin_w;
        if (x0 + bin_w < -0.5 + strip) {
            EXPECT_EQ(b[static_cast<std::size_t>(i)], 0.0) << i;
        }
        // Away from the strip's edge (sub-sampled there) the baseline is the exact flat truth.
        if (x0 > -0.5 + strip) {
            EXPECT_NEAR(b[static_cast<std::size_t>(i)], e[static_cast<std::size_t>(i)], 1e-6 * e.back()) << i;
        }
    }
    EXPECT_NEAR(dark, strip, 0.25 * bin_w);   // 4 x 4 sub-points per bin
    // The same light from the other side darkens the other edge.
    Scene mirrored = make_sine_scene(c);
    mirrored.lights[0].direction.x = -mirrored.lights[0].direction.x;
    const TracedScene m(std::move(mirrored));
    const Image other = flat_interface_baseline(*m.frame, *m.chart);
    EXPECT_EQ(other.at(0, 0), baseline.at(c.bins_x - 1, 0));
    EXPECT_EQ(other.at(c.bins_x - 1, 0), 0.0f);

    // The Monte Carlo reference of flat water (the `flat` generator) agrees per column, but for the one
    // the strip's edge crosses (there the baseline is a 4-point average).
    Scene flat = make_sine_scene(c);
    flat.objects[0].heightfield.generator = HeightGenerator::Flat;
    const TracedScene f(std::move(flat));
    const Columns cols = reference_columns(run_reference(f, 2'000'000));
    const int edge_column = static_cast<int>(strip / bin_w);
    const ZTest t = z_test(cols, column_means(flat_interface_baseline(*f.frame, *f.chart)), edge_column);
    EXPECT_LE(t.worst, t.threshold) << "column " << t.column;
    std::printf("flat water, 30 degrees: unlit strip %.4f m (closed form %.4f), reference max |t| %.2f (threshold "
                "%.2f)\n", dark, strip, t.worst, t.threshold);
}

TEST(FlatInterfaceBaseline, OnlyForDirectionalLightThroughOneHeightField) {
    Scene point = make_sine_scene(SineSetup{});
    point.lights[0].type = LightType::Point;
    point.lights[0].position = {0.0, 0.0, 1.0};
    const TracedScene p(std::move(point));
    EXPECT_TRUE(flat_interface_baseline(*p.frame, *p.chart).empty());
    // sand.json: a height-field receiver under noise water; the baseline is E0 n_z per true area.
    Scene sand = load_scene(scene_path("sand.json"));
    sand.receiver.width = sand.receiver.height = 32;
    const TracedScene s(std::move(sand));
    const Image b = flat_interface_baseline(*s.frame, *s.chart);
    ASSERT_EQ(b.width, 32);
    const auto [lo, hi] = std::minmax_element(b.pixels.begin(), b.pixels.end());
    EXPECT_GT(*lo, 0.5f);
    EXPECT_LE(*hi, 1.0f);
}
