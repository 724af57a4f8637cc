// The views as data (harness/run/view_table.hpp): a fourth view is one registered row plus a method's
// output in CausticOutput::views, and runs, the viewer's session and the conformance suite measure it with
// no harness edit. The row registered here is the receiver at half resolution (2 x 2 bin means), measured
// against the closed form's 2 x 2 means; the test-only method draws no caustic (the flat interface's
// irradiance), so its errors are known independently: compare_images on the two downsampled maps.
#include <unistd.h>

#include <deque>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/run/metrics.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/run/view_table.hpp>
#include <caustics/view/session.hpp>

#include "conformance_cases.hpp"
#include "conformance_judge.hpp"

namespace caustics {
namespace {

constexpr const char* kView = "receiver_half";
constexpr const char* kMethod = "view_table_probe";

// 2 x 2 means (odd last rows and columns dropped).
Image half(const Image& m) {
    Image h(m.width / 2, m.height / 2, 1);
    for (int j = 0; j < h.height; ++j)
        for (int i = 0; i < h.width; ++i)
            h.at(i, j) = 0.25f * (m.at(2 * i, 2 * j) + m.at(2 * i + 1, 2 * j) + m.at(2 * i, 2 * j + 1) +
                                  m.at(2 * i + 1, 2 * j + 1));
    return h;
}

ViewSpec half_receiver_row() {
    ViewSpec v;
    v.name = kView;
    v.unit = "W/m^2";
    v.size = [](const ViewSources& s) { return std::make_pair(s.chart->width() / 2, s.chart->height() / 2); };
    v.truth = [](const ViewSources& s, ViewTruth& t) {
        if (!s.analytic || !s.analytic->available) return false;
        // A derived truth: the ViewTruth keeps it.
        auto truth = std::make_shared<const Image>(half(s.analytic->receiver));
        t.maps = {truth.get(), nullptr, nullptr};
        t.owned.push_back(std::move(truth));
        t.kind = s.analytic->kind;
        return true;
    };
    v.missing_note = "method produced no receiver_half view";
    return v;
}

// Draws no caustic: the flat interface's irradiance on the receiver, and (unless `half_view` is 0) its
// half-resolution view; `bad_size` makes that view one bin too wide.
class Probe final : public Method {
public:
    explicit Probe(const ParamSet& p) : half_view_(p.get_int("half_view")), bad_size_(p.get_int("bad_size")) {}
    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override {
        CausticOutput out;
        if (!request.receiver) return out;
        out.receiver = flat_interface_baseline(frame, *request.receiver);
        if (half_view_) {
            out.views[kView] = half(out.receiver);
            if (bad_size_) out.views[kView] = Image(out.views[kView].width + 1, out.views[kView].height, 1);
        }
        return out;
    }
    AccuracyClaim accuracy_claim(const FrameGeometry&) const override {
        return AccuracyClaim::outside("draws no caustic", {{"caustic_modelled", 0.0, 1.0, false}});
    }

private:
    long long half_view_, bad_size_;
};

MethodInfo probe_info() {
    MethodInfo info;
    info.name = kMethod;
    info.doc = "test-only: the flat interface's irradiance, with a half-resolution receiver view";
    info.params = {{"grid", ParamType::Int, "1", 1, 1, {}, "no grid"},
                   {"iterations", ParamType::Int, "1", 1, 1, {}, "no iterations"},
                   {"half_view", ParamType::Int, "1", 0, 1, {}, "produce the receiver_half view"},
                   {"bad_size", ParamType::Int, "0", 0, 1, {}, "make the receiver_half view the wrong size"}};
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<Probe>(p); };
    return info;
}
CAUSTICS_REGISTER_METHOD(probe_info);

// Registered before any test runs (the table is not thread-safe to extend later).
const bool registered = [] {
    register_view(half_receiver_row());
    return true;
}();

// The half view's nrmse computed here, without the view table: the flat interface's 2 x 2 means against
// the closed form's.
double expected_half_nrmse(const Scene& scene) {
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    const AnalyticTruth truth = analytic_truth(frame, chart);
    EXPECT_TRUE(truth.available);
    return compare_images(half(flat_interface_baseline(frame, chart)), half(truth.receiver), false).nrmse;
}

std::string scene_path(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json"; }

}  // namespace

TEST(ViewTable, BuiltInRowsThenRegisteredOnesAndNamesAreUnique) {
    ASSERT_TRUE(registered);
    const std::deque<ViewSpec>& rows = view_table();
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows[0].name, "receiver");
    EXPECT_TRUE(rows[0].primary);
    EXPECT_EQ(rows[1].name, "camera");
    EXPECT_EQ(rows[2].name, "camera_volume");
    EXPECT_EQ(rows[3].name, kView);
    EXPECT_THROW(register_view(half_receiver_row()), std::invalid_argument);
    EXPECT_EQ(view_table().size(), 4u);
    // camera_volume is asked for only where the medium scatters.
    EXPECT_EQ(requested_views(load_scene(scene_path("sine"))).size(), 3u);
    EXPECT_EQ(requested_views(load_scene(scene_path("sphere_fog"))).size(), 4u);
}

// A method that does not model the medium is refused on a scattering scene, with the camera_volume row's
// refusal and its own reason; the same scene without a scattering medium is accepted.
TEST(ViewTable, CapabilityIsTheMethodsAndEveryRequestedViews) {
    const std::unique_ptr<Method> probe = require_method(kMethod).create(ParamSet::resolve(kMethod, probe_info().params, {}));
    const Capability fog = decide_capability(*probe, load_scene(scene_path("sphere_fog")));
    EXPECT_FALSE(fog.supported);
    EXPECT_EQ(fog.reason.rfind(view_table()[2].refusal, 0), 0u) << fog.reason;
    EXPECT_NE(fog.reason.find("camera_volume"), std::string::npos) << fog.reason;
    EXPECT_TRUE(decide_capability(*probe, load_scene(scene_path("sine"))).supported);
    // The supported set: every requested view but the one the probe refuses.
    std::vector<std::string> names;
    for (const ViewSpec* v : supported_views(*probe, load_scene(scene_path("sphere_fog")))) names.push_back(v->name);
    EXPECT_EQ(names, (std::vector<std::string>{"receiver", "camera", kView}));
    EXPECT_EQ(supported_views(*probe, load_scene(scene_path("sine"))).size(), 3u);
}

TEST(ViewTable, RunMeasuresTheFourthView) {
    RenderOptions o;
    o.scene_path = scene_path("sine");
    o.method = kMethod;
    o.reference.photons = 100'000;
    o.warmup = 0;
    o.repeats = 1;
    o.timing_max_s = 0.1;
    o.progress = false;
    struct RemovedAtExit {
        std::string path;
        ~RemovedAtExit() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    } cache{::testing::TempDir() + "caustics_view_table_cache_" + std::to_string(::getpid())};
    o.cache_dir = cache.path;
    const RenderRun run = run_render(o);
    ASSERT_EQ(run.status, RunStatus::Ok) << run.message;
    const nlohmann::json& e = run.metrics["error"];
    ASSERT_TRUE(e.contains(kView)) << run.metrics.dump(2);
    EXPECT_NEAR(e[kView]["nrmse"].get<double>(), expected_half_nrmse(load_scene(o.scene_path)), 1e-6);
    EXPECT_EQ(e[kView]["nrmse_net"].get<double>(), e[kView]["nrmse"].get<double>());   // exact truth
    EXPECT_TRUE(e.contains("receiver"));
    EXPECT_EQ(run.message.find("receiver_half"), std::string::npos) << run.message;

    // Without the view: the row's note, and no error.
    o.overrides = {{"half_view", "0"}};
    const RenderRun without = run_render(o);
    ASSERT_EQ(without.status, RunStatus::Ok) << without.message;
    // Not measured: its key is there, null, like a built-in view's.
    ASSERT_TRUE(without.metrics["error"].contains(kView));
    EXPECT_TRUE(without.metrics["error"][kView]["nrmse"].is_null());
    EXPECT_NE(without.message.find("method produced no receiver_half view"), std::string::npos) << without.message;

    // The wrong size is refused like a built-in view's, naming the view.
    o.overrides = {{"bad_size", "1"}};
    try {
        (void)run_render(o);
        FAIL() << "a receiver_half view of the wrong size was accepted";
    } catch (const std::runtime_error& err) {
        EXPECT_NE(std::string(err.what()).find("receiver_half"), std::string::npos) << err.what();
    }
}

TEST(ViewTable, ViewerSessionMeasuresTheFourthView) {
    view::SessionOptions o;
    o.scene = "sine";
    o.method = kMethod;
    o.reference = false;   // the closed form is the truth
    view::Session s(o);
    s.render();
    const auto it = s.errors().by_view.find(kView);
    ASSERT_NE(it, s.errors().by_view.end());
    EXPECT_NEAR(it->second.json["nrmse"].get<double>(), expected_half_nrmse(s.scene()), 1e-6);
    ASSERT_TRUE(s.errors().view("receiver") != nullptr);
    EXPECT_TRUE(s.errors().view("receiver")->have_baseline);

    // A view of the wrong size is the session's status (the viewer shows it), not an exception that would
    // end the viewer.
    o.overrides = {{"bad_size", "1"}};
    view::Session bad(o);
    EXPECT_NO_THROW(bad.render());
    EXPECT_EQ(bad.status().rfind("failed: ", 0), 0u) << bad.status();
    EXPECT_NE(bad.status().find(kView), std::string::npos) << bad.status();
    EXPECT_FALSE(bad.errors().view("receiver") != nullptr);
}

TEST(ViewTable, ConformanceJudgeMeasuresTheFourthView) {
    const Scene scene = test_support::shipped_scene("sine");
    const test_support::JudgedRow row = test_support::judge_case(require_method(kMethod), "sine", scene, false, false);
    EXPECT_FALSE(row.inside);
    const auto it = row.views.find(kView);
    ASSERT_NE(it, row.views.end());
    EXPECT_NEAR(it->second.json["nrmse"].get<double>(), expected_half_nrmse(scene), 1e-6);
    ASSERT_TRUE(row.views.count("receiver"));
    EXPECT_NEAR(row.views.at("receiver").json["nrmse"].get<double>(), row.error, 1e-9);
}

// The claim's judgement runs, the viewer and the suite share.
TEST(ViewTable, ClaimBoundIsTheStatedErrorOrHalfTheBaselines) {
    const AccuracyClaim claim = AccuracyClaim::within(0.10);
    EXPECT_DOUBLE_EQ(judge_claim(claim, 0.05, 1.0).bound, 0.10);
    EXPECT_TRUE(judge_claim(claim, 0.10, 1.0).met);
    EXPECT_FALSE(judge_claim(claim, 0.101, 1.0).met);
    EXPECT_DOUBLE_EQ(judge_claim(claim, 0.05, 0.12).bound, 0.06);
    EXPECT_FALSE(judge_claim(claim, 0.07, 0.12).met);
    // A nearly flat truth: half the baseline's error would be below the 1 % floor, which holds instead.
    EXPECT_DOUBLE_EQ(judge_claim(claim, 0.004, 0.01).bound, 0.01);
    EXPECT_TRUE(judge_claim(claim, 0.009, 0.01).met);
    EXPECT_DOUBLE_EQ(judge_claim(AccuracyClaim::within(0.005), 0.004, 0.008).bound, 0.005);
}

}  // namespace caustics
