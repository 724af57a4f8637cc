#pragma once
// `caustics report DIR`: checks the sweep folder and runs the plotting scripts (scripts/report/report.py)
// with an interpreter that has Debian's matplotlib, pandas and numpy (docs/design.md section 10). The script
// runs as a child that dies with this process (a killed report leaves nothing running), and writes
// report.md, every figure and every table under a temporary name renamed into place (no half file).
#include <string>

namespace caustics {

// Returns the script's exit status; throws InputError when DIR holds no sweep results.
int run_report(const std::string& dir);

// /usr/bin/python3 when it has the modules, else the first python3 on PATH that has them; empty if none.
std::string find_plotting_python();

}  // namespace caustics
