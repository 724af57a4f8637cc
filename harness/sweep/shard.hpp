#pragma once
// Sharded sweeps (cluster runs, e.g. one Slurm array task per shard).
//
// `caustics sweep SPEC --out DIR --shard I/N` runs shard I of N into DIR/shards/I/ (the files of a whole
// sweep, resumable on its own); `caustics sweep SPEC --out DIR --references-only [--shard I/N]` computes
// the references the sweep needs (shard I of N of its (scene, frame) pairs) into the cache and
// DIR/references/ first, so that run tasks only read them; `caustics sweep merge DIR` joins the shards
// into DIR/results.jsonl, results.csv and manifest.json, which `caustics report DIR` reads like a whole
// sweep's.
//
// The assignment balances expected cost, not position: runs are taken in decreasing estimated cost
// (grid^2 x iterations, the axes every method maps to its work; a method without them counts 1) and
// each goes to the shard with the least cost so far (ties: the lower shard), so a method whose large
// grids come last in the plan is spread over every shard. It depends only on the plan, so every task
// computes the same one.
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/sweep/sweep_spec.hpp>

namespace caustics {

struct ShardId {
    int index = -1;   // -1: not sharded
    int count = 0;
    bool active() const { return index >= 0; }
};

// Parses "I/N" (0 <= I < N <= kMaxShards); throws InputError naming `option` otherwise.
ShardId parse_shard(const std::string& text, const std::string& option = "--shard");
constexpr int kMaxShards = 10000;

// The estimated cost of a run (see the file comment).
double estimated_run_cost(const PlannedRun& run);

// For each shard, the positions (in `runs`) of its runs, ascending.
std::vector<std::vector<std::size_t>> assign_shards(const std::vector<PlannedRun>& runs, int count);

struct MergeSummary {
    int shards = 0;
    std::size_t runs = 0;
};

// Merges DIR/shards/* into DIR (see the file comment). Throws InputError (exit 2) naming the shard
// folder and what is wrong, before writing anything: no shards, a shard missing from 0..N-1, shards of
// different plans or shard counts, a shard whose results lack some of its runs. Running it twice gives
// the same files.
MergeSummary merge_shards(const std::string& dir);

// The Slurm job and node of this process (SLURM_JOB_ID, SLURM_ARRAY_JOB_ID, SLURM_ARRAY_TASK_ID,
// SLURMD_NODENAME, SLURM_CPUS_PER_TASK), or null outside Slurm: what a shard's manifest records.
nlohmann::json slurm_environment();

// Per-shard progress from the files alone (no scheduler): one line per shard and a total.
std::string sweep_status(const std::string& dir);

}  // namespace caustics
