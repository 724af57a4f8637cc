#include <caustics/report/report_front.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <locale>
#include <set>
#include <sstream>
#include <vector>

#include <caustics/util/errors.hpp>
#include <caustics/util/resources.hpp>

namespace caustics {
namespace fs = std::filesystem;

namespace {

// Runs `argv` (argv[0] a path, or a name looked up on PATH) and waits for it; returns its exit code, or 1
// if it could not start or ended on a signal. The child dies with this process (PR_SET_PDEATHSIG, checked
// against the race of a parent that died before the prctl took effect), so a killed `caustics report`
// leaves no script running that would write the report later. `quiet` sends its output to /dev/null.
int run_tied_child(const std::vector<std::string>& argv, bool quiet) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) return 1;
    if (pid == 0) {
        if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0) _exit(127);
        if (getppid() != parent) _exit(127);   // the parent died before the prctl took effect
        if (quiet) {
            const int null_fd = open("/dev/null", O_WRONLY);
            if (null_fd >= 0) {
                dup2(null_fd, STDOUT_FILENO);
                dup2(null_fd, STDERR_FILENO);
                close(null_fd);
            }
        }
        execvp(args[0], args.data());
        _exit(127);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return 1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

// The results.csv a sweep writes: a header with the columns the report reads, and at least one run. Checked
// before the script starts, so that an empty, truncated or foreign file is refused with exit 2 and one
// message rather than a traceback.
void check_results_csv(const std::string& dir) {
    const fs::path path = fs::path(dir) / "results.csv";
    const std::string valid = "the results.csv a sweep writes: a header (run_id, scene, method, status, ...) and a row per run";
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string(), "", "cannot be read; valid: " + valid);
    std::string header;
    if (!std::getline(in, header) || header.empty()) throw InputError(path.string(), "", "is empty; valid: " + valid);
    std::set<std::string> columns;
    std::stringstream fields(header);
    for (std::string field; std::getline(fields, field, ',');) {
        if (!field.empty() && field.back() == '\r') field.pop_back();
        if (field.size() >= 2 && field.front() == '"' && field.back() == '"') field = field.substr(1, field.size() - 2);
        columns.insert(field);
    }
    std::string missing;
    for (const char* c : {"run_id", "scene", "method", "status", "time_ms_median", "nrmse", "radiometric"})
        if (!columns.count(c)) missing += (missing.empty() ? "" : ", ") + std::string(c);
    if (!missing.empty()) throw InputError(path.string(), "", "has no column " + missing + "; valid: " + valid);
    std::string row;
    bool any = false;
    while (std::getline(in, row))
        if (row.find_first_not_of(" \t\r") != std::string::npos) {
            any = true;
            break;
        }
    if (!any) throw InputError(path.string(), "", "holds a header and no run; valid: " + valid);
}

bool has_plotting_modules(const std::string& python) {
    return run_tied_child({python, "-c", "import matplotlib, pandas, numpy, OpenImageIO"}, true) == 0;
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
    check_results_csv(dir);
    const std::string python = find_plotting_python();
    if (python.empty())
        throw InputError("report", "python3",
                         "no python3 with matplotlib, pandas, numpy and OpenImageIO; run scripts/setup.sh "
                         "(Debian packages python3-matplotlib python3-pandas python3-numpy python3-openimageio)");
    const fs::path script = data_directory() / "scripts" / "report" / "report.py";
    if (!fs::is_regular_file(script))
        throw InputError(script.string(), "", "the report script is missing; valid: an installation or build tree "
                                              "with scripts/report/ in its data folder (or set CAUSTICS_DATA_DIR)");
    return run_tied_child({python, script.string(), dir}, false);
}

int run_compare(const CompareOptions& o) {
    for (const std::string& dir : {o.base, o.new_dir})
        if (!fs::is_regular_file(fs::path(dir) / "results.jsonl"))
            throw InputError(dir, "results.jsonl", "not a sweep folder; valid: a folder `caustics sweep` wrote (or merged)");
    const std::string python = find_plotting_python();
    if (python.empty())
        throw InputError("compare", "python3",
                         "no python3 with matplotlib, pandas, numpy and OpenImageIO; run scripts/setup.sh");
    const fs::path script = data_directory() / "scripts" / "report" / "compare.py";
    if (!fs::is_regular_file(script))
        throw InputError(script.string(), "", "the compare script is missing; valid: an installation or build tree "
                                              "with scripts/report/ in its data folder (or set CAUSTICS_DATA_DIR)");
    auto number = [](double v) {
        std::ostringstream s;
        s.imbue(std::locale::classic());
        s.precision(17);
        s << v;
        return s.str();
    };
    std::vector<std::string> argv = {python, script.string(), o.base, o.new_dir, "--alpha", number(o.alpha),
                                     "--time-threshold", number(o.time_threshold), "--error-threshold",
                                     number(o.error_threshold)};
    if (!o.out.empty()) argv.insert(argv.end(), {"--out", o.out});
    if (o.fail_on_regression) argv.push_back("--fail-on-regression");
    return run_tied_child(argv, false);
}

}  // namespace caustics
