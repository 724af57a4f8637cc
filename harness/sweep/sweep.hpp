#pragma once
// The sweep runner (`caustics sweep SPEC --out DIR [--resume]`).
//
// Each run executes in a child process writing DIR/runs/<run-id>/, so that a method that crashes, aborts
// or hangs is recorded as `failed` and the sweep goes on; the child dies with the sweep
// (PR_SET_PDEATHSIG). By default the child is a worker that renders run after run with the scene frame and
// reference kept loaded (worker.hpp); --isolate-runs starts a `caustics render` process per run instead.
// Both record the same results (timing aside); manifest.json says which ran ("run_mode"). References are
// computed once per scene and frame by the sweep itself, through the on-disk cache that the children
// then read.
//
// Files: DIR/manifest.json (context + spec as run + the plan and its hash), DIR/results.jsonl (one line
// per finished run, the source of truth), DIR/results.csv (derived from it), DIR/references/<scene>-f<frame>/,
// DIR/runs/<id>/. A finished run's line is never rewritten: results.jsonl is replaced atomically with the
// old lines copied byte for byte plus the new one, so a sweep killed at any moment keeps every finished
// run, and --resume redoes only runs without a line.
//
// The plan (manifest.json "plan", hashed as "plan_hash") is everything that decides what a run measures
// and against what: per scene its file contents (and assets), frames, reference noise target and truth;
// the reference settings (photons, seed, photon cap, sampler, replicas); the timing protocol (warm-up,
// repeats, precision, time cap, per-run time limit, threads); every method's axis values; and the runs
// (count and a hash of every run's id and parameters). --resume with another plan is refused (InputError
// naming what differs, e.g. "scenes.pool.noise_target: 0.003 in the folder, 0.002 now") before any file
// is written; so is --resume of a folder with results but no readable manifest. A folder from before
// plans were recorded is compared by its spec (description and report settings aside). A resume with the
// same plan keeps the manifest and appends its own context to "resumed".
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/sweep/shard.hpp>
#include <caustics/sweep/sweep_spec.hpp>

namespace caustics {

struct SweepOptions {
    std::string spec_path;
    std::vector<std::string> axis_overrides;   // --axis METHOD.AXIS=VALUES
    std::string out_dir;
    bool resume = false;
    bool yes = false;                          // allow more than kMaxRunsWithoutConfirmation runs
    int threads = 0;
    std::string cache_dir;                     // empty: default_cache_dir()
    std::string render_program;                // the `caustics` executable; empty: this process's
    bool isolate_runs = false;                 // one `caustics render` process per run (no worker)
    double timeout_s = 0.0;                    // per-run limit; 0: the spec's timing.timeout_s or none
    bool progress = true;
    ShardId shard;                             // --shard I/N: shard I of N into out_dir/shards/I (shard.hpp)
    bool references_only = false;              // compute the references (of the shard's (scene, frame)
                                               // pairs when sharded) into the cache and out_dir/references
};

constexpr std::size_t kMaxRunsWithoutConfirmation = 500;

// "worker" or "isolated": how the sweep runs its runs. Workers are used unless isolate_runs is set or
// render_program names another program than this one, which need not know the worker's protocol (the
// worker is this program's own hidden `sweep-worker` command).
std::string run_mode(const SweepOptions& options);

struct SweepSummary {
    std::size_t total = 0, done_before = 0, ran = 0, ok = 0, skipped = 0, failed = 0, unstable = 0;
    std::size_t references = 0;   // references computed or found (--references-only)
    bool loaded = false;          // the machine was busy as the sweep started (manifest.json machine.loaded)
};

// Throws InputError for a bad spec, a sweep of more than kMaxRunsWithoutConfirmation runs without --yes
// (or more than kMaxSweepRuns at all), an existing sweep directory without --resume, or --resume with
// another plan.
SweepSummary run_sweep(const SweepOptions& options);

// results.csv from the JSON lines (the columns depend only on the spec's methods, so a resumed sweep
// writes the same header).
std::string results_csv(const SweepSpec& spec, const std::vector<nlohmann::json>& rows);
// The same from the parameter columns (every parameter of the spec's methods' tables), which a shard's
// manifest records so that a merge writes the header the whole sweep would.
std::string results_csv(const std::set<std::string>& param_names, const std::vector<nlohmann::json>& rows);
std::set<std::string> csv_param_names(const SweepSpec& spec);

}  // namespace caustics
