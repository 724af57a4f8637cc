// caustics compare BASE NEW: two sweeps matched run by run, time and error changes with their significance
// (scripts/report/compare.py; docs/cli.md).
#include <memory>

#include "command.hpp"
#include "options.hpp"
#include <caustics/report/report_front.hpp>

namespace caustics::cli {
namespace {

Command make_compare_command() {
    Command c;
    c.name = "compare";
    c.summary = "Compare two sweep folders run by run: time (Mann-Whitney U on the timed frames) and error changes";
    c.order = 55;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto o = std::make_shared<CompareOptions>();
        app.add_option("base", o->base, "The base sweep folder (results.jsonl)")->required();
        app.add_option("new", o->new_dir, "The new sweep folder")->required();
        add_output_folder_option(app, "--out", o->out, "Output folder (default NEW/compare): compare.md, compare.csv, a figure");
        add_number_option(app, "--alpha", o->alpha, 1e-9, 0.5, "Significance level of the time test (default 0.01)");
        add_number_option(app, "--time-threshold", o->time_threshold, 0.0, 10.0,
                          "Smallest time change reported, as a fraction (default 0.05)");
        add_number_option(app, "--error-threshold", o->error_threshold, 0.0, 10.0,
                          "Smallest error change reported, as a fraction of the base's error (default 0.01)");
        app.add_flag("--fail-on-regression", o->fail_on_regression, "Exit with status 3 when a run is slower or worse");
        return [o]() { return run_compare(*o); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_compare_command);
}  // namespace caustics::cli
