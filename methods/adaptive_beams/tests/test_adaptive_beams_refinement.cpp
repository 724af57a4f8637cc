// adaptive_beams past the first focus of water: the claim at a finest adaptive grid of 512, and the
// refinement of the surfaces' beams (fold_iterations) only as far as the receiver needs, with the volume
// view on its own levels.
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/blocks/regime/first_focus.hpp>
#include <caustics/reference/analytic_truth.hpp>
#include "adaptive_beams_render.hpp"
#include "conformance_cases.hpp"
#include "conformance_drawn.hpp"
#include "conformance_judge.hpp"
#include "method_support.hpp"
#include "sine_truth_support.hpp"

using namespace caustics;
using namespace caustics::adaptive_beams_test;

namespace {

// The finest light-space grid a claim states (its finest_grid bound), 0 where it states none.
double finest_grid_of(const AccuracyClaim& claim) {
    for (const RegimeBound& b : claim.bounds)
        if (b.quantity == "finest_grid") return b.value;
    return 0.0;
}

// Renders `scene` at the defaults: whether its surfaces were refined past the focus, and that its receiver is
// the one `same` draws (the settings whose beams the defaults must use there).
void expect_defaults_draw_as(const Scene& scene, int refined, const std::map<std::string, std::string>& same) {
    const Rendered d = render(scene, {}, 64, 2, false);
    EXPECT_EQ(d.out.health.get("refined_past_focus"), refined);
    EXPECT_EQ(d.out.receiver.pixels, render(scene, same, 64, 2, false).out.receiver.pixels);
}

}  // namespace

// Past the first focus the folds of the ray map lie inside the beams that cross them: a finest adaptive grid
// of 512 with fold_split is claimed to 0.10 up to 6 x the first focus (600 drawn cases of three seeds, worst
// 0.084). A sine 2.25 x its focus down under 20 deg light, against the exact truth: inside and met at a finest
// grid of 512 (the defaults' grid 32 with 4 levels); at 256 (claimed to 1.2 x) outside, the reason naming what
// reaches 6 x.
TEST(AdaptiveBeams, PastTheFocusClaimedAtAFinestGridOf512) {
    const Scene scene = past_focus_sine_scene();
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    constexpr int kBins = 256;
    const ReceiverChart chart(frame, kBins, kBins);
    const AnalyticTruth truth = analytic_truth(frame, chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    double mean = 0.0, var = 0.0;
    for (float v : truth.receiver.pixels) mean += v / static_cast<double>(truth.receiver.pixels.size());
    for (float v : truth.receiver.pixels) var += (v - mean) * (v - mean) / static_cast<double>(truth.receiver.pixels.size());
    const double baseline = std::sqrt(var) / mean;
    const MethodInfo& info = require_method(kMethod);
    auto claim_at = [&](const std::map<std::string, std::string>& overrides) {
        return info.create(ParamSet::resolve(info.name, info.params, overrides))->accuracy_claim(frame);
    };
    const AccuracyClaim at256 = claim_at({{"iterations", "3"}, {"fold_iterations", "0"}});
    EXPECT_FALSE(at256.inside);
    EXPECT_NE(at256.reason.find("6 x needs a finest adaptive grid of 512"), std::string::npos) << at256.reason;
    // Neither without fold_split nor from a coarser initial grid (8, 6 levels): not measured. From the paper's
    // grid 16 with 5 levels it is.
    EXPECT_FALSE(claim_at({{"iterations", "4"}, {"fold_split", "false"}}).inside);
    EXPECT_FALSE(claim_at({{"iterations", "6"}, {"grid", "8"}}).inside);
    EXPECT_TRUE(claim_at({{"iterations", "5"}, {"grid", "16"}}).inside);
    const AccuracyClaim at512 = claim_at({{"iterations", "4"}});
    ASSERT_TRUE(at512.inside) << at512.reason;
    const Rendered r = render(scene, {{"iterations", "4"}}, kBins, 2, false);
    const double e = nrmse(r.out.receiver, truth.receiver);
    const double e128 = nrmse(render(scene, {{"fold_iterations", "0"}}, kBins, 2, false).out.receiver, truth.receiver);
    std::printf("sine 2.25 x its first focus, 20 deg: nrmse at a finest grid of 128 %.4f, 512 %.4f, baseline %.4f\n",
                e128, e, baseline);
    EXPECT_LT(e, at512.bound(baseline));
    EXPECT_GT(e128, at512.bound(baseline));   // why the defaults' 2 levels (finest 128) alone call it outside
    EXPECT_FALSE(claim_at({{"fold_iterations", "0"}}).inside);
    // At the defaults the surfaces' beams get the levels that reach 2.25 x within the 0.05 aim (finest 512: 4),
    // the same beams as iterations 4, and the claim says so.
    const AccuracyClaim defaults = claim_at({});
    EXPECT_TRUE(defaults.inside) << defaults.reason;
    const Rendered d = render(scene, {}, kBins, 2, false);
    EXPECT_EQ(d.out.health.get("refined_past_focus"), 1);
    EXPECT_EQ(r.out.health.get("refined_past_focus"), 0);
    EXPECT_EQ(d.out.receiver.pixels, r.out.receiver.pixels);
    EXPECT_EQ(finest_grid_of(defaults), 512.0);   // 32 << 4: the claim states the refined beams' finest grid
    // Where refining cannot widen the regime it is not done: the paper's coarse deviation test, or no fold split.
    for (const auto& overrides : std::vector<std::map<std::string, std::string>>{{{"deviation", "0.05"}},
                                                                              {{"fold_split", "false"}}}) {
        EXPECT_EQ(render(scene, overrides, 64, 2, false).out.health.get("refined_past_focus"), 0);
        EXPECT_FALSE(claim_at(overrides).inside);
    }
}

// The surfaces get the fewest levels that kept the drawn cases within 0.05 (claim.cpp): a finest grid of 256
// up to 1.0 x the focus, 512 up to 3 x, 1024 up to 6 x. `sine` with its floor at 0.9 x its first focus depth
// gets 256 (3 levels from 32), at 2 x 512, at 4 x 1024 (claimed only: that frame takes about a second); past
// 6 x nothing is measured and the frame keeps its 2 levels, outside the claim.
TEST(AdaptiveBeams, RefinedOnlyAsFarAsTheReceiverNeeds) {
    Scene scene = test_support::shipped_scene("sine");
    const regime::WaterRegime w = regime::water_regime(build_frame_geometry(scene, 0));
    ASSERT_TRUE(w.valid);
    const MethodInfo& info = require_method(kMethod);
    const std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, {}));
    for (const auto& [ratio, finest] : std::vector<std::pair<double, double>>{{0.9, 256}, {2.0, 512}, {4.0, 1024}, {7.0, 128}}) {
        scene.objects[1].center.z = w.surface_z - ratio * w.focus.first_focus_depth;
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const AccuracyClaim claim = method->accuracy_claim(frame);
        EXPECT_EQ(claim.inside, ratio < 6.0) << ratio << ": " << claim.reason;
        EXPECT_EQ(finest_grid_of(claim), finest) << ratio;
    }
    scene.objects[1].center.z = w.surface_z - 0.9 * w.focus.first_focus_depth;
    expect_defaults_draw_as(scene, 1, {{"iterations", "3"}});
}

// The volume view keeps its own levels (volume_iterations 1) when the surfaces are refined: pool_murky, 2.1 x
// past its focus, draws the same camera_volume with and without fold_iterations.
TEST(AdaptiveBeams, VolumeViewKeepsItsLevelsWhenTheSurfacesAreRefined) {
    Scene scene = test_support::shipped_scene("pool_murky");
    scene.camera.width = 48;
    scene.camera.height = 36;
    const Rendered d = render(scene, {}, 32, 2, true);
    const Rendered off = render(scene, {{"fold_iterations", "0"}}, 32, 2, true);
    EXPECT_EQ(d.out.health.get("refined_past_focus"), 1);
    EXPECT_EQ(off.out.health.get("refined_past_focus"), 0);
    EXPECT_EQ(d.out.camera_volume.pixels, off.out.camera_volume.pixels);
    EXPECT_NE(d.out.receiver.pixels, off.out.receiver.pixels);
}

// Before the reach of `iterations` (sine: 0.62 of the way to its first focus) nothing is refined, and the
// frame is the one fold_iterations 0 draws; before 0.7 of the way the levels are the settings' own even where
// they reach less (grid 16 with 2 levels: a finest grid of 64, outside the claim).
TEST(AdaptiveBeams, NotRefinedWithinTheReachOfItsLevels) {
    const Scene sine = test_support::shipped_scene("sine");
    expect_defaults_draw_as(sine, 0, {{"fold_iterations", "0"}});
    const Rendered coarse = render(sine, {{"grid", "16"}, {"iterations", "2"}}, 64, 2, false);
    EXPECT_EQ(coarse.out.health.get("refined_past_focus"), 0);
    EXPECT_EQ(coarse.out.receiver.pixels,
              render(sine, {{"grid", "16"}, {"iterations", "2"}, {"fold_iterations", "0"}}, 64, 2, false).out.receiver.pixels);
}


// The surfaces' aim at the defaults: within 0.05 of the exact truth on drawn cases (the suite's draws of the
// default seed, 256 x 256 bins), its first 12 and the seven of its first 200 that missed 0.05 before the
// initial grid was 32 and the levels aimed at 0.05 (0.052 to 0.074: sines of wavelength 0.17 to 0.22 m, from
// 0.66 to 5.7 x their first focus). Over 1,000 cases of five seeds the worst was 0.047 (README).
TEST(AdaptiveBeams, SurfacesWithinTheAimOnDrawnCases) {
    const MethodInfo& info = require_method(kMethod);
    std::vector<int> indices;
    for (int i = 0; i < 12; ++i) indices.push_back(i);
    for (int i : {26, 47, 77, 140, 152, 159, 179}) indices.push_back(i);
    for (const int i : indices) {
        const test_support::DrawnCase c = test_support::drawn_case(test_support::kDefaultConformanceSeed, i);
        const test_support::JudgedRow row = test_support::judge_case(info, c.name, c.scene, false, false);
        ASSERT_FALSE(row.refused) << c.name;
        std::printf("%s (%s): nrmse %.4f\n", c.name.c_str(), c.what.c_str(), row.error);
        EXPECT_TRUE(row.inside) << c.name << ": " << row.stated.reason;
        EXPECT_LE(row.error, 0.05) << c.name << " (" << c.what << ")";
    }
}
