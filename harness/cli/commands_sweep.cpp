// caustics sweep SPEC [--out DIR] [--resume] [--axis METHOD.AXIS=VALUES]... [--yes] [--threads T]
#include <filesystem>
#include <iostream>
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

Command make_sweep_command() {
    Command c;
    c.name = "sweep";
    c.summary = "Run the Cartesian product of a sweep spec's axes; write results.csv, results.jsonl and per-run files";
    c.order = 40;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<SweepOptions>();
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
        return [o]() { return run_sweep_command(*o); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_sweep_command);
}  // namespace caustics::cli
