#include <caustics/run/run_context.hpp>
#include <caustics/util/build_info.hpp>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <thread>

#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <fftw3.h>
#include <tbb/global_control.h>
#include <tbb/version.h>

#include <caustics/util/resources.hpp>

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

std::string trimmed_output(const std::string& command) {
    std::array<char, 128> buffer{};
    std::string out;
    if (FILE* pipe = popen(command.c_str(), "r")) {
        while (fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
        pclose(pipe);
    }
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    return out;
}

// The commit the program was built from, and how that is known: a build tree asks its source tree's git
// (build.json names the source folder), an installation records the commit of its last build.
std::pair<std::string, std::string> git_commit() {
    const nlohmann::json build = build_description();
    if (build.contains("source_dir") && build["source_dir"].is_string()) {
        std::string dir = build["source_dir"].get<std::string>();
        std::string quoted = "'";
        for (char c : dir) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
        const std::string out = trimmed_output("git -C " + quoted + "' rev-parse --short=12 HEAD 2>/dev/null");
        return {out.empty() ? "unknown" : out, "source tree"};
    }
    if (build.contains("git_commit") && build["git_commit"].is_string() && !build["git_commit"].get<std::string>().empty())
        return {build["git_commit"].get<std::string>(), "build time"};
    return {"unknown", "unknown"};
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
    const auto [commit, known_from] = git_commit();
    c["git_commit"] = commit;
    c["git_commit_from"] = known_from;
    c["libraries"] = {{"embree", RTC_VERSION_STRING},
                      {"openimageio", OIIO_VERSION_STRING},
                      {"tbb", TBB_VERSION_STRING},
                      {"fftw", std::string(fftw_version)}};
    return c;
}

}  // namespace caustics
