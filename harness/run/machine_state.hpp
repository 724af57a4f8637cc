#pragma once
// How busy the machine is when a sweep starts and ends (timings are only comparable on a quiet machine):
// the share of CPU time other work takes, sampled over a quarter second from /proc/stat while the sweep
// itself waits, with the load averages of /proc/loadavg and the CPU frequency governor, where the system
// shows them. A sweep records one at its start and one at its end in manifest.json ("machine"), and flags
// itself `loaded` when the CPUs were at least half busy as it started. (The load averages trail by minutes:
// a sweep started right after another, or after a build, would read as loaded by them.)
#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace caustics {

struct MachineState {
    std::optional<double> busy;                    // fraction of all CPUs' time busy over the sample
    std::optional<double> load1, load5, load15;   // runnable processes averaged over 1, 5, 15 minutes
    std::string governor;                          // cpu0's scaling governor ("" where not readable)
    unsigned cores = 0;
};

// Read now, sampling the busy fraction over `sample_s` seconds (fields stay empty where /proc or /sys do
// not show them).
MachineState read_machine_state(double sample_s = 0.25);

// Parses the first three fields of /proc/loadavg's text; false where they are not three numbers.
bool parse_loadavg(const std::string& text, double& load1, double& load5, double& load15);

// Parses /proc/stat's aggregate "cpu ..." line into total and idle (idle + iowait) jiffies.
bool parse_cpu_times(const std::string& line, std::uint64_t& total, std::uint64_t& idle);

// Loaded: the CPUs were at least half busy as the sweep started (without a busy sample: the 1-minute load
// average at least half the cores).
bool machine_loaded(const MachineState& start);

// {"busy": fraction or null, "load_average": [1, 5, 15] or null, "governor": name or null, "cores": n}.
nlohmann::json machine_state_json(const MachineState& s);

}  // namespace caustics
