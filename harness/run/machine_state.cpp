// How busy the machine is (see machine_state.hpp).
#include <caustics/run/machine_state.hpp>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

namespace caustics {

bool parse_loadavg(const std::string& text, double& load1, double& load5, double& load15) {
    std::istringstream in(text);
    in.imbue(std::locale::classic());
    return static_cast<bool>(in >> load1 >> load5 >> load15) && load1 >= 0.0 && load5 >= 0.0 && load15 >= 0.0;
}

bool parse_cpu_times(const std::string& line, std::uint64_t& total, std::uint64_t& idle) {
    std::istringstream in(line);
    std::string label;
    if (!(in >> label) || label != "cpu") return false;
    std::uint64_t v[8] = {};
    int n = 0;
    while (n < 8 && in >> v[n]) ++n;
    if (n < 4) return false;   // user nice system idle at least
    total = 0;
    for (int k = 0; k < n; ++k) total += v[k];
    idle = v[3] + (n > 4 ? v[4] : 0);   // idle + iowait
    return true;
}

namespace {

bool read_cpu_times(std::uint64_t& total, std::uint64_t& idle) {
    std::ifstream stat("/proc/stat");
    std::string line;
    return std::getline(stat, line) && parse_cpu_times(line, total, idle);
}

}  // namespace

MachineState read_machine_state(double sample_s) {
    MachineState s;
    s.cores = std::thread::hardware_concurrency();
    std::uint64_t t0 = 0, i0 = 0, t1 = 0, i1 = 0;
    if (sample_s > 0.0 && read_cpu_times(t0, i0)) {
        std::this_thread::sleep_for(std::chrono::duration<double>(sample_s));
        if (read_cpu_times(t1, i1) && t1 > t0 && i1 >= i0)
            s.busy = 1.0 - static_cast<double>(i1 - i0) / static_cast<double>(t1 - t0);
    }
    std::ifstream loadavg("/proc/loadavg");
    std::string line;
    double l1 = 0.0, l5 = 0.0, l15 = 0.0;
    if (std::getline(loadavg, line) && parse_loadavg(line, l1, l5, l15)) s.load1 = l1, s.load5 = l5, s.load15 = l15;
    std::ifstream governor("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor");
    if (std::getline(governor, line)) s.governor = line;
    return s;
}

bool machine_loaded(const MachineState& start) {
    if (start.busy) return *start.busy >= 0.5;
    return start.load1 && start.cores > 0 && *start.load1 >= 0.5 * start.cores;
}

nlohmann::json machine_state_json(const MachineState& s) {
    nlohmann::json j;
    j["busy"] = s.busy ? nlohmann::json(*s.busy) : nlohmann::json(nullptr);
    j["load_average"] = s.load1 ? nlohmann::json::array({*s.load1, *s.load5, *s.load15}) : nlohmann::json(nullptr);
    j["governor"] = s.governor.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.governor);
    j["cores"] = s.cores;
    return j;
}

}  // namespace caustics
