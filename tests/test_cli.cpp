// The `caustics` program end to end (docs/design.md section 7): malformed inputs give exit code 2, one
// "caustics: error:" line naming the file or key, and no output files; a small render writes every file
// and metrics.json key; `list --json` documents every parameter.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "catalog_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using Result = caustics::test_support::ProgramResult;
using caustics::test_support::run_program;
using caustics::test_support::slurp;

class CliTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("caustics_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        fs::remove_all(dir_);   // also on failure: the assertion messages say what went wrong
    }

    Result run(const std::vector<std::string>& args) { return run_program(CAUSTICS_BINARY, args, dir_); }

    // A small, valid scene: sine water over a diffuse floor receiver, directional light.
    static json base_scene() {
        const json camera = {{"position", {0, -1.3, 1.4}}, {"look_at", {0, 0, -0.4}}, {"up", {0, 0, 1}},
                             {"fov_y", 45}, {"width", 48}, {"height", 36}};
        return caustics::test_support::small_sine_scene(2.0, 64, camera, 32);
    }

    std::string write_scene(const std::string& name, const json& scene) {
        const fs::path p = dir_ / name;
        std::ofstream(p) << scene.dump(2);
        return p.string();
    }

    std::string out_dir() const { return (dir_ / "out").string(); }
    std::string cache_dir() const { return (dir_ / "cache").string(); }

    // Exit code 2, one error line naming `expect`, and nothing written under the --out folder.
    void expect_input_error(const std::vector<std::string>& args, const std::string& expect) {
        SCOPED_TRACE("args: " + [&] { std::string s; for (auto& a : args) s += a + " "; return s; }());
        const Result r = run(args);
        EXPECT_EQ(r.code, 2) << r.err;
        EXPECT_EQ(r.err.rfind("caustics: error: ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(expect), std::string::npos) << "stderr does not name '" << expect << "': " << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        std::error_code ec;
        const bool empty = !fs::exists(out_dir(), ec) || fs::is_empty(out_dir(), ec);
        EXPECT_TRUE(empty) << "files were written under " << out_dir();
    }

    std::vector<std::string> render_args(const std::string& scene, std::vector<std::string> extra = {}) {
        std::vector<std::string> a = {"render", scene, "--out", out_dir(), "--photons", "20000", "--repeats", "1",
                                      "--warmup", "0", "--cache", cache_dir()};
        if (std::find(extra.begin(), extra.end(), "--method") == extra.end()) {
            a.push_back("--method");
            a.push_back("caustic_triangles");
        }
        a.insert(a.end(), extra.begin(), extra.end());
        return a;
    }

    fs::path dir_;
};

}  // namespace

TEST_F(CliTest, MissingSceneFile) {
    const std::string missing = (dir_ / "no_such_scene.json").string();
    expect_input_error(render_args(missing), "no_such_scene.json");
}

TEST_F(CliTest, BadJson) {
    const fs::path p = dir_ / "broken.json";
    std::ofstream(p) << "{ \"lights\": [ ";
    expect_input_error(render_args(p.string()), "broken.json");
}

TEST_F(CliTest, UnknownSceneKey) {
    json s = base_scene();
    s["colour"] = 1;
    expect_input_error(render_args(write_scene("unknown_key.json", s)), "colour");
}

TEST_F(CliTest, NegativeResolution) {
    json s = base_scene();
    s["receiver"]["resolution"] = {-4, 32};
    expect_input_error(render_args(write_scene("negative.json", s)), "resolution");
}

TEST_F(CliTest, NaNIor) {
    json s = base_scene();
    s["objects"][0]["material"]["ior"] = "NaN";
    expect_input_error(render_args(write_scene("nan_ior.json", s)), "ior");
}

TEST_F(CliTest, NonPositiveIor) {
    json s = base_scene();
    s["objects"][0]["material"]["ior"] = 0.0;
    expect_input_error(render_args(write_scene("zero_ior.json", s)), "ior");
}

TEST_F(CliTest, EmptyMesh) {
    std::ofstream(dir_ / "empty.gltf") << R"({"asset": {"version": "2.0"}})";
    json s = base_scene();
    s["objects"].push_back({{"name", "thing"}, {"shape", "mesh"}, {"file", "empty.gltf"},
                            {"material", {{"type", "mirror"}}}});
    expect_input_error(render_args(write_scene("empty_mesh.json", s)), "empty.gltf");
}

TEST_F(CliTest, UnreadableAsset) {
    std::ofstream(dir_ / "garbage.glb") << "this is not a binary glTF file";
    json s = base_scene();
    s["objects"].push_back({{"name", "thing"}, {"shape", "mesh"}, {"file", "garbage.glb"},
                            {"material", {{"type", "mirror"}}}});
    expect_input_error(render_args(write_scene("garbage_mesh.json", s)), "garbage.glb");
}

TEST_F(CliTest, MissingHeightMap) {
    json s = base_scene();
    s["objects"][0]["generator"] = {{"type", "image"}, {"file", "no_such_height.png"}, {"amplitude", 0.05}};
    expect_input_error(render_args(write_scene("missing_map.json", s)), "no_such_height.png");
}

TEST_F(CliTest, ReceiverNamesNoObject) {
    json s = base_scene();
    s["receiver"]["object"] = "nothing_here";
    expect_input_error(render_args(write_scene("receiver.json", s)), "nothing_here");
}

TEST_F(CliTest, FrameOutOfRange) {
    const std::string scene = write_scene("frames.json", base_scene());
    expect_input_error(render_args(scene, {"--frame", "5"}), "frame");
}

TEST_F(CliTest, UnknownMethod) {
    const std::string scene = write_scene("method.json", base_scene());
    expect_input_error(render_args(scene, {"--method", "no_such_method"}), "no_such_method");
}

TEST_F(CliTest, UnknownSetKey) {
    const std::string scene = write_scene("setkey.json", base_scene());
    expect_input_error(render_args(scene, {"--set", "gird=32"}), "gird");
}

TEST_F(CliTest, OutOfRangeSetValue) {
    const std::string scene = write_scene("setvalue.json", base_scene());
    expect_input_error(render_args(scene, {"--set", "grid=1"}), "grid");
    expect_input_error(render_args(scene, {"--set", "grid=abc"}), "grid");
}

TEST_F(CliTest, SetWithoutEquals) {
    const std::string scene = write_scene("seteq.json", base_scene());
    expect_input_error(render_args(scene, {"--set", "grid"}), "--set");
}

TEST_F(CliTest, UsageErrors) {
    const std::string scene = write_scene("usage.json", base_scene());
    expect_input_error({"render", scene, "--out", out_dir()}, "--method");
    expect_input_error(render_args(scene, {"--repeats", "0"}), "--repeats");
    expect_input_error({"no_such_command"}, "no_such_command");
}

TEST_F(CliTest, ReferenceCommandBadScene) {
    json s = base_scene();
    s["objects"][1]["material"]["albedo"] = {0.8, 0.8};
    expect_input_error({"reference", write_scene("albedo.json", s), "--out", out_dir(), "--photons", "1000",
                        "--cache", cache_dir()},
                       "albedo");
}

TEST_F(CliTest, RenderWritesFilesAndKeys) {
    const std::string scene = write_scene("good.json", base_scene());
    const Result r = run({"render", scene, "--method", "caustic_triangles", "--set", "grid=32", "--photons", "50000",
                          "--repeats", "2", "--warmup", "1", "--threads", "2", "--out", out_dir(), "--cache",
                          cache_dir()});
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* f : {"receiver.exr", "camera.exr", "beauty.png", "metrics.json"})
        EXPECT_TRUE(fs::is_regular_file(fs::path(out_dir()) / f)) << f;
    const json m = json::parse(slurp(fs::path(out_dir()) / "metrics.json"));
    // docs/design.md section 7, plus build_type, warmup, repeats, below_reference_noise, message, and issue 11's
    // frame time, dispersion, truth and baseline.
    for (const char* k : {"method", "scene", "frame", "params", "radiometric", "time_ms", "fps", "prepare_ms",
                          "update_ms", "stages_ms", "threads", "error", "reference", "health", "status",
                          "build_type", "warmup", "repeats", "below_reference_noise", "message", "frame_ms",
                          "frame_time", "render_fps", "noisy_timing", "truth", "baseline", "no_better_than_flat",
                          "claim", "baseline_volume", "method_build_type"})
        EXPECT_TRUE(m.contains(k)) << k;
    EXPECT_EQ(m.size(), 30u) << m.dump(2);
    // A method compiled into the program has the program's build type.
    EXPECT_EQ(m["method_build_type"], m["build_type"]);
    for (const char* k : {"inside", "max_error", "bound", "reason", "bounds", "met"}) EXPECT_TRUE(m["claim"].contains(k)) << k;
    for (const char* t : {"time_ms", "frame_ms"}) {
        for (const char* k : {"median", "min", "p90", "stdev", "iqr", "ci_rel"}) {
            ASSERT_TRUE(m[t].contains(k)) << t << "." << k;
            EXPECT_TRUE(m[t][k].is_number()) << t << "." << k;
        }
        // Every timed frame's time, in order: as many as the timed frames, their minimum the summary's.
        ASSERT_TRUE(m[t]["samples"].is_array()) << t;
        const std::vector<double> samples = m[t]["samples"].get<std::vector<double>>();
        EXPECT_EQ(static_cast<int>(samples.size()), m["repeats"].get<int>()) << t;
        ASSERT_FALSE(samples.empty());
        EXPECT_NEAR(*std::min_element(samples.begin(), samples.end()), m[t]["min"].get<double>(), 6e-4) << t;
    }
    for (const char* view : {"receiver", "camera", "camera_volume"})
        for (const char* k : {"nrmse", "relmse", "psnr", "ssim", "nrmse_fit", "fit_scale", "nrmse_net", "nrmse_net_lo",
                              "nrmse_net_hi", "relmse_net", "consistent_with_reference", "error_vs_baseline"})
            EXPECT_TRUE(m["error"][view].contains(k)) << view << "." << k;
    EXPECT_TRUE(m["error"]["receiver"]["nrmse"].is_number());
    EXPECT_TRUE(m["error"]["camera_volume"]["nrmse"].is_null());   // no scattering medium: no volume view
    EXPECT_TRUE(m["error"]["receiver"]["nrmse_fit"].is_null());   // radiometric: never fitted
    for (const char* k : {"photons", "noise_nrmse", "cache_key"}) EXPECT_TRUE(m["reference"].contains(k)) << k;
    EXPECT_EQ(m["reference"]["photons"].get<long long>(), 50000);
    EXPECT_TRUE(m["health"].contains("nonfinite_pixels"));
    EXPECT_EQ(m["method"], "caustic_triangles");
    EXPECT_EQ(m["scene"], "good");
    EXPECT_EQ(m["params"]["grid"], 32);
    // At least the asked repeats; more until the median is known to 5 % (or the time cap).
    EXPECT_GE(m["repeats"].get<int>(), 2);
    EXPECT_TRUE(m["noisy_timing"].get<bool>() || m["frame_ms"]["ci_rel"].get<double>() <= 0.05);
    EXPECT_EQ(m["warmup"], 1);
    EXPECT_EQ(m["threads"], 2);
    EXPECT_EQ(m["status"], "ok");
    // No temporary files are left behind by the atomic writes.
    for (const auto& entry : fs::directory_iterator(out_dir()))
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}

// The checked options (harness/cli/options.hpp) pass valid values on unchanged, in every spelling they
// accept: an exponent (2e4), a choice in any case, the largest seed, the bounds of a range.
TEST_F(CliTest, CheckedOptionsAcceptValidSpellings) {
    const std::string scene = write_scene("spellings.json", base_scene());
    const Result r = run({"render", scene, "--method", "caustic_triangles", "--set", "grid=16", "--photons", "2e4",
                          "--sampler", "Independent", "--replicas", "4", "--truth", "reference", "--seed",
                          "4611686018427387904", "--threads", "1", "--noise-target", "0", "--warmup", "0", "--repeats",
                          "1", "--max-time", "0.5", "--timing-precision", "1", "--frame", "0", "--out", out_dir(),
                          "--cache", cache_dir()});
    ASSERT_EQ(r.code, 0) << r.err;
    const json m = json::parse(slurp(fs::path(out_dir()) / "metrics.json"));
    EXPECT_EQ(m["reference"]["photons"].get<long long>(), 20000);
    EXPECT_EQ(m["reference"]["sampler"], "independent");
    EXPECT_EQ(m["reference"]["replicas"], 4);
    EXPECT_EQ(m["truth"]["kind"], "reference");
    EXPECT_EQ(m["threads"], 1);
}

TEST_F(CliTest, NoReferenceLeavesErrorNull) {
    const std::string scene = write_scene("noref.json", base_scene());
    const Result r = run({"render", scene, "--method", "caustic_triangles", "--set", "grid=16", "--no-reference",
                          "--repeats", "1", "--warmup", "0", "--out", out_dir()});
    ASSERT_EQ(r.code, 0) << r.err;
    const json m = json::parse(slurp(fs::path(out_dir()) / "metrics.json"));
    EXPECT_TRUE(m["error"]["receiver"]["nrmse"].is_null());
    EXPECT_TRUE(m["reference"]["photons"].is_null());
    EXPECT_TRUE(m["below_reference_noise"].is_null());
}

TEST_F(CliTest, ReferenceWritesFiles) {
    const std::string scene = write_scene("ref.json", base_scene());
    const Result r = run({"reference", scene, "--photons", "20000", "--out", out_dir(), "--cache", cache_dir()});
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* f : {"reference_receiver.exr", "reference_camera.exr", "reference_stderr.exr", "reference.json"})
        EXPECT_TRUE(fs::is_regular_file(fs::path(out_dir()) / f)) << f;
    const json j = json::parse(slurp(fs::path(out_dir()) / "reference.json"));
    EXPECT_EQ(j["photons"].get<long long>(), 20000);
    EXPECT_TRUE(j["noise_nrmse"].is_number());
    EXPECT_TRUE(j["ledger"]["emitted"].is_number());
}

TEST_F(CliTest, ListJsonDocumentsEveryParameter) {
    const Result r = run({"list", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = json::parse(r.out);
    ASSERT_TRUE(j["methods"].is_array());
    ASSERT_FALSE(j["methods"].empty());
    for (const json& m : j["methods"]) {
        SCOPED_TRACE(m.value("name", "?"));
        EXPECT_TRUE(m["name"].is_string());
        EXPECT_TRUE(m["doc"].is_string() && !m["doc"].get<std::string>().empty());
        EXPECT_TRUE(m["radiometric"].is_boolean());
        bool grid = false, iterations = false;
        for (const json& p : m["params"]) {
            SCOPED_TRACE(p.value("name", "?"));
            EXPECT_TRUE(p["type"].is_string());
            EXPECT_TRUE(p.contains("default") && !p["default"].is_null());
            EXPECT_TRUE(p["doc"].is_string() && !p["doc"].get<std::string>().empty());
            EXPECT_TRUE(p["valid"].is_string());
            EXPECT_TRUE(p["sweep"].is_array());   // the values "methods": "all" runs; empty: the default
            grid |= p["name"] == "grid";
            iterations |= p["name"] == "iterations";
        }
        EXPECT_TRUE(grid && iterations) << "every method declares grid and iterations";
    }
    EXPECT_TRUE(j["scenes"].is_array());
    const Result text = run({"list"});
    EXPECT_EQ(text.code, 0);
    EXPECT_NE(text.out.find("caustic_triangles"), std::string::npos);
}


// `caustics compare`: a folder that is not a sweep is refused (exit 2, one line naming results.jsonl, nothing
// written); a sweep compared with itself is the same everywhere, so even the CI gate passes, and the
// comparison's files are written (scripts/report/tests/test_compare.py tests the statistics).
TEST_F(CliTest, CompareRefusesANonSweepAndFindsASweepEqualToItself) {
    const fs::path empty = fs::path(out_dir()) / "not_a_sweep";
    fs::create_directories(empty);
    Result r = run({"compare", empty.string(), empty.string(), "--out", (fs::path(out_dir()) / "cmp").string()});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("results.jsonl"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(fs::path(out_dir()) / "cmp"));

    const fs::path spec = dir_ / "compare_spec.json";
    std::ofstream(spec) << R"({"scenes": ["sine"], "truth": "analytic", "reference": {"photons": 20000},
        "timing": {"warmup": 0, "repeats": 3, "precision": 1, "max_time_s": 0.2},
        "methods": {"caustic_triangles": {"grid": [16, 24]}}})";
    const fs::path sweep = fs::path(out_dir()) / "sweep";
    r = run({"sweep", spec.string(), "--out", sweep.string(), "--cache", cache_dir()});
    ASSERT_EQ(r.code, 0) << r.err;
    const fs::path cmp = fs::path(out_dir()) / "cmp";
    r = run({"compare", sweep.string(), sweep.string(), "--out", cmp.string(), "--fail-on-regression"});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("2 matched runs, 0 slower or worse"), std::string::npos) << r.out;
    for (const char* f : {"compare.md", "compare.csv", "compare_time_vs_error.png"})
        EXPECT_TRUE(fs::is_regular_file(cmp / f)) << f;
    EXPECT_NE(slurp(cmp / "compare.csv").find("SAME,"), std::string::npos);
    r = run({"compare", sweep.string(), sweep.string(), "--alpha", "2"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--alpha"), std::string::npos) << r.err;
    // --out is checked as every command's output folder is, before any work.
    r = run({"compare", sweep.string(), sweep.string(), "--out", "/proc/caustics_compare"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("virtual file system"), std::string::npos) << r.err;
}
