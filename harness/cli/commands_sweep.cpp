// caustics sweep SPEC [--out DIR] [--resume] [--axis METHOD.AXIS=VALUES]... [--yes] [--threads T] [--dry-run]
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "command.hpp"
#include <caustics/sweep/sweep.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

int run_sweep_command(SweepOptions o) {
    if (o.out_dir.empty()) o.out_dir = (fs::path("results") / "sweeps" / fs::path(o.spec_path).stem()).string();
    const SweepSummary s = run_sweep(o);
    std::cout << "sweep: " << s.total << " runs (" << s.done_before << " already done, " << s.ran << " run now: "
              << s.ok << " ok, " << s.skipped << " skipped, " << s.failed << " failed, " << s.unstable
              << " unstable)\n"
              << "wrote " << (fs::path(o.out_dir) / "results.csv").string() << "\n";
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

Command make_sweep_command() {
    Command c;
    c.name = "sweep";
    c.summary = "Run the Cartesian product of a sweep spec's axes; write results.csv, results.jsonl and per-run files";
    c.order = 40;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<SweepOptions>();
        auto dry_run = std::make_shared<bool>(false);
        add_input_file_argument(app, "spec", o->spec_path, "Sweep spec (JSON), e.g. scripts/sweeps/quick.json",
                                "a sweep spec (JSON), e.g. scripts/sweeps/quick.json")
            ->required();
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
        app.add_flag("--dry-run", *dry_run, "List the planned runs and their count per method; run and write nothing");
        return [o, dry_run]() { return *dry_run ? list_planned_runs(*o) : run_sweep_command(*o); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_sweep_command);
}  // namespace caustics::cli
