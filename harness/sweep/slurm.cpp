#include <caustics/sweep/slurm.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <caustics/util/image_io.hpp>

namespace caustics {
namespace fs = std::filesystem;

namespace {

// The command line every task shares: program, sweep, spec, --out, --cache, --axis..., --yes, and
// --timeout and --isolate-runs where given.
std::string sweep_words(const SlurmPlan& p) {
    std::string s = shell_quote(p.program) + " sweep " + shell_quote(p.spec_path) + " --out " + shell_quote(p.out_dir) +
                    " --cache " + shell_quote(p.cache_dir) + " --yes --threads \"${SLURM_CPUS_PER_TASK:-" +
                    std::to_string(p.cpus_per_task) + "}\"";
    for (const std::string& a : p.axis_overrides) s += " --axis " + shell_quote(a);
    if (p.timeout_s > 0.0) {
        char t[40];
        std::snprintf(t, sizeof t, "%.17g", p.timeout_s);
        s += " --timeout " + std::string(t);
    }
    if (p.isolate_runs) s += " --isolate-runs";
    return s;
}

std::string header(const SlurmPlan& p, const std::string& name, const std::string& array) {
    std::ostringstream s;
    s << "#!/bin/bash\n"
      << "#SBATCH --job-name=caustics-" << name << "\n"
      << "#SBATCH --cpus-per-task=" << p.cpus_per_task << "\n"
      << "#SBATCH --output=" << (fs::path(p.out_dir) / "slurm" / (name + "-%A_%a.log")).string() << "\n";
    if (!array.empty()) s << "#SBATCH --array=" << array << "\n";
    s << "set -euo pipefail\n"
      << "# Written by `caustics sweep --slurm`: every path is on the shared file system.\n"
      << "export CAUSTICS_CACHE_DIR=" << shell_quote(p.cache_dir) << "\n";
    return s.str();
}

std::string run_command(const std::string& command) {
    std::array<char, 512> buffer{};
    std::string out;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) throw std::runtime_error("cannot run: " + command);
    while (fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
    const int status = pclose(pipe);
    while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
    if (status != 0) throw std::runtime_error("`" + command + "` failed: " + out);
    return out;
}

}  // namespace

std::string shell_quote(const std::string& word) {
    if (!word.empty() && word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+@%") ==
                             std::string::npos)
        return word;
    std::string q = "'";
    for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

SlurmScripts write_slurm_scripts(const SlurmPlan& p) {
    const fs::path dir = fs::path(p.out_dir) / "slurm";
    SlurmScripts s{(dir / "references.sbatch").string(), (dir / "runs.sbatch").string(), (dir / "merge.sbatch").string()};
    const std::string words = sweep_words(p);
    write_text_atomic(s.references, header(p, "references", "0-" + std::to_string(p.reference_tasks - 1)) + words +
                                        " --references-only --shard \"${SLURM_ARRAY_TASK_ID}/" +
                                        std::to_string(p.reference_tasks) + "\"\n");
    write_text_atomic(s.runs, header(p, "runs", "0-" + std::to_string(p.run_tasks - 1)) + words +
                                  " --resume --shard \"${SLURM_ARRAY_TASK_ID}/" + std::to_string(p.run_tasks) + "\"\n");
    write_text_atomic(s.merge, header(p, "merge", "") + shell_quote(p.program) + " sweep merge " + shell_quote(p.out_dir) +
                                   "\n" + shell_quote(p.program) + " report " + shell_quote(p.out_dir) + "\n");
    for (const std::string& f : {s.references, s.runs, s.merge})
        fs::permissions(f, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
    return s;
}

std::vector<std::string> submit_slurm_scripts(const SlurmPlan& p, const SlurmScripts& s) {
    const std::string sbatch = "sbatch --parsable " + (p.extra_args.empty() ? std::string() : p.extra_args + " ");
    auto job_id = [](const std::string& parsable) { return parsable.substr(0, parsable.find(';')); };
    const std::string references = job_id(run_command(sbatch + shell_quote(s.references)));
    const std::string runs = job_id(run_command(sbatch + "--dependency=afterok:" + references + " " + shell_quote(s.runs)));
    const std::string merge = job_id(run_command(sbatch + "--dependency=afterany:" + runs + " " + shell_quote(s.merge)));
    return {references, runs, merge};
}

}  // namespace caustics
