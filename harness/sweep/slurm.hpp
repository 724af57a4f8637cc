#pragma once
// Slurm job arrays for a sharded sweep (shard.hpp): `caustics sweep SPEC --out DIR --slurm N`.
//
// DIR/slurm/references.sbatch  an array over the sweep's (scene, frame) pairs (at most N tasks), each
//                              `caustics sweep SPEC --out DIR --references-only --shard $TASK/R`;
// DIR/slurm/runs.sbatch        an array of N tasks, each `--shard $SLURM_ARRAY_TASK_ID/N --resume`, after
//                              the references (afterok: a run never computes or races on a reference);
// DIR/slurm/merge.sbatch       `caustics sweep merge DIR` then `caustics report DIR`, after every run task
//                              (afterany: a failed task is reported by the merge, not hidden).
// Each task asks for whole cores (--cpus-per-task, the sweep's --threads or 1 core's worth of them) and
// passes them to --threads; every path is absolute, on the shared file system every node sees (the
// output folder, the cache, the spec and the program). --slurm-args are added to every sbatch call.
#include <string>
#include <vector>

namespace caustics {

struct SlurmPlan {
    std::string program;          // absolute path of the caustics program
    std::string spec_path;        // absolute
    std::vector<std::string> axis_overrides;
    std::string out_dir;          // absolute
    std::string cache_dir;        // absolute
    int run_tasks = 1;            // N
    int reference_tasks = 1;      // min(N, reference pairs)
    int cpus_per_task = 1;
    double timeout_s = 0.0;       // per-run limit (0: the spec's)
    bool isolate_runs = false;    // --isolate-runs: a process per run instead of a worker (sweep.hpp)
    std::string extra_args;       // --slurm-args, split on spaces, added to every sbatch call
};

struct SlurmScripts {
    std::string references, runs, merge;   // paths of the written scripts
};

// Writes the three scripts (atomically) into plan.out_dir/slurm/.
SlurmScripts write_slurm_scripts(const SlurmPlan& plan);

// Submits them with sbatch --parsable in dependency order; returns the three job ids. Throws
// std::runtime_error with sbatch's message when a submission fails.
std::vector<std::string> submit_slurm_scripts(const SlurmPlan& plan, const SlurmScripts& scripts);

// A shell word: single-quoted where needed.
std::string shell_quote(const std::string& word);

}  // namespace caustics
