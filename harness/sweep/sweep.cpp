#include <caustics/sweep/sweep.hpp>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/run/machine_state.hpp>
#include <caustics/run/run_context.hpp>
#include <caustics/sweep/worker.hpp>

#include "detail/sweep_files.hpp"
#include "detail/sweep_plan.hpp"

namespace caustics {
namespace fs = std::filesystem;
using nlohmann::json;
using sweep_files::differences;
using sweep_files::joined;
using sweep_files::listed;
using sweep_files::read_result_lines;

namespace {

std::string self_executable() {
    std::error_code ec;
    fs::path p = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string("caustics") : p.string();
}

std::string last_line_of(const std::string& path) {
    std::ifstream in(path);
    std::string line, last;
    while (std::getline(in, line))
        if (!line.empty()) last = line;
    const std::string prefix = "caustics: error: ";
    if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
    return last;
}

std::string csv_field(const json& v) {
    std::string s;
    if (v.is_null()) return "";
    if (v.is_string()) s = v.get<std::string>();
    else if (v.is_boolean()) s = v.get<bool>() ? "true" : "false";
    else if (v.is_number()) s = v.dump();
    else s = v.dump();
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

const json& at_path(const json& j, std::initializer_list<const char*> keys) {
    static const json null_value;
    const json* cur = &j;
    for (const char* k : keys) {
        if (!cur->is_object() || !cur->contains(k)) return null_value;
        cur = &(*cur)[k];
    }
    return *cur;
}

// The row of a run that produced no metrics.json (bad parameters, crash, timeout).
json bare_row(const PlannedRun& run, const std::string& status, const std::string& message) {
    json params(json::object());
    for (const auto& [k, v] : run.params) params[k] = v;
    return {{"method", run.method}, {"scene", run.scene_name}, {"frame", run.frame}, {"params", params},
            {"status", status}, {"message", message}};
}

// Shortest text that reads back as the same double (children parse it).
std::string number_text(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// The reference the run's children will ask for, so the parent's computation fills their cache entry.
void apply_reference_options(const SweepSpec& spec, const PlannedRun& run, RenderOptions& ro) {
    ro.reference = spec.reference;
    ro.reference.noise_target = run.noise_target;
}

// What a shard's manifest records of it: which of the plan's runs it holds (positions and ids).
json shard_record(const ShardId& shard, const std::vector<PlannedRun>& runs, const std::vector<std::size_t>& positions) {
    json ids = json::array();
    for (const std::size_t p : positions) ids.push_back(runs[p].id);
    return {{"index", shard.index}, {"count", shard.count}, {"positions", positions}, {"run_ids", ids}};
}

std::string shard_text(const json& shard) {
    if (!shard.is_object()) return "a whole sweep";
    return "shard " + shard.value("index", json()).dump() + "/" + shard.value("count", json()).dump();
}

// The reference of the run's scene and frame, through the cache, and its files in `ref_dir`. False when
// the scene frame has no reference (bad input of that scene frame: the runs record the message).
bool prepare_reference(const SweepSpec& spec, const PlannedRun& run, const SweepOptions& options,
                       const std::string& cache, const fs::path& ref_dir) {
    try {
        RenderOptions ro;
        apply_reference_options(spec, run, ro);
        ro.threads = options.threads;
        ro.cache_dir = cache;
        ro.progress = options.progress;
        SceneFrame sf(load_scene(run.scene_path), run.frame);
        const ReferenceResult ref = reference_for(sf, ro);
        write_reference_outputs(ref_dir.string(), sf.scene(), run.frame, ref);
        // The closed form the runs' receiver errors are measured against, for the report's images.
        if (run.truth != "reference") {
            const AnalyticTruth truth = analytic_truth(sf.geometry(), sf.chart());
            if (truth.available) write_exr(truth.receiver, (ref_dir / "truth_receiver.exr").string());
        }
        return true;
    } catch (const InputError&) {
        return false;
    }
}

// --references-only: every (scene, frame) reference of the sweep, or shard I of N of them (the pairs in
// order of first use, pair k in shard k mod N), into the cache and DIR/references/. Runs nothing.
SweepSummary compute_references(const SweepSpec& spec, const std::vector<PlannedRun>& runs, const SweepOptions& options) {
    const std::string cache = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    SweepSummary summary;
    std::set<std::string> seen;
    std::size_t k = 0;
    for (const PlannedRun& run : runs) {
        const std::string key = reference_key(run);
        if (!seen.insert(key).second) continue;
        const bool mine = !options.shard.active() || static_cast<int>(k % options.shard.count) == options.shard.index;
        ++k;
        if (!mine) continue;
        ++summary.total;
        if (options.progress) std::fprintf(stderr, "sweep: reference %s\n", key.c_str());
        if (prepare_reference(spec, run, options, cache, fs::path(options.out_dir) / "references" / key)) ++summary.references;
        else ++summary.skipped;
    }
    return summary;
}

}  // namespace

std::string run_mode(const SweepOptions& options) {
    const bool other_program = !options.render_program.empty() && options.render_program != self_executable();
    return options.isolate_runs || other_program ? "isolated" : "worker";
}

std::set<std::string> csv_param_names(const SweepSpec& spec) {
    std::set<std::string> param_names;
    for (const auto& m : spec.methods)
        if (const MethodInfo* info = find_method(m.method))
            for (const auto& p : info->params) param_names.insert(p.name);
    return param_names;
}

std::string results_csv(const SweepSpec& spec, const std::vector<json>& rows) {
    return results_csv(csv_param_names(spec), rows);
}

std::string results_csv(const std::set<std::string>& param_names, const std::vector<json>& rows) {
    struct Column {
        std::string name;
        std::function<json(const json&)> get;
    };
    std::vector<Column> columns;
    auto add = [&](std::string name, std::initializer_list<const char*> path) {
        std::vector<const char*> keys(path);
        columns.push_back({std::move(name), [keys](const json& r) {
                               const json* cur = &r;
                               for (const char* k : keys) {
                                   if (!cur->is_object() || !cur->contains(k)) return json();
                                   cur = &(*cur)[k];
                               }
                               return *cur;
                           }});
    };
    add("run_id", {"run_id"});
    add("scene", {"scene"});
    add("frame", {"frame"});
    add("method", {"method"});
    add("status", {"status"});
    add("radiometric", {"radiometric"});
    add("grid", {"params", "grid"});
    add("iterations", {"params", "iterations"});
    add("time_ms_median", {"time_ms", "median"});
    add("time_ms_min", {"time_ms", "min"});
    add("time_ms_p90", {"time_ms", "p90"});
    add("time_ms_stdev", {"time_ms", "stdev"});
    add("time_ms_iqr", {"time_ms", "iqr"});
    add("time_ms_ci_rel", {"time_ms", "ci_rel"});
    add("frame_time", {"frame_time"});
    add("frame_ms_median", {"frame_ms", "median"});
    add("frame_ms_ci_rel", {"frame_ms", "ci_rel"});
    add("fps", {"fps"});
    add("render_fps", {"render_fps"});
    add("noisy_timing", {"noisy_timing"});
    add("prepare_ms", {"prepare_ms"});
    add("update_ms", {"update_ms"});
    for (const char* metric : {"nrmse", "relmse", "psnr", "ssim", "nrmse_fit", "fit_scale", "nrmse_net", "nrmse_net_lo",
                               "nrmse_net_hi", "relmse_net", "nrmse_fit_net", "nrmse_fit_net_lo", "nrmse_fit_net_hi",
                               "consistent_with_reference"}) {
        add(metric, {"error", "receiver", metric});
        add(std::string("camera_") + metric, {"error", "camera", metric});
        add(std::string("volume_") + metric, {"error", "camera_volume", metric});
    }
    // The error the report ranks, of the kind the method is judged by (fitted when not radiometric).
    columns.push_back({"error_kind", [](const json& r) {
                           if (!r.contains("radiometric") || !r["radiometric"].is_boolean()) return json();
                           return json(r["radiometric"].get<bool>() ? "nrmse" : "nrmse_fit");
                       }});
    for (const char* suffix : {"", "_lo", "_hi"}) {
        const std::string s = suffix;
        columns.push_back({"error_net" + s, [s](const json& r) {
                               const json& radiometric = at_path(r, {"radiometric"});
                               if (!radiometric.is_boolean()) return json();
                               const std::string key = (radiometric.get<bool>() ? "nrmse_net" : "nrmse_fit_net") + s;
                               return at_path(r, {"error", "receiver", key.c_str()});
                           }});
    }
    add("baseline_error", {"baseline", "error"});
    add("baseline_kind", {"baseline", "kind"});
    add("error_vs_baseline", {"error", "receiver", "error_vs_baseline"});
    add("no_better_than_flat", {"no_better_than_flat"});
    add("claim_inside", {"claim", "inside"});
    add("claim_max_error", {"claim", "max_error"});
    add("claim_bound", {"claim", "bound"});
    add("claim_met", {"claim", "met"});
    add("claim_reason", {"claim", "reason"});
    add("truth", {"truth", "kind"});
    columns.push_back({"noise_nrmse", [](const json& r) {
                           // The noise of the truth the errors are measured against (0 for a closed form).
                           const json& t = at_path(r, {"truth", "noise_nrmse"});
                           return t.is_null() ? at_path(r, {"reference", "noise_nrmse"}) : t;
                       }});
    add("reference_noise_nrmse", {"reference", "noise_nrmse"});
    add("reference_noise_nrmse_volume", {"reference", "noise_nrmse_volume"});
    add("volume_baseline_error", {"baseline_volume", "error"});
    add("volume_error_vs_baseline", {"error", "camera_volume", "error_vs_baseline"});
    add("noise_target", {"reference", "noise_target"});
    add("noise_target_met", {"reference", "noise_target_met"});
    add("below_reference_noise", {"below_reference_noise"});
    add("reference_photons", {"reference", "photons"});
    add("threads", {"threads"});
    columns.push_back({"health", [](const json& r) {
                           std::string s;
                           if (r.contains("health") && r["health"].is_object())
                               for (const auto& [k, v] : r["health"].items())
                                   s += (s.empty() ? "" : ";") + k + "=" + v.dump();
                           return json(s);
                       }});
    for (const auto& name : param_names) {
        columns.push_back({"param." + name, [name](const json& r) {
                               const json& v = at_path(r, {"params"});
                               return v.is_object() && v.contains(name) ? v[name] : json();
                           }});
    }
    add("message", {"message"});

    std::string out;
    for (std::size_t c = 0; c < columns.size(); ++c) out.append(c ? "," : "").append(columns[c].name);
    out += "\n";
    for (const auto& row : rows) {
        for (std::size_t c = 0; c < columns.size(); ++c) out.append(c ? "," : "").append(csv_field(columns[c].get(row)));
        out += "\n";
    }
    return out;
}

namespace {

// The `caustics render` command line of one planned run (its reference read from the shared cache).
std::vector<std::string> render_argv(const SweepSpec& spec, const PlannedRun& run, const SweepOptions& options,
                                     const std::string& program, const std::string& cache, const fs::path& run_dir) {
    std::vector<std::string> argv = {program, "render", run.scene_path, "--method", run.method,
                                     "--frame", std::to_string(run.frame), "--out", run_dir.string(),
                                     "--warmup", std::to_string(spec.warmup), "--repeats", std::to_string(spec.repeats),
                                     "--timing-precision", number_text(spec.timing_precision),
                                     "--max-time", number_text(spec.timing_max_s), "--truth", run.truth,
                                     "--threads", std::to_string(options.threads), "--cache", cache};
    ReferenceSettings asked = spec.reference;
    asked.noise_target = run.noise_target;
    for (std::string& a : reference_arguments(asked)) argv.push_back(std::move(a));
    for (const auto& [k, v] : run.params) {
        argv.push_back("--set");
        argv.push_back(k + "=" + v);
    }
    return argv;
}

// The run's row: its metrics.json, or a bare row saying how the child ended.
json row_of_child(const ChildResult& child, const PlannedRun& run, const fs::path& run_dir, const std::string& log,
                  double timeout) {
    json row;
    const fs::path metrics_path = run_dir / "metrics.json";
    if (child.exit_code == 0 && fs::exists(metrics_path)) {
        std::ifstream in(metrics_path);
        row = json::parse(in, nullptr, false);
        if (row.is_discarded()) row = bare_row(run, "failed", "metrics.json unreadable");
    } else if (child.timed_out) {
        row = bare_row(run, "failed", "timed out after " + std::to_string(timeout) + " s");
    } else if (child.signal) {
        row = bare_row(run, "failed", std::string("crashed: ") + strsignal(child.signal) + " (" + last_line_of(log) + ")");
    } else if (child.exit_code == 2) {
        row = bare_row(run, "skipped", last_line_of(log));   // the method rejected the parameters
    } else {
        row = bare_row(run, "failed", "exit code " + std::to_string(child.exit_code) + ": " + last_line_of(log));
    }
    return row;
}

}  // namespace

SweepSummary run_sweep(const SweepOptions& options) {
    const SweepSpec spec = load_sweep_spec(options.spec_path, options.axis_overrides);   // at most kMaxSweepRuns
    const std::uint64_t planned = count_runs(spec);
    if (planned > kMaxRunsWithoutConfirmation && !options.yes)
        throw InputError(options.spec_path, "methods",
                         "the sweep has " + std::to_string(planned) + " runs (more than " +
                             std::to_string(kMaxRunsWithoutConfirmation) + "); pass --yes to run it anyway");
    const std::vector<PlannedRun> runs = plan_runs(spec);
    if (options.out_dir.empty()) throw InputError("--out", "", "a sweep needs an output folder");
    // A shard is a sweep folder of its own under DIR/shards/I, holding the runs assigned to it.
    const fs::path dir = options.shard.active() ? fs::path(options.out_dir) / "shards" / std::to_string(options.shard.index)
                                                : fs::path(options.out_dir);
    std::vector<std::size_t> positions;
    if (options.shard.active()) {
        positions = assign_shards(runs, options.shard.count)[static_cast<std::size_t>(options.shard.index)];
    } else {
        for (std::size_t i = 0; i < runs.size(); ++i) positions.push_back(i);
    }
    const fs::path jsonl = dir / "results.jsonl";
    std::error_code ec;
    if (!options.resume && !options.references_only && fs::exists(jsonl, ec))
        throw InputError("--out", options.out_dir, "already holds a sweep; pass --resume to continue it or choose another folder");
    // Every scene must load before anything runs: a malformed scene is bad input of the whole sweep.
    std::vector<std::string> scene_hashes;
    for (const auto& scene : spec.scenes) scene_hashes.push_back(sweep_plan::scene_content_hash(load_scene(scene.path)));
    const double timeout = options.timeout_s > 0.0 ? options.timeout_s : spec.timeout_s;
    const json plan = sweep_plan::sweep_plan(spec, runs, scene_hashes, options.threads, timeout);

    // A resumed sweep must continue the plan it was started with: checked before any file is written.
    if (options.references_only) return compute_references(spec, runs, options);
    json manifest = options.resume ? sweep_plan::check_resume(dir, plan, spec) : json::object();
    const json shard = options.shard.active() ? shard_record(options.shard, runs, positions) : json();
    if (!manifest.empty() && manifest.value("shard", json()) != shard)
        throw InputError("--resume", dir.string(),
                         "the sweep in this folder was started as " + shard_text(manifest.value("shard", json())) +
                             ", not as " + shard_text(shard) + "; resume it with the same --shard");
    const MachineState machine_start = read_machine_state();
    if (manifest.empty()) {
        manifest = run_context();
        manifest["machine"] = {{"start", machine_state_json(machine_start)}, {"end", nullptr},
                               {"loaded", machine_loaded(machine_start)}};
        manifest["spec_path"] = options.spec_path;
        manifest["spec"] = spec.as_run;
        manifest["runs_planned"] = runs.size();
        manifest["run_mode"] = run_mode(options);
        if (const json slurm = slurm_environment(); !slurm.is_null()) manifest["slurm"] = slurm;
    } else {
        json resumed = run_context();
        resumed["machine"] = {{"start", machine_state_json(machine_start)}, {"end", nullptr},
                              {"loaded", machine_loaded(machine_start)}};
        resumed["spec_path"] = options.spec_path;
        resumed["run_mode"] = run_mode(options);
        if (const json slurm = slurm_environment(); !slurm.is_null()) resumed["slurm"] = slurm;
        manifest["resumed"].push_back(resumed);
    }
    manifest["plan"] = plan;
    manifest["plan_hash"] = sweep_plan::plan_hash(plan);
    if (options.shard.active()) {
        manifest["shard"] = shard;
        manifest["csv_params"] = csv_param_names(spec);
    }
    fs::create_directories(dir / "runs");
    write_text_atomic((dir / "manifest.json").string(), manifest.dump(2) + "\n");

    std::vector<std::string> lines = read_result_lines(jsonl);
    std::set<std::string> finished;
    std::vector<json> rows;
    for (const auto& l : lines) {
        rows.push_back(json::parse(l));
        finished.insert(rows.back()["run_id"].get<std::string>());
    }
    // Rewrite once so that a cut-off trailing line is gone before new lines follow it.
    write_text_atomic(jsonl.string(), joined(lines));
    write_text_atomic((dir / "results.csv").string(), results_csv(spec, rows));

    SweepSummary summary;
    summary.total = positions.size();
    summary.done_before = finished.size();
    const std::string program = options.render_program.empty() ? self_executable() : options.render_program;
    const std::string cache = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    const auto start = std::chrono::steady_clock::now();
    std::set<std::string> references_done;
    // One worker for the sweep (replaced after a crash or timeout); null: a child per run.
    std::unique_ptr<SweepWorker> worker;
    if (run_mode(options) == "worker") worker = std::make_unique<SweepWorker>(program);

    for (const std::size_t position : positions) {
        const PlannedRun& run = runs[position];
        if (finished.count(run.id)) continue;
        const fs::path run_dir = dir / "runs" / run.id;
        fs::remove_all(run_dir, ec);   // a run cut off earlier is redone from scratch
        fs::create_directories(run_dir);

        // The shared reference of this scene and frame, computed here once, read by the children from
        // the cache. A frame outside the scene's animation is the run's problem (skipped), not the sweep's.
        const std::string ref_key = reference_key(run);
        if (!references_done.count(ref_key)) {
            references_done.insert(ref_key);
            prepare_reference(spec, run, options, cache, dir / "references" / ref_key);
        }

        const std::vector<std::string> argv = render_argv(spec, run, options, program, cache, run_dir);
        const std::string log = (run_dir / "log.txt").string();
        if (options.progress) {
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const std::size_t done = summary.ran, left = positions.size() - finished.size() - summary.ran;
            std::string eta = done ? std::to_string(static_cast<long>(elapsed / done * left)) + " s" : "?";
            std::fprintf(stderr, "sweep [%zu/%zu] %s  (%.2f runs/s, ETA %s)\n", finished.size() + summary.ran + 1,
                         positions.size(), run.id.c_str(), done ? done / elapsed : 0.0, eta.c_str());
        }
        const ChildResult child = worker ? worker->run(std::vector<std::string>(argv.begin() + 1, argv.end()), log, timeout)
                                         : run_child(argv, log, timeout);

        json row = row_of_child(child, run, run_dir, log, timeout);
        row["run_id"] = run.id;
        row["scene"] = run.scene_name;
        const std::string status = row.value("status", "failed");
        summary.ok += status == "ok";
        summary.skipped += status == "skipped";
        summary.failed += status == "failed";
        summary.unstable += status == "unstable";
        ++summary.ran;

        lines.push_back(row.dump());
        rows.push_back(row);
        write_text_atomic(jsonl.string(), joined(lines));
        write_text_atomic((dir / "results.csv").string(), results_csv(spec, rows));
    }
    // The machine as the sweep ends (its own runs are part of this load), beside the start's.
    json& machine = manifest.contains("resumed") ? manifest["resumed"].back()["machine"] : manifest["machine"];
    machine["end"] = machine_state_json(read_machine_state());
    write_text_atomic((dir / "manifest.json").string(), manifest.dump(2) + "\n");
    summary.loaded = machine_loaded(machine_start);
    return summary;
}

}  // namespace caustics
