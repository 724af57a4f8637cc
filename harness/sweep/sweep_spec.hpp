#pragma once
// Sweep specifications (issue "Sweeps and paper outputs"): which scenes, frames and methods to run, and
// for each method its named axes, whose Cartesian product is the set of runs (nvbench-style axes).
//
// {
//   "description": "free text",
//   "scenes": ["sine", {"scene": "pool", "frames": [30, 60]}],   // a name in scenes/ or a path,
//                                                 // optionally with its own frames, "noise_target"
//                                                 // and "truth"
//   "frames": [0, 10] | {"range": [0, 30, 10]},  // frames of scenes that name none (default [0])
//   "reference": {"photons": 2000000, "seed": 1,       // photons: fixed count, or the first round
//                 "noise_target": 0.02,               // add photons until noise_nrmse <= target
//                 "photon_cap": 2000000000, "sampler": "sobol", "replicas": 8},
//   "truth": "auto",                             // receiver truth: auto | analytic | reference
//   "timing": {"warmup": 2, "repeats": 5, "timeout_s": 600,
//              "precision": 0.05, "max_time_s": 3},  // repeat until the median is known to 5 % or 3 s
//   "report": {...},                             // settings for `caustics report` (scripts/report)
//   "methods": {
//     "my_method":    {"grid": {"pow2": [32, 256]}},
//     "other_method": {"grid": [64, 128], "iterations": {"range": [1, 5, 1]},
//                     "estimator": ["approx", "newton"]}
//   }
//   or "methods": "all"                          // every registered method, each parameter at the sweep
//                                                // values its table declares (ParamSpec::sweep), the
//                                                // others at their defaults; --axis still overrides
// }
//
// Axis values: a list of scalars; {"range": [start, stop, step]} (stop included when reached);
// {"pow2": [lo, hi]} (every power of two from lo to hi, both powers of two). Axes are checked against the
// method's parameter table when the spec is read (unknown axis, wrong type, empty axis: InputError);
// values outside a parameter's range are not an error of the spec: that run is recorded as skipped.
//
// What would mix or duplicate runs is refused (InputError naming it): a value given twice in one axis
// (compared by canonical value after expansion: 64 and 64.0, or two range steps that print the same), a
// frame given twice for one scene, a scene given twice (the same file by name, by path or through a
// link), two scene files with one name (run ids and reference folders are named after the scene), an
// --axis given twice. Sizes are bounded before anything is expanded, by arithmetic on the generators:
// at most kMaxAxisValues values per axis (frames included), integers within +-kMaxAxisInteger, and at
// most kMaxSweepRuns runs in all (even with --yes; sweep.hpp asks for --yes above 500).
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/reference/reference.hpp>

namespace caustics {

constexpr std::uint64_t kMaxAxisValues = 100'000;      // values of one axis or one scene's frames
constexpr std::uint64_t kMaxSweepRuns = 100'000;       // runs of one sweep, even with --yes
constexpr long long kMaxAxisInteger = 1LL << 53;       // 9007199254740992: the largest integer a double
                                                       // (results.csv, the report, range checks) holds exactly

struct SweepAxis {
    std::string name;
    std::vector<std::string> values;   // canonical text of each value, in order
};

struct SweepMethod {
    std::string method;
    std::vector<SweepAxis> axes;       // sorted by name (JSON objects are unordered)
};

struct SweepScene {
    std::string path;                  // resolved scene file path
    std::vector<int> frames;
    double noise_target = -1.0;        // < 0: the spec's reference.noise_target
    std::string truth;                 // empty: the spec's truth
};

struct SweepSpec {
    std::string path;
    std::string description;
    std::vector<SweepScene> scenes;
    ReferenceSettings reference{.photons = 2'000'000};   // noise_target 0: a fixed photon count
    std::string truth = "auto";
    int warmup = 2;
    int repeats = 5;
    double timing_precision = 0.05;
    double timing_max_s = 3.0;
    double timeout_s = 0.0;            // per-run limit (0: none); a run past it is recorded as failed
    std::vector<SweepMethod> methods;
    nlohmann::json as_run;             // the spec after command-line overrides (the manifest records it)
};

// One run of the Cartesian product.
struct PlannedRun {
    std::string id;                    // stable, file-name safe, unique within the sweep
    std::string scene_path;
    std::string scene_name;
    int frame = 0;
    double noise_target = 0.0;         // the scene's reference noise target (0: fixed photons)
    std::string truth = "auto";
    std::string method;
    std::map<std::string, std::string> params;   // the axis values of this run
};

// The run's (scene, frame) reference as a folder name, "<scene>-f<frame>": the runs that share it share
// one reference (DIR/references/<key>/).
std::string reference_key(const PlannedRun& run);

// Reads a spec and applies `axis_overrides` ("method.axis=<json value>", from --axis). Throws InputError
// naming the file and key for every malformed input, every duplicate, and a sweep of more than
// kMaxSweepRuns runs (counted before any axis is expanded).
SweepSpec load_sweep_spec(const std::string& path, const std::vector<std::string>& axis_overrides = {});

// The number of runs plan_runs would return, without planning them (saturates at UINT64_MAX).
std::uint64_t count_runs(const SweepSpec& spec);

// The runs in a fixed order: scene, frame, method (by name), then the Cartesian product of the axes
// (sorted by name; the last one varies fastest). Throws InputError if two runs would share an id or the
// spec has more than kMaxSweepRuns runs.
std::vector<PlannedRun> plan_runs(const SweepSpec& spec);

// The number of values an axis description (list, range or pow2) gives, computed without expanding it;
// throws InputError for a malformed one or one whose numbers are out of bounds. `key` names it.
std::uint64_t axis_value_count(const nlohmann::json& value, const std::string& file, const std::string& key);

// Expands one axis value description (list, range or pow2); throws InputError (as axis_value_count) and
// for more than kMaxAxisValues values. `key` names it in messages.
std::vector<nlohmann::json> expand_axis_values(const nlohmann::json& value, const std::string& file,
                                               const std::string& key);

}  // namespace caustics
