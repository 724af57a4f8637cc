// Sweep specs, the run plan, and the sweep runner's bookkeeping (resume after SIGKILL, skipped and
// failed runs). The runner tests drive the real `caustics` program.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include <caustics/run/machine_state.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/sweep/sweep.hpp>
#include <caustics/sweep/sweep_spec.hpp>
#include "test_support.hpp"

using namespace caustics;
namespace fs = std::filesystem;

namespace {

// A folder of the test's own, removed when the test ends (also when it fails).
class TempDir {
public:
    explicit TempDir(const std::string& name)
        : path_(fs::temp_directory_path() / ("caustics_test_sweep_" + name + "_" + std::to_string(getpid()))) {
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    fs::path operator/(const std::string& name) const { return path_ / name; }

private:
    fs::path path_;
};



fs::path write_file(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
    return path;
}

std::string read_file(const fs::path& path) { return caustics::test_support::slurp(path); }

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::stringstream s(text);
    for (std::string line; std::getline(s, line);) lines.push_back(line);
    return lines;
}

std::string shell_quote(const std::string& s) { return caustics::test_support::quote(s); }

int run_program(const std::string& args, const fs::path& log) {
    const std::string command = std::string(CAUSTICS_BINARY) + " " + args + " >" + shell_quote(log.string()) + " 2>&1";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

const char* kValidSpec = R"({
  "scenes": ["sine"],
  "frames": [0],
  "reference": {"photons": 20000},
  "timing": {"warmup": 0, "repeats": 1},
  "methods": {"caustic_triangles": {"grid": {"pow2": [16, 64]}, "iterations": [1]}}
})";

}  // namespace

TEST(SweepSpec, ValidSpecExpandsToCartesianProduct) {
    const TempDir d("valid");
    const SweepSpec spec = load_sweep_spec(write_file(d / "s.json", kValidSpec).string(),
                                           {"caustic_triangles.absorption=[true,false]"});
    ASSERT_EQ(spec.methods.size(), 1u);
    const auto runs = plan_runs(spec);
    ASSERT_EQ(runs.size(), 3u * 1u * 2u);
    // Axes sorted by name (absorption, grid, iterations), the last varying fastest; ids unique.
    EXPECT_EQ(runs[0].params.at("absorption"), "true");
    EXPECT_EQ(runs[0].params.at("grid"), "16");
    EXPECT_EQ(runs[1].params.at("grid"), "32");
    EXPECT_EQ(runs[3].params.at("absorption"), "false");
    EXPECT_EQ(runs[3].params.at("grid"), "16");
    std::set<std::string> ids;
    for (const auto& r : runs) ids.insert(r.id);
    EXPECT_EQ(ids.size(), runs.size());
    EXPECT_EQ(spec.reference.photons, 20000u);
}

TEST(SweepSpec, PerSceneFramesOverrideTheDefault) {
    const TempDir d("frames");
    const SweepSpec spec = load_sweep_spec(write_file(d / "s.json", R"({
      "scenes": ["sine", {"scene": "pool", "frames": {"range": [0, 4, 2]}}], "frames": [0],
      "methods": {"caustic_triangles": {}}})").string());
    ASSERT_EQ(spec.scenes.size(), 2u);
    EXPECT_EQ(spec.scenes[0].frames, std::vector<int>{0});
    EXPECT_EQ(spec.scenes[1].frames, (std::vector<int>{0, 2, 4}));
    const auto runs = plan_runs(spec);
    ASSERT_EQ(runs.size(), 4u);   // a method with no axes runs once with its defaults
    EXPECT_EQ(runs[3].scene_name, "pool");
    EXPECT_EQ(runs[3].frame, 4);
    EXPECT_TRUE(runs[3].params.empty());
}

TEST(SweepSpec, RangeAndPow2) {
    auto r = expand_axis_values(nlohmann::json::parse(R"({"range": [1, 9, 4]})"), "f", "k");
    ASSERT_EQ(r.size(), 3u);
    EXPECT_EQ(r[2].get<int>(), 9);
    auto f = expand_axis_values(nlohmann::json::parse(R"({"range": [0.5, 1.0, 0.25]})"), "f", "k");
    ASSERT_EQ(f.size(), 3u);
    EXPECT_DOUBLE_EQ(f[2].get<double>(), 1.0);
    auto p = expand_axis_values(nlohmann::json::parse(R"({"pow2": [32, 256]})"), "f", "k");
    ASSERT_EQ(p.size(), 4u);
    EXPECT_EQ(p[3].get<int>(), 256);
}

// Axes are measured by arithmetic before they are expanded: a generator that would overflow or give too
// many values is refused at once, however large its bounds.
TEST(SweepSpec, AxesAreCountedBeforeExpanding) {
    using nlohmann::json;
    EXPECT_EQ(axis_value_count(json::parse(R"({"pow2": [1, 9007199254740992]})"), "f", "k"), 54u);
    EXPECT_EQ(axis_value_count(json::parse(R"({"range": [10, 1, -3]})"), "f", "k"), 4u);
    EXPECT_EQ(axis_value_count(json::parse(R"({"range": [0.0, 1.0, 0.25]})"), "f", "k"), 5u);
    const auto p = expand_axis_values(json::parse(R"({"pow2": [1, 9007199254740992]})"), "f", "k");
    ASSERT_EQ(p.size(), 54u);
    EXPECT_EQ(p.back().get<long long>(), 9007199254740992LL);
    const auto r = expand_axis_values(json::parse(R"({"range": [10, 1, -3]})"), "f", "k");
    ASSERT_EQ(r.size(), 4u);
    EXPECT_EQ(r.back().get<long long>(), 1);
    const auto start = std::chrono::steady_clock::now();
    for (const char* bad : {R"({"pow2": [2, 4611686018427387904]})", R"({"pow2": [2, 18446744073709551615]})",
                            R"({"range": [-9223372036854775807, 9223372036854775807, 922337203685477580]})",
                            R"({"range": [0, 9007199254740992, 1]})", R"({"range": [0, 1, 1e-300]})",
                            R"({"range": [-1e308, 1e308, 1e300]})", R"({"range": [0, 10, -1]})", R"({"range": [0, 1, 2.5e-6]})"}) {
        try {
            (void)expand_axis_values(json::parse(bad), "f.json", "methods.m.a");
            ADD_FAILURE() << bad << ": accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("methods.m.a"), std::string::npos) << bad << ": " << e.what();
        }
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 0.5);
}

// What would give two runs one id, or measure one run twice, is refused naming it.
TEST(SweepSpec, DuplicatesAreRefused) {
    const TempDir d("duplicates");
    const std::string sine = std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json";
    const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
        {"value", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": [16, 32, 16]}}})", "value 16 is given twice"},
        {"int_float", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": [64, 64.0]}}})", "(as 64 and 64.0)"},
        {"range", R"({"scenes": ["sine"], "methods": {"caustic_mapping": {"d0": {"range": [1, 1.000000000000001, 1e-16]}}}})",
         "methods.caustic_mapping.d0"},
        {"enum", R"({"scenes": ["sine"], "methods": {"caustic_mapping": {"estimator": ["newton", "approx", "newton"]}}})",
         "value newton is given twice"},
        {"scene", R"({"scenes": ["sine", ")" + sine + R"("], "methods": {"caustic_triangles": {}}})", "scenes[1]"},
        {"frame", R"({"scenes": ["pool"], "frames": {"range": [0, 4, 2]}, "methods": {"caustic_triangles": {}}})", ""},
        {"scene_frame", R"({"scenes": [{"scene": "pool", "frames": [3, 3]}], "methods": {"caustic_triangles": {}}})",
         "scenes[0].frames"},
    };
    for (const auto& [name, text, key] : cases) {
        const fs::path file = write_file(d / (name + ".json"), text);
        if (key.empty()) {   // a control: no duplicate
            EXPECT_NO_THROW(load_sweep_spec(file.string())) << name;
            continue;
        }
        try {
            load_sweep_spec(file.string());
            ADD_FAILURE() << name << ": accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << name << ": " << e.what();
        }
    }
    const fs::path ok = write_file(d / "ok.json", kValidSpec);
    EXPECT_THROW(load_sweep_spec(ok.string(), {"caustic_triangles.grid=[16]", "caustic_triangles.grid=[32]"}), InputError);
    EXPECT_NO_THROW(load_sweep_spec(ok.string(), {"caustic_triangles.grid=[16]", "caustic_triangles.iterations=[1]"}));
}

// count_runs is what plan_runs returns, and more than kMaxSweepRuns runs are refused when the spec is read.
TEST(SweepSpec, RunCountAndCeiling) {
    const TempDir d("count");
    const SweepSpec spec = load_sweep_spec(write_file(d / "s.json", R"({
      "scenes": ["sine", {"scene": "pool", "frames": [0, 1, 2]}],
      "methods": {"caustic_triangles": {"grid": [16, 32]}, "caustic_mapping": {"grid": [16], "estimator": ["approx", "newton"]}}})").string());
    EXPECT_EQ(count_runs(spec), 4u * (2u + 2u));
    EXPECT_EQ(plan_runs(spec).size(), count_runs(spec));
    const fs::path big = write_file(d / "big.json", R"({"scenes": ["sine"],
      "methods": {"caustic_mapping": {"grid": {"range": [1, 1000, 1]}, "map": {"range": [1, 101, 1]}}}})");
    try {
        load_sweep_spec(big.string());
        ADD_FAILURE() << "101000 runs accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("101000 runs"), std::string::npos) << e.what();
    }
    const fs::path edge = write_file(d / "edge.json", R"({"scenes": ["sine"],
      "methods": {"caustic_mapping": {"grid": {"range": [1, 1000, 1]}, "map": {"range": [1, 100, 1]}}}})");
    EXPECT_EQ(count_runs(load_sweep_spec(edge.string())), kMaxSweepRuns);
}

// Every shipped spec stays valid under the duplicate and size checks (paper.json needs --yes, not more): a
// parameter a method renames or drops fails here, not in a study's first run.
TEST(SweepSpec, ShippedSpecsLoad) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(std::string(CAUSTICS_SOURCE_DIR) + "/scripts/sweeps"))
        if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
    EXPECT_GE(names.size(), 3u);
    for (const std::string& name : names) {
        const std::string path = std::string(CAUSTICS_SOURCE_DIR) + "/scripts/sweeps/" + name + ".json";
        SweepSpec spec;
        ASSERT_NO_THROW(spec = load_sweep_spec(path)) << name;
        EXPECT_GT(count_runs(spec), 0u) << name;
        EXPECT_LE(count_runs(spec), kMaxSweepRuns) << name;
        EXPECT_EQ(plan_runs(spec).size(), count_runs(spec)) << name;
    }
}

// Each malformed spec: InputError whose message names the offending key.
TEST(SweepSpec, MalformedCatalog) {
    const TempDir d("malformed");
    const std::string m = R"("methods": {"caustic_triangles": {"grid": [32]}})";
    const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
        {"unknown_method", R"({"scenes": ["sine"], "methods": {"no_such_method": {}}})", "no_such_method"},
        {"unknown_axis", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"gird": [1]}}})", "gird"},
        {"empty_axis", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": []}}})", "grid"},
        {"bad_range", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": {"range": [64, 16, 8]}}}})", "grid.range"},
        {"bad_pow2", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": {"pow2": [30, 64]}}}})", "grid.pow2"},
        {"non_numeric_int", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": ["big"]}}})", "grid"},
        {"fractional_int", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": [32.5]}}})", "grid"},
        {"unknown_scene", R"({"scenes": ["atlantis"], )" + m + "}", "scenes[0]"},
        {"duplicate_axis", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": [32], "grid": [64]}}})", "grid"},
        {"negative_repeats", R"({"scenes": ["sine"], "timing": {"repeats": -3}, )" + m + "}", "timing.repeats"},
        {"unknown_top_key", R"({"scenes": ["sine"], "sceens": [], )" + m + "}", "sceens"},
        {"bad_scene_entry", R"({"scenes": [{"scene": "sine", "frame": [1]}], )" + m + "}", "scenes[0].frame"},
        {"negative_frame", R"({"scenes": ["sine"], "frames": [-1], )" + m + "}", "frames"},
        {"no_methods", R"({"scenes": ["sine"], "methods": {}})", "methods"},
        {"bad_json", R"({"scenes": ["sine"], )", "JSON"},
    };
    for (const auto& [name, text, key] : cases) {
        const fs::path file = write_file(d / (name + ".json"), text);
        try {
            load_sweep_spec(file.string());
            ADD_FAILURE() << name << ": accepted";
        } catch (const InputError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(key), std::string::npos) << name << ": " << msg;
            EXPECT_NE(msg.find(file.string()), std::string::npos) << name << ": " << msg;
        }
    }
    EXPECT_THROW(load_sweep_spec((d / "missing.json").string()), InputError);
    EXPECT_THROW(load_sweep_spec(write_file(d / "ok.json", kValidSpec).string(), {"caustic_triangles.grid"}), InputError);
}

TEST(SweepCli, MalformedSpecExitsTwoAndWritesNothing) {
    const TempDir d("cli_bad");
    const fs::path spec = write_file(d / "bad.json", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": ["x"]}}})");
    EXPECT_EQ(run_program("sweep " + shell_quote(spec.string()) + " --out " + shell_quote((d / "out").string()), d / "log"), 2);
    EXPECT_FALSE(fs::exists(d / "out"));
    EXPECT_NE(read_file(d / "log").find("methods.caustic_triangles.grid"), std::string::npos);
}

TEST(SweepCli, TooManyRunsNeedYes) {
    const TempDir d("cli_many");
    const fs::path spec = write_file(d / "big.json", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": {"range": [2, 1000, 1]}}}})");
    EXPECT_EQ(run_program("sweep " + shell_quote(spec.string()) + " --out " + shell_quote((d / "out").string()), d / "log"), 2);
    EXPECT_NE(read_file(d / "log").find("--yes"), std::string::npos);
}

// A sweep killed with SIGKILL in the middle of a run resumes: every run exactly once, finished rows
// byte-identical.
TEST(SweepCli, ResumeAfterKillKeepsFinishedRowsAndRunsEachOnce) {
    const TempDir d("resume");
    const fs::path spec = write_file(d / "s.json", R"({
      "scenes": ["sine"], "reference": {"photons": 20000}, "timing": {"warmup": 0, "repeats": 2},
      "methods": {"caustic_triangles": {"grid": [16, 24, 32, 40, 48, 56]}}})");
    const fs::path out = d / "out";
    const std::string args = "sweep " + shell_quote(spec.string()) + " --out " + shell_quote(out.string()) +
                             " --cache " + shell_quote((d / "cache").string());
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        const std::string command = std::string("exec ") + CAUSTICS_BINARY + " " + args + " >/dev/null 2>&1";
        execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    // Wait for two finished runs and the third one under way, then kill without warning.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(240);
    while (std::chrono::steady_clock::now() < deadline) {
        if (lines_of(read_file(out / "results.jsonl")).size() >= 2) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    const std::vector<std::string> before = lines_of(read_file(out / "results.jsonl"));
    ASSERT_GE(before.size(), 2u) << "the sweep did not get far enough to be interrupted";
    ASSERT_LT(before.size(), 6u) << "the sweep finished before it was killed";

    EXPECT_EQ(run_program(args, d / "log_fresh"), 2) << "an existing sweep without --resume must be refused";
    ASSERT_EQ(run_program(args + " --resume", d / "log_resume"), 0) << read_file(d / "log_resume");
    const std::vector<std::string> after = lines_of(read_file(out / "results.jsonl"));
    ASSERT_EQ(after.size(), 6u);
    for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(after[i], before[i]) << "row " << i << " changed";
    std::map<std::string, int> seen;
    for (const auto& line : after) ++seen[nlohmann::json::parse(line)["run_id"].get<std::string>()];
    EXPECT_EQ(seen.size(), 6u);
    for (const auto& [id, n] : seen) EXPECT_EQ(n, 1) << id;
    // The CSV has a header and one row per run, and each run folder has its metrics.
    EXPECT_EQ(lines_of(read_file(out / "results.csv")).size(), 7u);
    for (const auto& [id, n] : seen) EXPECT_TRUE(fs::exists(out / "runs" / id / "metrics.json")) << id;
    EXPECT_TRUE(fs::exists(out / "manifest.json"));
    // The machine's state: at the killed sweep's start (it never reached its end), and at the resumed
    // part's start and end; `loaded` follows the rule from the recorded start.
    const nlohmann::json manifest = nlohmann::json::parse(read_file(out / "manifest.json"));
    const nlohmann::json& first = manifest["machine"];
    EXPECT_TRUE(first["end"].is_null());
    ASSERT_EQ(manifest["resumed"].size(), 1u);
    const nlohmann::json& again = manifest["resumed"][0]["machine"];
    for (const nlohmann::json* m : {&first["start"], &again["start"], &again["end"]}) {
        ASSERT_TRUE((*m)["load_average"].is_array()) << m->dump();   // Linux shows /proc/loadavg
        EXPECT_EQ((*m)["load_average"].size(), 3u);
        EXPECT_GT((*m)["cores"].get<unsigned>(), 0u);
    }
    for (const nlohmann::json* m : {&first, &again}) {
        ASSERT_TRUE((*m)["start"]["busy"].is_number());   // Linux shows /proc/stat
        const double busy = (*m)["start"]["busy"].get<double>();
        EXPECT_TRUE(busy >= 0.0 && busy <= 1.0) << busy;
        MachineState start;
        start.busy = busy;
        EXPECT_EQ((*m)["loaded"].get<bool>(), machine_loaded(start));
    }
}

TEST(MachineState, LoadAverageAndTheLoadedRule) {
    double a = 0, b = 0, c = 0;
    ASSERT_TRUE(parse_loadavg("0.52 1.10 2.00 3/245 12345", a, b, c));
    EXPECT_DOUBLE_EQ(a, 0.52);
    EXPECT_DOUBLE_EQ(b, 1.10);
    EXPECT_DOUBLE_EQ(c, 2.00);
    EXPECT_FALSE(parse_loadavg("", a, b, c));
    EXPECT_FALSE(parse_loadavg("0.5 x 1", a, b, c));
    EXPECT_FALSE(parse_loadavg("-1 0 0", a, b, c));
    std::uint64_t total = 0, idle = 0;
    ASSERT_TRUE(parse_cpu_times("cpu  100 5 50 800 45 0 3 0 0 0", total, idle));
    EXPECT_EQ(total, 1003u);
    EXPECT_EQ(idle, 845u);
    EXPECT_FALSE(parse_cpu_times("cpu0 1 2 3 4", total, idle));
    EXPECT_FALSE(parse_cpu_times("cpu 1 2", total, idle));
    MachineState s;
    s.cores = 2;
    EXPECT_FALSE(machine_loaded(s)) << "nothing read: not flagged";
    s.load1 = 0.99;
    EXPECT_FALSE(machine_loaded(s));
    s.load1 = 1.0;
    EXPECT_TRUE(machine_loaded(s)) << "without a busy sample: half the cores' load";
    s.busy = 0.1;
    EXPECT_FALSE(machine_loaded(s)) << "the busy sample decides: a trailing load average is not busy now";
    s.busy = 0.5;
    EXPECT_TRUE(machine_loaded(s));
    const nlohmann::json j = machine_state_json(s);
    EXPECT_DOUBLE_EQ(j["busy"].get<double>(), 0.5);
    EXPECT_TRUE(j["load_average"].is_array());
    EXPECT_TRUE(j["governor"].is_null());
}

// An out-of-range axis value is a skipped run (with the parameter's valid range), a run past its time
// limit a failed one; the sweep still exits 0.
TEST(SweepCli, SkippedAndFailedRunsAreRecorded) {
    const TempDir d("skipfail");
    const std::string common = R"("scenes": ["sine"], "reference": {"photons": 20000},)";
    const fs::path skip_spec = write_file(d / "skip.json", "{" + common + R"( "timing": {"warmup": 0, "repeats": 1},
      "methods": {"caustic_triangles": {"grid": [1, 16]}}})");
    const std::string cache = " --cache " + shell_quote((d / "cache").string());
    ASSERT_EQ(run_program("sweep " + shell_quote(skip_spec.string()) + " --out " + shell_quote((d / "a").string()) + cache, d / "log_a"), 0)
        << read_file(d / "log_a");
    auto rows = lines_of(read_file(d / "a" / "results.jsonl"));
    ASSERT_EQ(rows.size(), 2u);
    auto skipped = nlohmann::json::parse(rows[0]);
    EXPECT_EQ(skipped["status"], "skipped");
    EXPECT_NE(skipped["message"].get<std::string>().find("grid"), std::string::npos) << skipped.dump();
    EXPECT_EQ(nlohmann::json::parse(rows[1])["status"], "ok");

    const fs::path fail_spec = write_file(d / "fail.json", "{" + common + R"( "timing": {"warmup": 0, "repeats": 1, "timeout_s": 0.05},
      "methods": {"caustic_triangles": {"grid": [16]}}})");
    ASSERT_EQ(run_program("sweep " + shell_quote(fail_spec.string()) + " --out " + shell_quote((d / "b").string()) + cache, d / "log_b"), 0)
        << read_file(d / "log_b");
    rows = lines_of(read_file(d / "b" / "results.jsonl"));
    ASSERT_EQ(rows.size(), 1u);
    auto failed = nlohmann::json::parse(rows[0]);
    EXPECT_EQ(failed["status"], "failed");
    EXPECT_NE(failed["message"].get<std::string>().find("timed out"), std::string::npos);
    EXPECT_NE(read_file(d / "b" / "results.csv").find("failed"), std::string::npos);
}
