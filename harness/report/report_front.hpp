#pragma once
// `caustics report DIR`: checks the sweep folder and runs the plotting scripts (scripts/report/report.py)
// with an interpreter that has Debian's matplotlib, pandas and numpy (docs/design.md section 10). The script
// runs as a child that dies with this process (a killed report leaves nothing running), and writes
// report.md, every figure and every table under a temporary name renamed into place (no half file).
#include <string>

namespace caustics {

// Returns the script's exit status; throws InputError when DIR holds no sweep results.
int run_report(const std::string& dir);

// `caustics compare BASE NEW`: two sweep folders matched run by run (scripts/report/compare.py). Checks
// both folders and the options before anything runs (InputError); returns the script's exit status (0, or 3
// with fail_on_regression when a run is slower or worse).
struct CompareOptions {
    std::string base, new_dir, out;   // out: empty for NEW/compare
    double alpha = 0.01, time_threshold = 0.05, error_threshold = 0.01;
    bool fail_on_regression = false;
};
int run_compare(const CompareOptions& o);

// /usr/bin/python3 when it has the modules, else the first python3 on PATH that has them; empty if none.
std::string find_plotting_python();

}  // namespace caustics
