// How busy the machine is (see machine_state.hpp).
#include <caustics/run/machine_state.hpp>

#include <fstream>
#include <sstream>
#include <thread>

namespace caustics {

bool parse_loadavg(const std::string& text, double& load1, double& load5, double& load15) {
    std::istringstream in(text);
    in.imbue(std::locale::classic());
    return static_cast<bool>(in >> load1 >> load5 >> load15) && load1 >= 0.0 && load5 >= 0.0 && load15 >= 0.0;
}

MachineState read_machine_state() {
    MachineState s;
    s.cores = std::thread::hardware_concurrency();
    std::ifstream loadavg("/proc/loadavg");
    std::string line;
    double l1 = 0.0, l5 = 0.0, l15 = 0.0;
    if (std::getline(loadavg, line) && parse_loadavg(line, l1, l5, l15)) s.load1 = l1, s.load5 = l5, s.load15 = l15;
    std::ifstream governor("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor");
    if (std::getline(governor, line)) s.governor = line;
    return s;
}

bool machine_loaded(const MachineState& start) {
    return start.load1 && start.cores > 0 && *start.load1 >= 0.5 * start.cores;
}

nlohmann::json machine_state_json(const MachineState& s) {
    nlohmann::json j;
    j["load_average"] = s.load1 ? nlohmann::json::array({*s.load1, *s.load5, *s.load15}) : nlohmann::json(nullptr);
    j["governor"] = s.governor.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.governor);
    j["cores"] = s.cores;
    return j;
}

}  // namespace caustics
