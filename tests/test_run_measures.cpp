// What one run records beside its error (issue 11): the no-caustic baseline and its flag, the truth used,
// the per-frame time of animated scenes, and the timing rule with its dispersion figures.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/util/timing.hpp>

using namespace caustics;

namespace {

std::string scene(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json"; }

}  // namespace

// A method that draws no caustic outputs the flat field: it scores exactly the baseline (ratio 1) and is
// flagged; caustic_triangles' map is far below it and is not. Against the sine scene's closed form the
// flat field's error is 0.539 (the independent measurement).
TEST(Baseline, FlatFieldScoresOneAndIsFlagged) {
    SceneFrame sf(load_scene(scene("sine")), 0);
    const AnalyticTruth truth = analytic_truth(sf.geometry(), sf.chart());
    ASSERT_TRUE(truth.available) << truth.reason;
    const Baseline baseline = make_baseline(flat_interface_baseline(sf.geometry(), sf.chart()), truth.receiver);
    EXPECT_EQ(baseline.kind, "flat_interface");
    const TruthMaps maps{&truth.receiver, nullptr, nullptr};
    const ViewErrors flat = measure_view(baseline.map, maps, nullptr, true, &baseline.map);
    ASSERT_TRUE(flat.have_baseline);
    EXPECT_NEAR(flat.baseline_error, 0.539, 0.002);
    EXPECT_DOUBLE_EQ(flat.json["error_vs_baseline"].get<double>(), 1.0);
    EXPECT_TRUE(flat.no_better_than_flat);

    // A map 10 % off the truth everywhere (nrmse 0.1 rms(t) / mean(t)) is clearly better than the flat field.
    Image close = truth.receiver;
    double sum = 0.0, sq = 0.0;
    for (float& v : close.pixels) sum += v, sq += double(v) * v, v *= 1.1f;
    const double n = static_cast<double>(close.pixels.size());
    const double expected = 0.1 * std::sqrt(sq / n) / (sum / n);
    const ViewErrors good = measure_view(close, maps, nullptr, true, &baseline.map);
    EXPECT_NEAR(good.json["error_vs_baseline"].get<double>(), expected / flat.baseline_error, 1e-4);
    EXPECT_FALSE(good.no_better_than_flat);

    // Not radiometric: both errors after a scale fit, so a scaled flat field is still just the baseline.
    Image scaled = baseline.map;
    for (float& v : scaled.pixels) v *= 7.0f;
    const ViewErrors fitted = measure_view(scaled, maps, nullptr, false, &baseline.map);
    EXPECT_NEAR(fitted.json["error_vs_baseline"].get<double>(), 1.0, 1e-6);
    EXPECT_TRUE(fitted.no_better_than_flat);
}

TEST(Baseline, SceneWithoutHeightFieldUsesTheBestConstantOverLitBins) {
    Image truth(4, 1, 1);
    truth.pixels = {0.0f, 1.0f, 3.0f, 2.0f};
    const Baseline b = make_baseline(Image(), truth);
    EXPECT_EQ(b.kind, "constant");
    EXPECT_EQ(b.map.pixels, (PixelVector{0.0f, 2.0f, 2.0f, 2.0f}));
}

// Through the whole pipeline: the analytic truth is used where the scene has one and said so, or the
// reference when asked; a static scene's frame is its render, an animated one's update + render.
TEST(RunMeasures, TruthAndFrameTimeAreRecorded) {
    RenderOptions o;
    o.scene_path = scene("sine");
    o.method = "caustic_triangles";
    o.overrides = {{"grid", "64"}};
    o.reference.photons = 200'000;
    o.warmup = 1;
    o.repeats = 3;
    o.timing_max_s = 0.2;
    o.progress = false;
    // A cache of its own, removed when the test ends (also on failure).
    struct RemovedAtExit {
        std::string path;
        ~RemovedAtExit() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    } cache{::testing::TempDir() + "caustics_run_measures_cache_" + std::to_string(::getpid())};
    o.cache_dir = cache.path;
    const RenderRun analytic = run_render(o);
    ASSERT_EQ(analytic.status, caustics::RunStatus::Ok) << analytic.message;
    const auto& m = analytic.metrics;
    EXPECT_EQ(m["truth"]["kind"], "analytic:sine");
    EXPECT_EQ(m["truth"]["noise_nrmse"].get<double>(), 0.0);
    EXPECT_EQ(m["frame_time"], "render");
    EXPECT_DOUBLE_EQ(m["frame_ms"]["median"].get<double>(), m["time_ms"]["median"].get<double>());
    EXPECT_EQ(m["baseline"]["kind"], "flat_interface");
    EXPECT_EQ(m["no_better_than_flat"], false);
    const auto& e = m["error"]["receiver"];
    EXPECT_EQ(e["nrmse_net"].get<double>(), e["nrmse"].get<double>());   // exact truth: nothing to remove
    EXPECT_TRUE(e["consistent_with_reference"].is_null());

    o.truth = "reference";
    const RenderRun mc = run_render(o);
    EXPECT_EQ(mc.metrics["truth"]["kind"], "reference");
    EXPECT_GT(mc.metrics["truth"]["noise_nrmse"].get<double>(), 0.0);
    const auto& n = mc.metrics["error"]["receiver"];
    EXPECT_LE(n["nrmse_net"].get<double>(), n["nrmse"].get<double>());
    EXPECT_LE(n["nrmse_net_lo"].get<double>(), n["nrmse_net"].get<double>());
    EXPECT_GE(n["nrmse_net_hi"].get<double>(), n["nrmse_net"].get<double>());
    EXPECT_TRUE(n["consistent_with_reference"].is_boolean());

    o.scene_path = scene("pool");
    o.frame = 30;
    o.no_reference = true;
    o.truth = "auto";
    const RenderRun pool = run_render(o);
    ASSERT_EQ(pool.status, caustics::RunStatus::Ok) << pool.message;
    const auto& p = pool.metrics;
    EXPECT_EQ(p["frame_time"], "update+render");
    EXPECT_GT(p["frame_ms"]["median"].get<double>(), p["time_ms"]["median"].get<double>());
    EXPECT_NEAR(p["fps"].get<double>(), 1000.0 / p["frame_ms"]["median"].get<double>(), 1e-9);
    EXPECT_NEAR(p["render_fps"].get<double>(), 1000.0 / p["time_ms"]["median"].get<double>(), 1e-9);
}

TEST(Timing, DispersionFiguresAndStoppingRule) {
    const TimingSummary s = summarize_ms({5, 1, 4, 2, 3, 10, 9, 8, 7, 6});
    EXPECT_DOUBLE_EQ(s.median, 5.5);
    EXPECT_NEAR(s.stdev, std::sqrt(82.5 / 9.0), 1e-12);
    EXPECT_DOUBLE_EQ(s.iqr, 4.5);   // quartiles 3.25 and 7.75 (linear interpolation)
    // n = 10: the 95 % interval of the median is [x_(2), x_(9)] = [2, 9].
    EXPECT_TRUE(s.has_interval);
    EXPECT_DOUBLE_EQ(s.ci_rel, 0.5 * (9.0 - 2.0) / 5.5);

    TimingPolicy policy;
    policy.min_repeats = 5;
    policy.precision = 0.05;
    policy.max_seconds = 1.0;
    EXPECT_EQ(timing_stop({1, 1, 1}, 0.003, policy), TimingStop::Continue);   // below the minimum
    EXPECT_EQ(timing_stop(std::vector<double>(8, 2.0), 0.016, policy), TimingStop::Precise);
    const std::vector<double> noisy = {1, 9, 2, 8, 3, 7, 1, 9};
    EXPECT_EQ(timing_stop(noisy, 0.04, policy), TimingStop::Continue);   // imprecise, time left
    EXPECT_EQ(timing_stop(noisy, 1.5, policy), TimingStop::Capped);      // imprecise, time spent
}
