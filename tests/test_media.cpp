// Participating media in the scene model and the run (issue 15): the media a scene declares, the medium
// holding the camera, the Henyey-Greenstein phase function against its closed-form moments, the rule
// that a scene whose medium scatters is measured only by methods that render the volume view, and the
// volume view's error block against a reference.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene.hpp>
#include <caustics/util/image_io.hpp>

using namespace caustics;

namespace {

namespace fs = std::filesystem;

std::string scene_path(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name; }

// A scene file with a small camera: these tests need the camera's G-buffer, not its resolution.
Scene small_camera(const std::string& name) {
    Scene s = load_scene(scene_path(name));
    s.camera.width = 32;
    s.camera.height = 24;
    return s;
}

int object_index(const Scene& s, const std::string& name) {
    for (std::size_t k = 0; k < s.objects.size(); ++k)
        if (s.objects[k].name == name) return static_cast<int>(k);
    return -1;
}

}  // namespace

TEST(Media, SceneFilesDeclareTheirMedia) {
    const Scene fog = load_scene(scene_path("sphere_fog.json"));
    EXPECT_TRUE(scene_scatters(fog));
    const MediumCoefficients outside = medium_at(fog, -1);
    EXPECT_DOUBLE_EQ(outside.scattering, 0.25);
    EXPECT_DOUBLE_EQ(outside.absorption, 0.02);
    EXPECT_DOUBLE_EQ(outside.anisotropy, 0.3);
    EXPECT_DOUBLE_EQ(outside.extinction(), 0.27);
    EXPECT_FALSE(medium_at(fog, object_index(fog, "ball")).scatters());   // clear glass

    const Scene murky = load_scene(scene_path("pool_murky.json"));
    EXPECT_TRUE(scene_scatters(murky));
    const MediumCoefficients water = medium_at(murky, object_index(murky, "water"));
    EXPECT_DOUBLE_EQ(water.absorption, 0.05);
    EXPECT_DOUBLE_EQ(water.scattering, 0.5);
    EXPECT_DOUBLE_EQ(water.anisotropy, 0.5);
    EXPECT_FALSE(medium_at(murky, -1).scatters());   // clear air above the pool

    EXPECT_FALSE(scene_scatters(load_scene(scene_path("pool.json"))));
    EXPECT_FALSE(scene_scatters(load_scene(scene_path("sphere.json"))));
}

TEST(Media, TheCameraKnowsTheMediumItIsIn) {
    const SceneFrame murky(small_camera("pool_murky.json"), 0);
    EXPECT_EQ(murky.gbuffer().medium_object, object_index(murky.scene(), "water"));   // 4 cm under the surface
    const SceneFrame fog(small_camera("sphere_fog.json"), 0);
    EXPECT_EQ(fog.gbuffer().medium_object, -1);
    // A point inside the glass ball is inside the ball, one under the pool's floor-level water inside the water.
    EXPECT_EQ(enclosing_dielectric(fog.tracer(), {0.0, 0.0, 0.8}), object_index(fog.scene(), "ball"));
    EXPECT_EQ(enclosing_dielectric(fog.tracer(), {0.0, 0.0, 1.5}), -1);
    EXPECT_EQ(enclosing_dielectric(murky.tracer(), {0.2, 0.1, -0.5}), object_index(murky.scene(), "water"));
}

// The phase function integrates to 1 over the sphere and its mean cosine is g (Henyey and Greenstein
// 1941): midpoint quadrature in cos(theta), fine enough for 1e-6 even at g = 0.9.
TEST(Media, HenyeyGreensteinIsNormalisedWithMeanCosineG) {
    for (const double g : {-0.6, 0.0, 0.3, 0.9}) {
        const int n = 400000;
        double total = 0.0, mean_cos = 0.0;
        for (int i = 0; i < n; ++i) {
            const double mu = -1.0 + (i + 0.5) * 2.0 / n;
            const double p = henyey_greenstein(mu, g) * 2.0 * std::numbers::pi * 2.0 / n;
            total += p;
            mean_cos += mu * p;
        }
        EXPECT_NEAR(total, 1.0, 1e-6) << "g " << g;
        EXPECT_NEAR(mean_cos, g, 1e-6) << "g " << g;
    }
    EXPECT_DOUBLE_EQ(henyey_greenstein(0.3, 0.0), 1.0 / (4.0 * std::numbers::pi));
}

TEST(Media, MethodsWithoutAVolumeViewAreSkippedWithTheReason) {
    const SceneFrame sf(small_camera("sphere_fog.json"), 0);
    RenderOptions options;
    options.no_reference = true;
    int skipped = 0;
    for (const MethodInfo* info : registered_methods()) {
        const ResolvedMethod m{info, ParamSet::resolve(info->name, info->params, {})};
        const auto method = info->create(m.params);
        const Capability v = method->volume_capability(sf.scene());
        if (v.supported) continue;
        const RenderRun run = run_method(sf, m, options, {});
        EXPECT_EQ(run.status, RunStatus::Skipped) << info->name;
        // A method that refuses media itself says so; one that does not is refused by the run, which
        // names the medium and the method's own reason.
        if (method->capabilities(sf.scene()).supported) {
            EXPECT_NE(run.message.find("medium scatters"), std::string::npos) << run.message;
            EXPECT_NE(run.message.find(v.reason), std::string::npos) << run.message;
        } else {
            EXPECT_FALSE(run.message.empty()) << info->name;
        }
        ++skipped;
    }
    EXPECT_GT(skipped, 0);
}

namespace {

// Renders a constant volume radiance `level` (and no surface caustic): enough to check how the run
// measures the third view.
class ConstantVolume final : public Method {
public:
    explicit ConstantVolume(double level) : level_(level) {}
    Capability volume_capability(const Scene&) const override { return Capability::yes(); }
    CausticOutput render(const FrameGeometry&, const RenderRequest& request) override {
        CausticOutput out;
        out.receiver = Image(request.receiver->width(), request.receiver->height(), 1);
        out.camera = Image(request.camera->width, request.camera->height, 1);
        if (request.camera_volume) {
            out.camera_volume = Image(request.camera->width, request.camera->height, 1);
            for (float& v : out.camera_volume.pixels) v = static_cast<float>(level_);
        }
        return out;
    }

private:
    double level_;
};

}  // namespace

TEST(Media, TheVolumeViewIsMeasuredAgainstTheReferenceAndWritten) {
    const SceneFrame sf(small_camera("sphere_fog.json"), 0);
    MethodInfo info;
    info.name = "constant_volume";
    info.params = {{"grid", ParamType::Int, "1", 1, 8, {}, "unused"}, {"iterations", ParamType::Int, "1", 1, 8, {}, "unused"}};
    const double level = 1.0;
    info.create = [level](const ParamSet&) { return std::make_unique<ConstantVolume>(level); };
    const ResolvedMethod m{&info, ParamSet::resolve(info.name, info.params, {})};

    // A reference known exactly (two replicas that agree) whose volume view is 1 in the top left quarter,
    // 3 in the bottom left and 0 on the right half: its mean is 1. The constant 1 is off by 0, 2 and 1:
    // nrmse = sqrt((0 + 4 + 1 + 1) / 4) = sqrt(1.5). The constant baseline (2, the mean of the lit pixels,
    // on the lit half) is off by 1 on the left half: sqrt(0.5), so the method is no better than it.
    const int w = sf.gbuffer().width, h = sf.gbuffer().height;
    ReferenceResult ref;
    ref.receiver = Image(sf.chart().width(), sf.chart().height(), 1);
    ref.receiver_stderr = ref.receiver;
    ref.receiver_replicas = {ref.receiver, ref.receiver};
    ref.camera_volume = Image(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w / 2; ++x) ref.camera_volume.pixels[static_cast<std::size_t>(y) * w + x] = y < h / 2 ? 1.0f : 3.0f;
    ref.camera_volume_stderr = Image(w, h, 1);
    ref.camera_volume_replicas = {ref.camera_volume, ref.camera_volume};
    RenderOptions options;
    options.warmup = 0;
    options.repeats = 1;
    options.beauty = false;
    options.truth = "reference";
    const RenderRun run = run_method(sf, m, options, [&]() -> const ReferenceResult* { return &ref; });
    ASSERT_EQ(run.status, RunStatus::Ok) << run.message;
    const auto& e = run.metrics["error"]["camera_volume"];
    EXPECT_NEAR(e["nrmse"].get<double>(), std::sqrt(1.5), 1e-6);
    EXPECT_NEAR(e["nrmse_net"].get<double>(), std::sqrt(1.5), 1e-6);
    EXPECT_EQ(run.metrics["baseline_volume"]["kind"], "constant");
    EXPECT_NEAR(run.metrics["baseline_volume"]["error"].get<double>(), std::sqrt(0.5), 1e-6);
    EXPECT_NEAR(e["error_vs_baseline"].get<double>(), std::sqrt(3.0), 1e-6);
    EXPECT_NE(run.message.find("camera_volume: no better than the constant baseline"), std::string::npos) << run.message;

    const fs::path dir = fs::temp_directory_path() / ("caustics_test_media_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    write_render_outputs(dir.string(), sf, run, options);
    const Image written = read_image((dir / "camera_volume.exr").string());
    EXPECT_EQ(written.width, w);
    EXPECT_FLOAT_EQ(written.pixels.front(), 1.0f);
    fs::remove_all(dir);
}
