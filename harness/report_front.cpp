#include "report_front.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>

#include "errors.hpp"

namespace caustics {
namespace fs = std::filesystem;

namespace {

std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

bool has_plotting_modules(const std::string& python) {
    const std::string probe = quoted(python) +
        " -c 'import matplotlib, pandas, numpy, OpenImageIO' >/dev/null 2>&1";
    return std::system(probe.c_str()) == 0;
}

}  // namespace

std::string find_plotting_python() {
    for (const char* candidate : {"/usr/bin/python3", "python3"})
        if (has_plotting_modules(candidate)) return candidate;
    return "";
}

int run_report(const std::string& dir) {
    if (!fs::is_regular_file(fs::path(dir) / "results.csv"))
        throw InputError(dir, "results.csv", "not a sweep folder (no results.csv); run `caustics sweep SPEC --out DIR` first");
    const std::string python = find_plotting_python();
    if (python.empty())
        throw InputError("report", "python3",
                         "no python3 with matplotlib, pandas, numpy and OpenImageIO; run scripts/setup.sh "
                         "(Debian packages python3-matplotlib python3-pandas python3-numpy python3-openimageio)");
    const fs::path script = fs::path(CAUSTICS_SOURCE_DIR) / "scripts" / "report" / "report.py";
    const std::string command = quoted(python) + " " + quoted(script.string()) + " " + quoted(dir);
    const int status = std::system(command.c_str());
    if (status == -1) return 1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace caustics
