#include <caustics/run/run_context.hpp>
#include <caustics/util/build_info.hpp>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fftw3.h>
#include <tbb/global_control.h>
#include <tbb/version.h>

namespace caustics {
namespace {

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            auto colon = line.find(':');
            if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
        }
    }
    return "unknown";
}

std::string git_commit() {
    const std::string command = std::string("git -C '") + CAUSTICS_SOURCE_DIR +
                                "' rev-parse --short=12 HEAD 2>/dev/null";
    std::array<char, 128> buffer{};
    std::string out;
    if (FILE* pipe = popen(command.c_str(), "r")) {
        while (fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
        pclose(pipe);
    }
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    return out.empty() ? "unknown" : out;
}

std::string host_name() {
    std::array<char, 256> name{};
    return gethostname(name.data(), name.size()) == 0 ? std::string(name.data()) : "unknown";
}

}  // namespace

nlohmann::json run_context() {
    nlohmann::json c;
    c["host"] = {{"name", host_name()},
                 {"cpu", cpu_model()},
                 {"cores", std::thread::hardware_concurrency()}};
    c["threads"] = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    c["build_type"] = build_type();
    c["compiler"] = std::string("g++ ") + __VERSION__;
    c["project_version"] = project_version();
    c["git_commit"] = git_commit();
    c["libraries"] = {{"embree", RTC_VERSION_STRING},
                      {"openimageio", OIIO_VERSION_STRING},
                      {"tbb", TBB_VERSION_STRING},
                      {"fftw", std::string(fftw_version)}};
    return c;
}

}  // namespace caustics
