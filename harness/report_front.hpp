#pragma once
// `caustics report DIR`: checks the sweep folder and runs the plotting scripts (scripts/report/report.py)
// with an interpreter that has Debian's matplotlib, pandas and numpy (DESIGN.md section 10).
#include <string>

namespace caustics {

// Returns the script's exit status; throws InputError when DIR holds no sweep results.
int run_report(const std::string& dir);

// /usr/bin/python3 when it has the modules, else the first python3 on PATH that has them; empty if none.
std::string find_plotting_python();

}  // namespace caustics
