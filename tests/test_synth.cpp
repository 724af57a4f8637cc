// Periodic caustic texture synthesis (issue 5 item 2, `caustics synth`): the textures tile (the
// differences across the wrapped edge look like those inside), the set loops (frame `frames` equals frame
// 0), caustic_triangles conserves flux over the tile, and bad requests are refused with exit code 2 and
// the reason: a surface that is not periodic in space and time, a method that cannot synthesise.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <caustics/util/errors.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/synth/synth.hpp>
#include "test_support.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace caustics;

namespace {

using caustics::test_support::run_program;
using caustics::test_support::slurp;

fs::path source_scene(const std::string& name) { return fs::path(CAUSTICS_SOURCE_DIR) / "scenes" / (name + ".json"); }

class SynthTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() / ("caustics_synth_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        fs::remove_all(dir_);   // also on failure: the assertion messages say what went wrong
    }

    // ocean_tile.json with edits applied to its JSON (e.g. no dispersion), written to the temp folder.
    std::string ocean_variant(const std::string& name, const std::function<void(json&)>& edit) {
        json j = json::parse(slurp(source_scene("ocean_tile")));
        edit(j);
        const fs::path p = dir_ / (name + ".json");
        std::ofstream(p) << j.dump(2);
        return p.string();
    }

    using Result = test_support::ProgramResult;
    Result run(const std::vector<std::string>& args) { return run_program(CAUSTICS_BINARY, args, dir_); }

    fs::path dir_;
};

double mean_of(const Image& img, int channel = 0) {
    double s = 0.0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) s += img.at(x, y, channel);
    return s / (static_cast<double>(img.width) * img.height);
}

double max_abs_diff(const Image& a, const Image& b) {
    EXPECT_EQ(a.pixels.size(), b.pixels.size());
    double d = 0.0;
    for (std::size_t k = 0; k < std::min(a.pixels.size(), b.pixels.size()); ++k)
        d = std::max(d, static_cast<double>(std::abs(a.pixels[k] - b.pixels[k])));
    return d;
}

// A seamless periodic texture: the statistics of the differences across the wrapped edge are like
// those inside. The caustic network is rough at the pixel scale, so the mean absolute difference over
// the wrap's 2 x 128 pairs is a noisy, heavy-tailed estimate (it typically lands at 0.65 - 0.95 of the
// interior mean, as the same estimate across the middle lines does): its bounds are loose. The
// correlation of the lines across the wrap is the sharp test: like inside (~0.5 here), where a seam gives ~0.
void expect_seamless(const Image& img, const std::string& what) {
    const SeamStats s = seam_stats(img);
    SCOPED_TRACE(what);
    ASSERT_GT(s.interior_mean_abs, 0.0);
    const double r_interior = s.wrap_mean_abs / s.interior_mean_abs;
    const double r_mid = s.wrap_mean_abs / s.mid_mean_abs;
    const double r_rms = s.wrap_rms / s.interior_rms;
    EXPECT_GT(r_interior, 0.5) << "wrap " << s.wrap_mean_abs << " interior " << s.interior_mean_abs;
    EXPECT_LT(r_interior, 1.3) << "wrap " << s.wrap_mean_abs << " interior " << s.interior_mean_abs;
    EXPECT_GT(r_mid, 0.5) << "wrap " << s.wrap_mean_abs << " middle " << s.mid_mean_abs;
    EXPECT_LT(r_mid, 2.0) << "wrap " << s.wrap_mean_abs << " middle " << s.mid_mean_abs;
    EXPECT_LT(r_rms, 1.5) << "wrap rms " << s.wrap_rms << " interior rms " << s.interior_rms;
    EXPECT_NEAR(s.wrap_correlation, s.interior_correlation, 0.2)
        << "correlation of the lines across the wrap " << s.wrap_correlation << ", inside " << s.interior_correlation;
}

// The statistics see a seam: a crop that is not a whole period (2/3 of the tile) wraps two unrelated lines.
void expect_crop_has_seam(const Image& img) {
    Image crop(img.width * 2 / 3, img.height * 2 / 3);
    for (int y = 0; y < crop.height; ++y)
        for (int x = 0; x < crop.width; ++x) crop.at(x, y) = img.at(x, y);
    const SeamStats s = seam_stats(crop);
    EXPECT_LT(s.wrap_correlation, s.interior_correlation - 0.3) << "the seam statistic does not detect a seam";
    EXPECT_GT(s.wrap_mean_abs / s.interior_mean_abs, 1.1) << "the seam statistic does not detect a seam";
}

SynthOptions small_options(const std::string& scene, const std::string& method, int frames, int size) {
    SynthOptions o;
    o.scene_path = scene;
    o.method = method;
    o.frames = frames;
    o.size = size;
    o.gif = false;
    return o;
}

}  // namespace

TEST_F(SynthTest, CausticTrianglesTilesAndLoops) {
    const std::string scene = ocean_variant("mono", [](json& j) { j["objects"][0]["material"]["dispersion"] = 0.0; });
    SynthOptions o = small_options(scene, "caustic_triangles", 8, 128);
    o.overrides["grid"] = "129";
    const SynthPlan plan = plan_synth(o);
    Synthesizer synth(plan);
    std::vector<Image> frames;
    for (int i = 0; i <= plan.frames; ++i) frames.push_back(synth.frame(i).texture);
    for (int i = 0; i < plan.frames; ++i) expect_seamless(frames[static_cast<std::size_t>(i)], "frame " + std::to_string(i));
    expect_crop_has_seam(frames[0]);
    // Loop: frame `frames` is frame 0 again (same surface, deterministic render), and the set moves.
    double peak = 0.0;
    for (float v : frames[0].pixels) peak = std::max(peak, static_cast<double>(v));
    EXPECT_LE(max_abs_diff(frames[static_cast<std::size_t>(plan.frames)], frames[0]), 1e-6 * peak);
    EXPECT_GT(max_abs_diff(frames[1], frames[0]), 0.01 * peak) << "consecutive frames are identical";
}

TEST_F(SynthTest, CausticTrianglesConservesFlux) {
    // Mean texture over the tile = E0 cos(theta_i) T = E0 at normal incidence without Fresnel or
    // absorption: every triangle's flux lands in the tile (toroidally).
    for (const double e0 : {1.0, 2.5}) {
        const std::string scene = ocean_variant("flux", [e0](json& j) {
            j["objects"][0]["material"]["dispersion"] = 0.0;
            j["lights"][0]["irradiance"] = e0;
        });
        const SynthPlan plan = plan_synth(small_options(scene, "caustic_triangles", 4, 256));
        Synthesizer synth(plan);
        for (int i = 0; i < 4; ++i) {
            const SynthFrame f = synth.frame(i);
            EXPECT_NEAR(mean_of(f.texture), e0, 2e-5 * e0) << "frame " << i;
            EXPECT_EQ(f.health.get("texture_too_large"), 0);
            EXPECT_EQ(f.health.get("nonfinite"), 0);
            EXPECT_EQ(f.health.get("lost_samples"), 0);
        }
    }
    // With dispersion the mono texture is the mean over the indices and each conserves flux; every RGB
    // channel's weights sum to 1, so each channel's mean is E0 as well.
    const SynthPlan plan = plan_synth(small_options(source_scene("ocean_tile").string(), "caustic_triangles", 2, 128));
    Synthesizer synth(plan);
    const SynthFrame f = synth.frame(1);
    ASSERT_EQ(f.texture_rgb.channels, 3);
    EXPECT_NEAR(mean_of(f.texture), 1.0, 2e-5);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean_of(f.texture_rgb, c), 1.0, 1e-4) << "channel " << c;
    // Fresnel: the mean is E0 times the mean transmittance, a little below the normal-incidence value.
    const std::string fres = ocean_variant("fresnel", [](json& j) {
        j["objects"][0]["material"]["dispersion"] = 0.0;
        j["fresnel"] = true;
    });
    const SynthPlan pf = plan_synth(small_options(fres, "caustic_triangles", 1, 128));
    Synthesizer sf(pf);
    const double t0 = 1.0 - std::pow((1.33 - 1.0) / (1.33 + 1.0), 2.0);
    const double m = mean_of(sf.frame(0).texture);
    EXPECT_LE(m, t0 + 1e-5);
    EXPECT_GT(m, t0 - 0.01);
}

TEST_F(SynthTest, WaveOpticsTilesLoopsAndConserves) {
    const std::string scene = ocean_variant("mono", [](json& j) { j["objects"][0]["material"]["dispersion"] = 0.0; });
    SynthOptions o = small_options(scene, "wave_optics", 4, 128);
    o.overrides["grid"] = "256";
    o.overrides["propagator"] = "fresnel";   // unitary: the mean is exactly the transmitted irradiance
    const SynthPlan plan = plan_synth(o);
    Synthesizer synth(plan);
    std::vector<Image> frames;
    for (int i = 0; i <= plan.frames; ++i) frames.push_back(synth.frame(i).texture);
    for (int i = 0; i < plan.frames; ++i) {
        expect_seamless(frames[static_cast<std::size_t>(i)], "wave_optics frame " + std::to_string(i));
        // Bilinear resampling of a 256-grid field to 128 texels keeps the mean to well under 1e-2.
        EXPECT_NEAR(mean_of(frames[static_cast<std::size_t>(i)]), 1.0, 1e-2);
    }
    double peak = 0.0;
    for (float v : frames[0].pixels) peak = std::max(peak, static_cast<double>(v));
    EXPECT_LE(max_abs_diff(frames[static_cast<std::size_t>(plan.frames)], frames[0]), 1e-6 * peak);
}

TEST_F(SynthTest, RefusesMethodThatCannotSynthesise) {
    try {
        (void)plan_synth(small_options(source_scene("ocean_tile").string(), "eikonal_fmm", 2, 64));
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("does not synthesise periodic textures"), std::string::npos) << e.what();
    }
    const fs::path out = dir_ / "out";
    const Result r = run({"synth", source_scene("ocean_tile").string(), "--method", "eikonal_fmm", "--frames", "2",
                          "--size", "64", "--out", out.string()});
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("does not synthesise periodic textures"), std::string::npos) << r.err;
    // The message lists the methods that can synthesise this scene.
    EXPECT_NE(r.err.find("valid: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("caustic_triangles"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "manifest.json"));
}

TEST_F(SynthTest, RefusesSurfaceThatIsNotPeriodic) {
    const fs::path out = dir_ / "out";
    const Result r = run({"synth", source_scene("sine").string(), "--method", "caustic_triangles", "--frames", "2",
                          "--size", "64", "--out", out.string()});
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("not periodic in space and time"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("'sine' generator"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    // The waves simulation does not loop either.
    const Result p = run({"synth", source_scene("pool").string(), "--method", "caustic_triangles", "--out", out.string()});
    EXPECT_EQ(p.code, 2) << p.out << p.err;
    EXPECT_NE(p.err.find("'waves' generator"), std::string::npos) << p.err;
    // Bad counts are bad input too.
    const Result f = run({"synth", source_scene("ocean_tile").string(), "--method", "caustic_triangles", "--frames", "0",
                          "--out", out.string()});
    EXPECT_EQ(f.code, 2) << f.out << f.err;
    EXPECT_NE(f.err.find("--frames"), std::string::npos) << f.err;
}

TEST_F(SynthTest, CommandWritesTheSet) {
    const fs::path out = dir_ / "set";
    const Result r = run({"synth", source_scene("ocean_tile").string(), "--method", "caustic_triangles", "--frames", "4",
                          "--size", "64", "--set", "grid=65", "--set", "dispersion_samples=3", "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    for (int i = 0; i < 4; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%03d", i);
        EXPECT_TRUE(fs::exists(out / (std::string(name) + ".exr"))) << name;
        EXPECT_TRUE(fs::exists(out / (std::string(name) + ".png"))) << name;
    }
    EXPECT_FALSE(fs::exists(out / "frame_004.exr"));
    EXPECT_TRUE(fs::exists(out / "contact_sheet.png"));
    EXPECT_TRUE(fs::exists(out / "tile_2x2.png"));
    const json m = json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(m["scene"], "ocean_tile");
    EXPECT_EQ(m["method"], "caustic_triangles");
    EXPECT_EQ(m["frames"], 4);
    EXPECT_EQ(m["size"], json::array({64, 64}));
    EXPECT_DOUBLE_EQ(m["period"].get<double>(), 2.0);
    EXPECT_DOUBLE_EQ(m["depth"].get<double>(), 0.5);
    EXPECT_EQ(m["params"]["grid"], 65);
    EXPECT_EQ(m["params"]["dispersion_samples"], 3);
    EXPECT_TRUE(m["colour"].get<bool>());
    ASSERT_EQ(m["per_frame"].size(), 4u);
    for (int i = 0; i < 4; ++i) {
        EXPECT_DOUBLE_EQ(m["per_frame"][i]["time"].get<double>(), i * 0.5);
        EXPECT_GE(m["per_frame"][i]["render_ms"].get<double>(), 0.0);
    }
    EXPECT_TRUE(m["timing"].contains("total_ms"));
    EXPECT_TRUE(m["files"].contains("preview_gif") || m["files"].contains("preview_gif_skipped"));
    if (m["files"].contains("preview_gif")) {
        EXPECT_TRUE(fs::exists(out / "preview.gif"));
    }
    // The EXR holds the linear colour texture; its mean luminance is the transmitted irradiance.
    const Image e = read_image((out / "frame_002.exr").string());
    EXPECT_EQ(e.width, 64);
    EXPECT_EQ(e.channels, 3);
    // No temporary files are left behind.
    for (const auto& entry : fs::directory_iterator(out))
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}
