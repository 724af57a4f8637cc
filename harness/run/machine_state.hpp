#pragma once
// How busy the machine is when a sweep starts and ends (issue: timings are only comparable on a quiet
// machine): the load averages of /proc/loadavg and the CPU frequency governor, where the system shows
// them. A sweep records one at its start and one at its end in manifest.json ("machine"), and flags
// itself `loaded` when other work was running as it started.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace caustics {

struct MachineState {
    std::optional<double> load1, load5, load15;   // runnable processes averaged over 1, 5, 15 minutes
    std::string governor;                          // cpu0's scaling governor ("" where not readable)
    unsigned cores = 0;
};

// Read now (fields stay empty where /proc or /sys do not show them).
MachineState read_machine_state();

// Parses the first three fields of /proc/loadavg's text; false where they are not three numbers.
bool parse_loadavg(const std::string& text, double& load1, double& load5, double& load15);

// A sweep is flagged loaded when, as it starts, the 1-minute load average is at least half the cores:
// other work held half the machine before any run began, and its timings are not those of a quiet one.
bool machine_loaded(const MachineState& start);

// {"load_average": [1, 5, 15] or null, "governor": name or null, "cores": n}.
nlohmann::json machine_state_json(const MachineState& s);

}  // namespace caustics
