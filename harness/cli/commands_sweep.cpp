// caustics sweep SPEC [--out DIR] [--resume] [--axis METHOD.AXIS=VALUES]... [--yes] [--threads T] [--dry-run]
//                     [--shard I/N] [--references-only] [--isolate-runs] [--slurm N [--slurm-args "..."]]
// caustics sweep merge DIR | caustics sweep status DIR      (sharded sweeps: harness/sweep/shard.hpp)
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "command.hpp"
#include <caustics/sweep/slurm.hpp>
#include <caustics/sweep/sweep.hpp>
#include <caustics/util/errors.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

int run_sweep_command(SweepOptions o) {
    if (o.out_dir.empty()) o.out_dir = (fs::path("results") / "sweeps" / fs::path(o.spec_path).stem()).string();
    const SweepSummary s = run_sweep(o);
    if (o.references_only) {
        std::cout << "sweep: " << s.references << " of " << s.total << " references ready"
                  << (s.skipped ? " (" + std::to_string(s.skipped) + " scene frames have none: their runs say why)" : "")
                  << " in " << (fs::path(o.out_dir) / "references").string() << "\n";
        return 0;
    }
    std::cout << "sweep: " << s.total << " runs (" << s.done_before << " already done, " << s.ran << " run now: "
              << s.ok << " ok, " << s.skipped << " skipped, " << s.failed << " failed, " << s.unstable
              << " unstable)\n"
              << "wrote " << (fs::path(o.out_dir) / "results.csv").string() << "\n";
    if (s.loaded)
        std::cerr << "sweep: warning: the machine was busy as the sweep started (its CPUs at least half busy with other "
                     "work; manifest.json machine.start): its timings are not a quiet machine's\n";
    return 0;
}

// --dry-run: the plan (the spec with --axis applied), one run id a line and the count per method; nothing
// is run or written, so a spec can be checked (and "methods": "all" seen expanded) before a long sweep.
int list_planned_runs(const SweepOptions& o) {
    const std::vector<PlannedRun> runs = plan_runs(load_sweep_spec(o.spec_path, o.axis_overrides));
    std::map<std::string, std::size_t> per_method;
    for (const PlannedRun& run : runs) {
        std::cout << run.id << "\n";
        ++per_method[run.method];
    }
    std::cout << "sweep: " << runs.size() << " runs planned (";
    for (auto it = per_method.begin(); it != per_method.end(); ++it)
        std::cout << (it == per_method.begin() ? "" : ", ") << it->first << " " << it->second;
    std::cout << "); dry run: nothing run or written\n";
    return 0;
}

// --slurm N: the job scripts of a sharded sweep (slurm.hpp), submitted unless --dry-run.
int slurm_command(const SweepOptions& o, int tasks, const std::string& extra, bool dry_run) {
    const SweepSpec spec = load_sweep_spec(o.spec_path, o.axis_overrides);
    const std::vector<PlannedRun> runs = plan_runs(spec);
    std::set<std::string> pairs;
    for (const PlannedRun& r : runs) pairs.insert(reference_key(r));
    SlurmPlan plan;
    plan.program = fs::absolute(fs::read_symlink("/proc/self/exe")).string();
    plan.spec_path = fs::absolute(o.spec_path).string();
    plan.axis_overrides = o.axis_overrides;
    plan.out_dir = fs::absolute(o.out_dir.empty() ? (fs::path("results") / "sweeps" / fs::path(o.spec_path).stem())
                                                  : fs::path(o.out_dir)).string();
    plan.cache_dir = fs::absolute(o.cache_dir.empty() ? default_cache_dir() : o.cache_dir).string();
    plan.run_tasks = tasks;
    plan.reference_tasks = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(tasks), std::max<std::size_t>(1, pairs.size())));
    plan.cpus_per_task = o.threads > 0 ? o.threads : 1;
    plan.timeout_s = o.timeout_s;
    plan.isolate_runs = o.isolate_runs;
    plan.extra_args = extra;
    const SlurmScripts scripts = write_slurm_scripts(plan);
    std::cout << "sweep: " << runs.size() << " runs in " << tasks << " array tasks, " << pairs.size()
              << " references in " << plan.reference_tasks << "; wrote " << scripts.references << ", " << scripts.runs
              << ", " << scripts.merge << "\n";
    if (dry_run) {
        std::cout << "dry run: nothing submitted\n";
        return 0;
    }
    const std::vector<std::string> jobs = submit_slurm_scripts(plan, scripts);
    std::cout << "submitted: references " << jobs[0] << ", runs " << jobs[1] << " (afterok), merge + report " << jobs[2]
              << " (afterany); `caustics sweep status " << plan.out_dir << "` shows progress\n";
    return 0;
}

Command make_sweep_command() {
    Command c;
    c.name = "sweep";
    c.summary = "Run the Cartesian product of a sweep spec's axes; write results.csv, results.jsonl and per-run files";
    c.order = 40;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<SweepOptions>();
        auto dry_run = std::make_shared<bool>(false);
        auto shard = std::make_shared<std::string>();
        auto slurm = std::make_shared<int>(0);
        auto slurm_args = std::make_shared<std::string>();
        auto folder = std::make_shared<std::string>();
        // `sweep merge DIR` and `sweep status DIR` act on a sweep folder instead of a spec.
        CLI::App* merge = app.add_subcommand("merge", "Merge the shards of DIR/shards/ into DIR (results, manifest)");
        CLI::App* status = app.add_subcommand("status", "Show a sweep folder's progress per shard, from its files");
        for (CLI::App* sub : {merge, status})
            sub->add_option("dir", *folder, "The sweep's output folder")->required();
        app.require_subcommand(0, 1);
        add_input_file_argument(app, "spec", o->spec_path, "Sweep spec (JSON), e.g. scripts/sweeps/quick.json",
                                "a sweep spec (JSON), e.g. scripts/sweeps/quick.json");
        add_output_folder_option(app, "--out", o->out_dir, "Output folder (default results/sweeps/<spec name>)");
        app.add_flag("--resume", o->resume, "Continue a sweep in --out: skip finished runs, redo a cut-off one");
        app.add_option("--axis", o->axis_overrides, "Override an axis: METHOD.AXIS=VALUES, e.g. my_method.grid=[64,128]")
            ->expected(1)
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        app.add_flag("--yes", o->yes, "Run a sweep of more than 500 runs");
        add_threads_option(app, o->threads, "Worker threads per run (0: all cores)");
        add_cache_option(app, o->cache_dir);
        add_number_option(app, "--timeout", o->timeout_s, 0.0, 604800.0,
                          "Per-run time limit in seconds (default: the spec's timing.timeout_s)",
                          "0: the spec's timing.timeout_s, 604800 s: a week");
        app.add_flag("--dry-run", *dry_run,
                     "List the planned runs and their count per method; run and write nothing (with --slurm: "
                     "write the job scripts, submit nothing)");
        CLI::Option* shard_option =
            app.add_option("--shard", *shard, "Run shard I of N (I/N) into DIR/shards/I; `sweep merge DIR` joins them");
        app.add_flag("--references-only", o->references_only,
                     "Compute the references the sweep needs (shard I of N of them with --shard) and run nothing");
        app.add_flag("--isolate-runs", o->isolate_runs,
                     "Start a `caustics render` process per run instead of a worker process that keeps the scene "
                     "frame and reference loaded between runs (same results; slower)");
        app.add_option("--slurm", *slurm, "Write and submit Slurm job arrays: references, N run tasks, merge + report")
            ->check(CLI::Range(1, kMaxShards));
        app.add_option("--slurm-args", *slurm_args, "Extra sbatch arguments for every job, e.g. \"--partition=cpu\"");
        return [o, dry_run, shard, shard_option, slurm, slurm_args, folder, merge, status]() {
            if (merge->parsed()) {
                const MergeSummary m = merge_shards(*folder);
                std::cout << "sweep: merged " << m.shards << " shards, " << m.runs << " runs into "
                          << (fs::path(*folder) / "results.csv").string() << "\n";
                return 0;
            }
            if (status->parsed()) {
                std::cout << sweep_status(*folder);
                return 0;
            }
            if (o->spec_path.empty())
                throw InputError("sweep", "spec", "a sweep spec (JSON) is required, e.g. scripts/sweeps/quick.json; "
                                                  "or `sweep merge DIR` / `sweep status DIR`");
            // An empty --shard is refused rather than taken as no shard (it ran the whole sweep).
            if (shard_option->count() > 0) o->shard = parse_shard(*shard);
            if (*slurm > 0) return slurm_command(*o, *slurm, *slurm_args, *dry_run);
            return *dry_run ? list_planned_runs(*o) : run_sweep_command(*o);
        };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_sweep_command);
}  // namespace caustics::cli
