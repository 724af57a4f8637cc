// The sweep part of the bad-input catalog (issue 12): sweeps that would mix or duplicate runs, axes that
// would overflow or run away, sweeps too large to plan, `--resume` with another plan, and a killed
// `caustics report` that must take its script along. Each case runs the real program under the
// catalog's memory and time limits (tests/catalog_support.hpp).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "catalog_support.hpp"
#include <caustics/report/report_front.hpp>

namespace fs = std::filesystem;
using nlohmann::json;
using caustics::test_support::CaseDir;
using caustics::test_support::small_sweep_spec;
using caustics::test_support::check_refused;
using caustics::test_support::ProgramResult;
using caustics::test_support::RefusalLimits;
using caustics::test_support::run_limited;
using caustics::test_support::slurp;

namespace {

std::string shipped_scene(const std::string& name) {
    return (fs::path(CAUSTICS_SOURCE_DIR) / "scenes" / (name + ".json")).string();
}

// A million runs from two axes of a thousand values each.
json million_run_spec() {
    json s = small_sweep_spec();
    s["methods"] = json::parse(R"({"caustic_mapping": {"grid": {"range": [1, 1000, 1]}, "map": {"range": [1, 1000, 1]}}})");
    return s;
}

std::vector<std::string> sweep_args(const CaseDir& dir, const std::string& spec, const std::string& out) {
    return {"sweep", spec, "--out", out, "--cache", dir.cache()};
}

// Every regular file under `root` (relative path -> bytes), to show that a refused resume changed nothing.
std::map<std::string, std::string> snapshot(const fs::path& root) {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        const std::string rel = fs::relative(entry.path(), root).string();
        files[rel] = entry.is_regular_file() ? slurp(entry.path()) : std::string("<dir>");
    }
    return files;
}

// The sweep folder the --resume cases and the report case start from, made once per test program (and
// removed when it ends).
struct BaseSweep {
    std::unique_ptr<CaseDir> dir;
    bool ok = false;
    std::string log;
};

const BaseSweep& base_sweep() {
    static const BaseSweep base = [] {
        BaseSweep b;
        b.dir = std::make_unique<CaseDir>("sweep_base");
        const std::string spec = b.dir->write_json("spec.json", small_sweep_spec());
        double seconds = 0.0;
        const ProgramResult r = run_limited({"sweep", spec, "--out", b.dir->file("sweep"), "--cache", b.dir->cache()},
                                            b.dir->path(), RefusalLimits{300, 4L << 20}, seconds);
        b.ok = r.code == 0;
        b.log = r.err;
        return b;
    }();
    return base;
}

// A copy of the base sweep folder in the case's folder (not under --out: check_refused requires that one
// empty; this one must be left unchanged instead).
fs::path copy_base(const CaseDir& dir) {
    const BaseSweep& base = base_sweep();
    if (!base.ok) throw std::runtime_error("the base sweep failed: " + base.log);
    const fs::path to = dir.path() / "sweep";
    fs::copy(base.dir->path() / "sweep", to, fs::copy_options::recursive);
    return to;
}

// ---------------------------------------------------------------------------------------------------
// A fresh sweep: the spec (and command line) is refused before anything is planned or written.

struct SpecCase {
    std::string name;
    std::function<json(const CaseDir&)> spec;
    std::vector<std::string> extra;      // further arguments
    std::vector<std::string> expect;     // what the message names
    int seconds = 30;                    // time limit (a hang or a slow refusal fails the case)
};

json with_methods(const char* methods) {
    json s = small_sweep_spec();
    s["methods"] = json::parse(methods);
    return s;
}

const std::vector<SpecCase>& spec_cases() {
    static const std::vector<SpecCase> cases = {
        {"duplicate_list_value", [](const CaseDir&) { return with_methods(R"({"caustic_triangles": {"grid": [16, 32, 16]}})"); },
         {}, {"methods.caustic_triangles.grid", "16", "twice"}},
        {"int_and_float_same_value", [](const CaseDir&) { return with_methods(R"({"caustic_triangles": {"grid": [64, 64.0]}})"); },
         {}, {"methods.caustic_triangles.grid", "64"}},
        {"range_repeats_a_value",
         [](const CaseDir&) { return with_methods(R"({"caustic_mapping": {"d0": {"range": [1, 1.000000000000001, 1e-16]}}})"); },
         {}, {"methods.caustic_mapping.d0", "1"}},
        {"axis_given_as_range_and_as_pow2", [](const CaseDir&) { return small_sweep_spec(); },
         {"--axis", R"(caustic_triangles.grid={"range": [16, 64, 16]})", "--axis", R"(caustic_triangles.grid={"pow2": [16, 64]})"},
         {"--axis", "caustic_triangles.grid", "twice"}},
        {"scene_by_name_and_by_path",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["scenes"] = {"sine", shipped_scene("sine")};
             return s;
         },
         {}, {"scenes[1]", "scenes[0]"}},
        {"scene_twice_with_other_frames",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["scenes"] = json::parse(R"(["sine", {"scene": "sine", "frames": [1]}])");
             return s;
         },
         {}, {"scenes[1]", "scenes[0]"}},
        {"scene_through_a_symlink",
         [](const CaseDir& d) {
             fs::create_symlink(shipped_scene("sine"), d.path() / "wave.json");
             json s = small_sweep_spec();
             s["scenes"] = {"sine", d.file("wave.json")};
             return s;
         },
         {}, {"scenes[1]", "scenes[0]"}},
        {"two_files_one_scene_name",   // run ids and reference folders are named after the scene
         [](const CaseDir& d) {
             fs::create_directories(d.path() / "mine");
             d.write("mine/sine.json", slurp(shipped_scene("sine")));
             json s = small_sweep_spec();
             s["scenes"] = {"sine", d.file("mine/sine.json")};
             return s;
         },
         {}, {"scenes[1]", "'sine'"}},
        {"repeated_default_frame",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["frames"] = {0, 10, 0};
             return s;
         },
         {}, {"'frames'", "0"}},
        {"repeated_scene_frame",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["scenes"] = json::parse(R"([{"scene": "pool", "frames": [30, 60, 30]}])");
             return s;
         },
         {}, {"scenes[0].frames", "30"}},
        {"pow2_past_the_64_bit_range",
         [](const CaseDir&) { return with_methods(R"({"caustic_triangles": {"grid": {"pow2": [2, 4611686018427387904]}}})"); },
         {}, {"methods.caustic_triangles.grid.pow2", "4611686018427387904"}, 5},
        {"integer_range_overflowing",
         [](const CaseDir&) {
             return with_methods(
                 R"({"caustic_triangles": {"grid": {"range": [-9223372036854775807, 9223372036854775807, 922337203685477580]}}})");
         },
         {}, {"methods.caustic_triangles.grid.range"}, 5},
        {"million_runs", [](const CaseDir&) { return million_run_spec(); }, {}, {"1000000", "runs"}, 2},
        {"million_runs_with_yes", [](const CaseDir&) { return million_run_spec(); }, {"--yes"}, {"1000000", "100000"}, 2},
        {"too_many_scene_frames_with_yes",
         [](const CaseDir& d) {
             // sine.json with an animation of 100,000 frames, so that every frame exists.
             json scene = json::parse(slurp(shipped_scene("sine")));
             scene["animation"]["frames"] = 100000;
             json s = small_sweep_spec();
             s["scenes"] = {d.write_json("long_sine.json", scene)};
             s["frames"] = json::parse(R"({"range": [0, 99999, 1]})");
             s["methods"] = json::parse(R"({"caustic_triangles": {"grid": [16, 32]}})");
             return s;
         },
         {"--yes"}, {"200000", "100000"}, 2},
        {"frame_past_the_animation",   // was a run skipped at run time
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["scenes"] = json::parse(R"(["sine", {"scene": "pool", "frames": [0, 120]}])");
             return s;
         },
         {}, {"scenes[1].frames", "frame 120 is past the animation", "pool.json", "valid 0 to 119"}},
        {"default_frame_past_the_animation",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["frames"] = {0, 1};
             return s;
         },
         {}, {"'frames'", "frame 1 is past the animation", "sine.json", "valid 0 to 0"}},
        {"unknown_timing_key",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["timing"]["repeat"] = 3;
             return s;
         },
         {}, {"timing.repeat", "valid keys"}},
        {"unknown_key_nested_in_report",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["report"] = {{"time_budget_ms", 16.7}, {"error_targets", 0.1}};
             return s;
         },
         {}, {"report.error_targets", "valid keys", "error_target"}},
        {"report_paper_settings_not_an_object",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["report"] = {{"paper_settings", {{"caustic_triangles", 256}}}};
             return s;
         },
         {}, {"report.paper_settings.caustic_triangles", "must be an object"}},
        {"photon_cap_below_photons",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["reference"]["photons"] = 200000;
             s["reference"]["photon_cap"] = 100000;
             return s;
         },
         {}, {"reference.photon_cap", "100000", "200000"}},
        {"axis_of_an_unknown_method", [](const CaseDir&) { return small_sweep_spec(); }, {"--axis", "nosuch.grid=[16]"},
         {"--axis", "nosuch", "unknown method", "caustic_triangles"}},
        {"axis_unknown_of_a_known_method", [](const CaseDir&) { return small_sweep_spec(); }, {"--axis", "caustic_triangles.gird=[16]"},
         {"--axis", "unknown axis 'gird'", "grid"}},
        {"shard_empty", [](const CaseDir&) { return small_sweep_spec(); }, {"--shard", ""}, {"--shard", "'' is not I/N"}},
        {"spec_not_an_object", [](const CaseDir&) { return json::array({"sine"}); }, {},
         {"must be a JSON object", "scenes", "an array of 1 element"}},
    };
    return cases;
}

void PrintTo(const SpecCase& c, std::ostream* os) { *os << c.name; }

class SweepSpecCatalog : public ::testing::TestWithParam<SpecCase> {};

TEST_P(SweepSpecCatalog, Refused) {
    const SpecCase& c = GetParam();
    CaseDir dir(c.name);
    const std::string spec = dir.write_json("spec.json", c.spec(dir));
    std::vector<std::string> args = sweep_args(dir, spec, dir.out());
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    check_refused(dir, args, c.expect, RefusalLimits{c.seconds, 4L << 20});
    EXPECT_FALSE(fs::exists(dir.out())) << "the output folder was created";
}

INSTANTIATE_TEST_SUITE_P(Sweep, SweepSpecCatalog, ::testing::ValuesIn(spec_cases()),
                         [](const ::testing::TestParamInfo<SpecCase>& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------------------
// --resume of the base sweep with another plan: refused naming what differs, every file unchanged.

struct ResumeCase {
    std::string name;
    std::function<json(const CaseDir&)> spec;
    std::vector<std::string> extra;
    std::vector<std::string> expect;
    std::function<void(const fs::path& sweep)> alter_folder = nullptr;   // e.g. an older manifest
};

const std::vector<ResumeCase>& resume_cases() {
    static const std::vector<ResumeCase> cases = {
        {"changed_noise_target",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["reference"]["noise_target"] = 0.25;
             return s;
         },
         {}, {"noise_target", "0.5 in the folder", "0.25 now"}},
        {"changed_photons",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["reference"]["photons"] = 40000;
             return s;
         },
         {}, {"reference.photons", "20000", "40000"}},
        {"changed_axis",
         [](const CaseDir&) { return with_methods(R"({"caustic_triangles": {"grid": [16, 24]}})"); },
         {}, {"methods.caustic_triangles.grid"}},
        {"axis_override_on_resume", [](const CaseDir&) { return small_sweep_spec(); }, {"--axis", "caustic_triangles.grid=[24]"},
         {"methods.caustic_triangles.grid"}},
        {"changed_repeats",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["timing"]["repeats"] = 2;
             return s;
         },
         {}, {"timing.repeats", "1 in the folder", "2 now"}},
        {"changed_timeout_option", [](const CaseDir&) { return small_sweep_spec(); }, {"--timeout", "7"}, {"timing.timeout_s"}},
        {"changed_truth",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["truth"] = "reference";
             return s;
         },
         {}, {"truth", "auto", "reference"}},
        {"changed_frames",
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["frames"] = {0, 1};
             return s;
         },
         {}, {"frames"}},
        {"edited_scene_file",
         [](const CaseDir& d) {
             fs::create_directories(d.path() / "scenes");
             d.write("scenes/sine.json", slurp(shipped_scene("sine")) + "\n");
             json s = small_sweep_spec();
             s["scenes"] = {d.file("scenes/sine.json")};
             return s;
         },
         {}, {"scenes.sine"}},
        {"folder_without_manifest", [](const CaseDir&) { return small_sweep_spec(); }, {}, {"manifest.json"},
         [](const fs::path& sweep) { fs::remove(sweep / "manifest.json"); }},
        {"older_manifest_with_another_spec",   // a folder from before plans were recorded: its spec is compared
         [](const CaseDir&) {
             json s = small_sweep_spec();
             s["reference"]["seed"] = 7;
             return s;
         },
         {}, {"reference.seed"},
         [](const fs::path& sweep) {
             json m = json::parse(slurp(sweep / "manifest.json"));
             m.erase("plan");
             m.erase("plan_hash");
             std::ofstream(sweep / "manifest.json", std::ios::binary) << m.dump(2) << "\n";
         }},
    };
    return cases;
}

void PrintTo(const ResumeCase& c, std::ostream* os) { *os << c.name; }

class SweepResumeCatalog : public ::testing::TestWithParam<ResumeCase> {};

TEST_P(SweepResumeCatalog, RefusedAndFolderUnchanged) {
    const ResumeCase& c = GetParam();
    CaseDir dir(c.name);
    const fs::path sweep = copy_base(dir);
    if (c.alter_folder) c.alter_folder(sweep);
    const auto before = snapshot(sweep);
    const std::string spec = dir.write_json("spec.json", c.spec(dir));
    std::vector<std::string> args = sweep_args(dir, spec, sweep.string());
    args.push_back("--resume");
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    check_refused(dir, args, c.expect);
    EXPECT_TRUE(snapshot(sweep) == before) << "the sweep folder changed";
}

INSTANTIATE_TEST_SUITE_P(Sweep, SweepResumeCatalog, ::testing::ValuesIn(resume_cases()),
                         [](const ::testing::TestParamInfo<ResumeCase>& info) { return info.param.name; });

// What is not part of the plan (the description, report settings, key order, the spec file's name and
// folder) may change on --resume; the finished rows stay as they were.
TEST(SweepResume, SamePlanIsAccepted) {
    CaseDir dir("same_plan");
    const fs::path sweep = copy_base(dir);
    const std::string rows = slurp(sweep / "results.jsonl");
    json s = small_sweep_spec();
    s["description"] = "another description";
    s["report"] = {{"time_budget_ms", 33.3}};
    const std::string spec = dir.write_json("renamed.json", s);
    double seconds = 0.0;
    std::vector<std::string> args = sweep_args(dir, spec, sweep.string());
    args.push_back("--resume");
    const ProgramResult r = run_limited(args, dir.path(), RefusalLimits{120, 4L << 20}, seconds);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(slurp(sweep / "results.jsonl"), rows);
    json manifest = json::parse(slurp(sweep / "manifest.json"));
    EXPECT_TRUE(manifest.contains("plan_hash")) << manifest.dump(2);
    EXPECT_TRUE(manifest.contains("plan")) << manifest.dump(2);
    EXPECT_EQ(manifest["resumed"].size(), 1u) << manifest.dump(2);

    // A folder from before plans were recorded resumes when its spec is the same, and records the plan.
    manifest.erase("plan");
    manifest.erase("plan_hash");
    std::ofstream(sweep / "manifest.json", std::ios::binary) << manifest.dump(2) << "\n";
    const std::string original = dir.write_json("original.json", small_sweep_spec());
    args = sweep_args(dir, original, sweep.string());
    args.push_back("--resume");
    const ProgramResult again = run_limited(args, dir.path(), RefusalLimits{120, 4L << 20}, seconds);
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_EQ(slurp(sweep / "results.jsonl"), rows);
    EXPECT_TRUE(json::parse(slurp(sweep / "manifest.json")).contains("plan_hash"));
}

// ---------------------------------------------------------------------------------------------------
// A killed `caustics report` takes report.py with it, and no report.md appears afterwards.

// Processes other than this one whose command line contains `needle` (and `also`, when given).
std::vector<pid_t> processes_naming(const std::string& needle, const std::string& also = "") {
    std::vector<pid_t> found;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator("/proc", ec)) {
        const std::string name = entry.path().filename().string();
        if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
        const pid_t pid = static_cast<pid_t>(std::stol(name));
        if (pid == getpid()) continue;
        std::string cmdline = slurp(entry.path() / "cmdline");
        for (char& ch : cmdline)
            if (ch == '\0') ch = ' ';
        if (cmdline.find(needle) != std::string::npos && (also.empty() || cmdline.find(also) != std::string::npos))
            found.push_back(pid);
    }
    return found;
}

TEST(ReportChild, KilledReportLeavesNoScriptAndNoReport) {
    if (caustics::find_plotting_python().empty()) GTEST_SKIP() << "no python3 with matplotlib, pandas, numpy and OpenImageIO";
    CaseDir dir("report_kill");
    const fs::path sweep = copy_base(dir);
    const std::string folder = sweep.string();
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        const int null_fd = open("/dev/null", O_WRONLY);
        dup2(null_fd, STDOUT_FILENO);
        dup2(null_fd, STDERR_FILENO);
        execl(CAUSTICS_BINARY, CAUSTICS_BINARY, "report", folder.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    using clock = std::chrono::steady_clock;
    bool started = false;
    for (const auto deadline = clock::now() + std::chrono::seconds(60); clock::now() < deadline;) {
        if (!processes_naming(folder, "report.py").empty()) {
            started = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(started) << "report.py never started";

    std::vector<pid_t> left;
    for (const auto deadline = clock::now() + std::chrono::seconds(2); clock::now() < deadline;) {
        left = processes_naming(folder);
        if (left.empty()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_TRUE(left.empty()) << left.size() << " process(es) still naming " << folder << " 2 s after the kill";
    for (const pid_t p : left) kill(p, SIGKILL);   // leave nothing behind either way
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    EXPECT_FALSE(fs::exists(sweep / "report.md")) << "report.md appeared after its command was killed";
}

}  // namespace
