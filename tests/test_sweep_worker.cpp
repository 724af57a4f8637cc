// The sweep's two run modes (harness/sweep/worker.hpp): a worker process that renders run after run with
// the scene frame and reference kept loaded (the default), and a `caustics render` process per run
// (--isolate-runs). Both record the same results, and in both a run that crashes or hangs is recorded as
// failed while the runs after it still run. The tests drive the real `caustics` program; the failing
// runs come from the sweep_fault plugin (tests/sweep_fault/), loaded through CAUSTICS_PLUGIN_PATH.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/run/render_run.hpp>
#include <caustics/util/image_io.hpp>
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using caustics::test_support::quote;
using caustics::test_support::slurp;

// Runs `caustics ARGS` (with `environment` before it, e.g. "CAUSTICS_PLUGIN_PATH=..."), output to `log`.
int run_caustics(const std::string& args, const fs::path& log, const std::string& environment = "") {
    const std::string command = environment + " " + quote(CAUSTICS_BINARY) + " " + args + " >" + quote(log.string()) + " 2>&1";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<json> result_rows(const fs::path& sweep) {
    std::vector<json> rows;
    std::stringstream lines(slurp(sweep / "results.jsonl"));
    for (std::string line; std::getline(lines, line);) rows.push_back(json::parse(line));
    return rows;
}

json manifest_of(const fs::path& sweep) { return json::parse(slurp(sweep / "manifest.json")); }

// The fields of a results row that measure time, which no two runs share, whatever runs them: the
// timings themselves, the number of timed frames (timing stops once the median is precise), whether
// that took longer than the time cap. The row holds no other run context (no time stamp or process id).
const std::set<std::string> kTimingKeys = {"time_ms", "frame_ms", "fps", "render_fps", "prepare_ms",
                                           "update_ms", "stages_ms", "repeats", "noisy_timing"};

// The message without its "noisy timing: ..." clause, which quotes the timing's precision.
std::string without_timing(const std::string& message) {
    const std::string prefix = "noisy timing: ";
    if (message.rfind(prefix, 0) != 0) return message;
    const std::size_t end = message.find("; ");
    return end == std::string::npos ? "" : message.substr(end + 2);
}

// The store a worker keeps (LoadedFrame): the next run of the same scene file and frame reuses the
// scene frame, another frame replaces it, and the metrics are those of a run without the store.
TEST(SweepWorker, LoadedFrameIsReusedForTheSameSceneFrameOnly) {
    caustics::RenderOptions o;
    o.scene_path = "pool";   // animated: frames 0 and 1 are two scene frames
    o.method = "caustic_triangles";
    o.overrides = {{"grid", "16"}};
    o.warmup = 0;
    o.repeats = 1;
    o.no_reference = true;   // the reference's reuse is covered by the sweeps below
    o.threads = 2;
    const json alone = caustics::run_render(o).metrics;
    caustics::LoadedFrame kept;
    const json first = caustics::run_render(o, &kept).metrics;
    const caustics::SceneFrame* frame = kept.frame.get();
    ASSERT_NE(frame, nullptr);
    o.overrides = {{"grid", "32"}};
    const json second = caustics::run_render(o, &kept).metrics;
    EXPECT_EQ(kept.frame.get(), frame) << "the same scene frame was built again";
    o.frame = 1;
    (void)caustics::run_render(o, &kept);
    EXPECT_NE(kept.scene_key.find("\n1"), std::string::npos) << kept.scene_key;
    json a = alone, b = first;
    for (const std::string& key : kTimingKeys) {
        a.erase(key);
        b.erase(key);
    }
    a["message"] = without_timing(a.value("message", ""));
    b["message"] = without_timing(b.value("message", ""));
    EXPECT_EQ(a, b);
    EXPECT_EQ(second["params"]["grid"], 32);
}

// A small sweep of cheap methods on two scenes (one with an analytic truth, one measured against the
// Monte Carlo reference): 10 runs, one of them skipped (grid 1 is below caustic_triangles' range).
const char* kTwoScenes = R"({
  "scenes": ["sine", {"scene": "pool", "frames": [30]}],
  "reference": {"photons": 20000, "replicas": 4},
  "timing": {"warmup": 0, "repeats": 2, "max_time_s": 0.05},
  "methods": {"caustic_triangles": {"grid": [1, 16, 32]}, "caustic_mapping": {"grid": [16, 32]}}
})";

TEST(SweepWorker, RecordsTheSameResultsAsAProcessPerRun) {
    const caustics::test_support::ScopedTempDir d("caustics_test_sweep_worker_same");
    fs::create_directories(d.path());
    const fs::path spec = d.path() / "spec.json";
    std::ofstream(spec) << kTwoScenes;
    const std::string common = "sweep " + quote(spec.string()) + " --threads 2 --cache " + quote((d.path() / "cache").string());
    const fs::path worker = d.path() / "worker", isolated = d.path() / "isolated";
    ASSERT_EQ(run_caustics(common + " --out " + quote(worker.string()), d.path() / "log_worker"), 0)
        << slurp(d.path() / "log_worker");
    ASSERT_EQ(run_caustics(common + " --out " + quote(isolated.string()) + " --isolate-runs", d.path() / "log_isolated"), 0)
        << slurp(d.path() / "log_isolated");
    EXPECT_EQ(manifest_of(worker)["run_mode"], "worker");
    EXPECT_EQ(manifest_of(isolated)["run_mode"], "isolated");

    const std::vector<json> a = result_rows(worker), b = result_rows(isolated);
    ASSERT_EQ(a.size(), 10u);
    ASSERT_EQ(b.size(), a.size());
    std::size_t ok = 0, skipped = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        json x = a[i], y = b[i];
        const std::string id = x.value("run_id", "?");
        ok += x["status"] == "ok";
        skipped += x["status"] == "skipped";
        for (const std::string& key : kTimingKeys) {
            EXPECT_EQ(x.contains(key), y.contains(key)) << id << ": " << key;
            x.erase(key);
            y.erase(key);
        }
        x["message"] = without_timing(x.value("message", ""));
        y["message"] = without_timing(y.value("message", ""));
        EXPECT_EQ(x, y) << id;   // every other field: status, parameters, errors, reference, health, claim
        // The images hold the same pixels, bit for bit (their headers differ: a time stamp), and a
        // skipped run's log reads the same.
        const fs::path run = fs::path("runs") / id;
        for (const char* image : {"receiver.exr", "camera.exr"}) {
            ASSERT_EQ(fs::exists(worker / run / image), fs::exists(isolated / run / image)) << id << " " << image;
            if (!fs::exists(worker / run / image)) continue;
            const caustics::Image p = caustics::read_image((worker / run / image).string());
            const caustics::Image q = caustics::read_image((isolated / run / image).string());
            EXPECT_TRUE(p.width == q.width && p.height == q.height && p.channels == q.channels &&
                        std::memcmp(p.pixels.data(), q.pixels.data(), p.pixels.size() * sizeof(float)) == 0)
                << id << " " << image;
        }
        if (x["status"] == "skipped") {
            EXPECT_EQ(slurp(worker / run / "log.txt"), slurp(isolated / run / "log.txt")) << id;
        }
    }
    EXPECT_EQ(ok, 8u);
    EXPECT_EQ(skipped, 2u);
    for (const json& row : a) {
        if (row["status"] == "skipped") {
            EXPECT_NE(row["message"].get<std::string>().find("grid"), std::string::npos) << row.dump();
        }
    }
}

// A run that dies of a signal (segv, abort) or outlives the time limit (hang) is recorded as failed,
// with the same message in both modes, and the runs after it still run and are ok. fork_segv dies while
// a process it started holds the worker's socket open for 8 s, longer than the 5 s time limit: it must be
// recorded as the crash it is, not as a timeout.
class SweepFaults : public testing::TestWithParam<bool> {};

TEST_P(SweepFaults, AFailingRunIsRecordedAndTheRestRun) {
    const bool isolate = GetParam();
    const caustics::test_support::ScopedTempDir d(std::string("caustics_test_sweep_worker_faults_") + (isolate ? "i" : "w"));
    fs::create_directories(d.path());
    const fs::path spec = d.path() / "spec.json";
    std::ofstream(spec) << R"({
      "scenes": ["sine"], "reference": {"photons": 20000, "replicas": 4},
      "timing": {"warmup": 0, "repeats": 1, "max_time_s": 0.05, "timeout_s": 5},
      "methods": {"caustic_triangles": {"grid": [16]}, "sweep_fault": {"fault": ["segv", "hang", "abort", "fork_segv", "none"]}}
    })";
    const fs::path out = d.path() / "out";
    // Under AddressSanitizer (scripts/test.sh --sanitize) the injected segmentation faults must still reach
    // the process as the signal they are (ASan's own handler would end it with exit code 1): handle_segv=0
    // leaves SIGSEGV to the system. A build without ASan ignores the variable.
    const std::string plugins = "CAUSTICS_PLUGIN_PATH=" + quote(CAUSTICS_TEST_PLUGIN_DIR) +
                                " ASAN_OPTIONS=halt_on_error=1:detect_leaks=0:handle_segv=0";
    ASSERT_EQ(run_caustics("sweep " + quote(spec.string()) + " --threads 2 --out " + quote(out.string()) + " --cache " +
                               quote((d.path() / "cache").string()) + (isolate ? " --isolate-runs" : ""),
                           d.path() / "log", plugins),
              0)
        << slurp(d.path() / "log");
    EXPECT_EQ(manifest_of(out)["run_mode"], isolate ? "isolated" : "worker");
    const std::vector<json> rows = result_rows(out);
    ASSERT_EQ(rows.size(), 6u) << slurp(d.path() / "log");
    const auto expect = [&](std::size_t i, const std::string& id_part, const std::string& status, const std::string& message) {
        EXPECT_NE(rows[i]["run_id"].get<std::string>().find(id_part), std::string::npos) << rows[i].dump();
        EXPECT_EQ(rows[i]["status"], status) << rows[i].dump();
        EXPECT_EQ(rows[i]["message"].get<std::string>().rfind(message, 0), 0u) << rows[i].dump();
    };
    expect(0, "caustic_triangles", "ok", "");
    expect(1, "fault=segv", "failed", "crashed: Segmentation fault (");
    expect(2, "fault=hang", "failed", "timed out after 5");
    expect(3, "fault=abort", "failed", "crashed: Aborted (");
    expect(4, "fault=fork_segv", "failed", "crashed: Segmentation fault (");
    expect(5, "fault=none", "ok", "");
    EXPECT_TRUE(fs::exists(out / "runs" / rows[5]["run_id"].get<std::string>() / "metrics.json"));
    EXPECT_FALSE(fs::exists(out / "runs" / rows[1]["run_id"].get<std::string>() / "metrics.json"));
}

// A plugin method whose constructor throws: refused with exit 2 before any work, the message naming the
// library it came from (it said "internal failure" with what it threw alone).
TEST(PluginFaults, ThrowingFactoryIsNamedWithItsLibrary) {
    const caustics::test_support::ScopedTempDir d("caustics_test_plugin_create");
    fs::create_directories(d.path());
    const std::string plugins = "CAUSTICS_PLUGIN_PATH=" + quote(CAUSTICS_TEST_PLUGIN_DIR);
    const fs::path out = d.path() / "out";
    const int code = run_caustics("render sine --method sweep_fault --set fault=create --out " + quote(out.string()) +
                                      " --cache " + quote((d.path() / "cache").string()),
                                  d.path() / "log", plugins);
    const std::string log = slurp(d.path() / "log");
    EXPECT_EQ(code, 2) << log;
    EXPECT_NE(log.find("caustics: error: "), std::string::npos) << log;
    EXPECT_NE(log.find("sweep_fault.so"), std::string::npos) << log;
    EXPECT_NE(log.find("creating the method failed: sweep_fault: asked to fail on create"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out / "metrics.json"));
    EXPECT_FALSE(fs::exists(d.path() / "cache"));
}

// A file named like a plugin that is not a shared library: exit 2, the file named, and what would be valid.
TEST(PluginFaults, NotASharedLibraryIsNamed) {
    const caustics::test_support::ScopedTempDir d("caustics_test_plugin_not_a_library");
    fs::create_directories(d.path() / "plugins");
    std::ofstream(d.path() / "plugins" / "fake.so") << "not an ELF file\n";
    const int code = run_caustics("list", d.path() / "log", "CAUSTICS_PLUGIN_PATH=" + quote((d.path() / "plugins").string()));
    const std::string log = slurp(d.path() / "log");
    EXPECT_EQ(code, 2) << log;
    EXPECT_NE(log.find("caustics: error: "), std::string::npos) << log;
    EXPECT_NE(log.find("fake.so: cannot load the library"), std::string::npos) << log;
    EXPECT_NE(log.find("valid: a shared library built with caustics_add_method()"), std::string::npos) << log;
}

INSTANTIATE_TEST_SUITE_P(Modes, SweepFaults, testing::Values(false, true),
                         [](const testing::TestParamInfo<bool>& info) { return info.param ? "Isolated" : "Worker"; });

// `caustics compare` on real sweeps (scripts/report/compare.py): a method with a known cost (sweep_fault's
// busy-wait of 8 ms a frame) run again by the same build is SAME; run by a build with a 20 % slowdown
// injected (SWEEP_FAULT_SLOWDOWN=1.2) it is SLOWER, and the CI gate fails with exit status 3. A busy-wait
// does not follow the machine's speed drift, but its frames are preempted when other work shares the cores,
// so ctest runs this case alone (RUN_SERIAL, tests/CMakeLists.txt).
TEST(SweepCompare, AnInjectedSlowdownIsSlowerAndARepeatIsSame) {
    const caustics::test_support::ScopedTempDir d("caustics_test_sweep_compare");
    fs::create_directories(d.path());
    const fs::path spec = d.path() / "spec.json";
    std::ofstream(spec) << R"({
      "scenes": ["sine"], "truth": "analytic", "reference": {"photons": 20000},
      "timing": {"warmup": 1, "repeats": 10, "precision": 0.01, "max_time_s": 0.3, "timeout_s": 60},
      "methods": {"sweep_fault": {"work_ms": [8]}}
    })";
    const std::string plugins = "CAUSTICS_PLUGIN_PATH=" + quote(CAUSTICS_TEST_PLUGIN_DIR);
    const auto sweep = [&](const std::string& name, const std::string& env) {
        const fs::path out = d.path() / name;
        EXPECT_EQ(run_caustics("sweep " + quote(spec.string()) + " --out " + quote(out.string()) + " --cache " +
                                   quote((d.path() / "cache").string()),
                               d.path() / ("log_" + name), plugins + env),
                  0)
            << slurp(d.path() / ("log_" + name));
        return out;
    };
    const fs::path base = sweep("base", ""), again = sweep("again", ""), slow = sweep("slow", " SWEEP_FAULT_SLOWDOWN=1.2");
    const auto verdict = [&](const fs::path& a, const fs::path& b, const std::string& name, const std::string& flags) {
        const fs::path out = d.path() / ("cmp_" + name);
        const int code = run_caustics("compare " + quote(a.string()) + " " + quote(b.string()) + " --out " +
                                          quote(out.string()) + flags,
                                      d.path() / ("log_cmp_" + name));
        const std::string csv = slurp(out / "compare.csv");
        return std::make_pair(code, csv);
    };
    const auto [same_code, same_csv] = verdict(base, again, "again", " --fail-on-regression");
    EXPECT_EQ(same_code, 0) << same_csv;
    EXPECT_NE(same_csv.find(",SAME,"), std::string::npos) << same_csv;
    const auto [slow_code, slow_csv] = verdict(base, slow, "slow", "");
    EXPECT_EQ(slow_code, 0) << slow_csv;
    EXPECT_NE(slow_csv.find(",SLOWER,"), std::string::npos) << slow_csv;
    const auto [gate_code, gate_csv] = verdict(base, slow, "gate", " --fail-on-regression");
    EXPECT_EQ(gate_code, 3) << gate_csv;
}

}  // namespace
