#pragma once
// The bad-input catalog (issue 12): each case runs the `caustics` program on one malformed input, under a
// memory limit and a time limit, and checks that it is refused up front: exit code 2, one line
// "caustics: error: ..." naming the file or key, nothing written under --out and no cache entry.
// Catalog tests (tests/test_catalog_*.cpp) build cases with CatalogCase and run them with check_refused.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace caustics::test_support {

// The tests' small scene: a sine water patch (side `size` m, `cells` x `cells`) over a floor 0.4 m
// below, lit straight down, a `receiver` x `receiver` receiver and the given camera. Each test file
// writes its own copy, so that a regression that ignores --out writes into an obviously named folder
// rather than a shipped scene's.
inline nlohmann::json small_sine_scene(double size, int cells, const nlohmann::json& camera, int receiver = 16) {
    nlohmann::json s = nlohmann::json::parse(R"({
      "description": "catalog scene",
      "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0}],
      "objects": [
        {"name": "water", "shape": "heightfield", "center": [0, 0], "base_height": 0.0,
         "material": {"type": "dielectric", "ior": 1.33},
         "generator": {"type": "sine", "amplitude": 0.01, "wavelength": 0.25, "direction": [1, 0],
                       "phase": 0, "speed": 0}},
        {"name": "floor", "shape": "plane", "center": [0, 0, -0.4], "u": [1, 0, 0], "v": [0, 1, 0],
         "material": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}
      ],
      "receiver": {"object": "floor", "resolution": [16, 16]},
      "animation": {"frames": 1, "fps": 30}
    })");
    s["camera"] = camera;
    s["objects"][0]["size"] = {size, size};
    s["objects"][0]["resolution"] = {cells, cells};
    s["receiver"]["resolution"] = {receiver, receiver};
    return s;
}

// One run of caustic_triangles on sine with a tiny reference and one timed repeat: the smallest valid sweep.
inline nlohmann::json small_sweep_spec() {
    return nlohmann::json::parse(R"({
      "description": "catalog base sweep",
      "scenes": ["sine"],
      "frames": [0],
      "reference": {"photons": 20000, "noise_target": 0.5},
      "truth": "auto",
      "timing": {"warmup": 0, "repeats": 1, "max_time_s": 0.1},
      "methods": {"caustic_triangles": {"grid": [16]}}
    })");
}

// A folder of its own for one case, removed when the case ends (also when it fails: the catalog's
// messages say what went wrong; nothing is left in /tmp).
class CaseDir {
public:
    explicit CaseDir(const std::string& name)
        : path_(std::filesystem::temp_directory_path() /
                ("caustics_catalog_" + sanitize(name) + "_" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~CaseDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    CaseDir(const CaseDir&) = delete;
    CaseDir& operator=(const CaseDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(path_ / name, std::ios::binary) << text;
        return file(name);
    }
    std::string write_json(const std::string& name, const nlohmann::json& j) const { return write(name, j.dump(2)); }
    std::string out() const { return file("out"); }
    std::string cache() const { return file("cache"); }

private:
    static std::string sanitize(std::string s) {
        for (char& c : s)
            if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
        return s;
    }
    std::filesystem::path path_;
};

struct RefusalLimits {
    int seconds = 60;               // wall-clock limit (timeout(1)); a hang fails the case
    long memory_kb = 4L << 20;      // address-space limit (ulimit -v): 4 GiB
};

// Runs `args` with the limits; returns the result and the elapsed seconds.
inline ProgramResult run_limited(const std::vector<std::string>& args, const std::filesystem::path& scratch,
                                 const RefusalLimits& limits, double& seconds) {
    // AddressSanitizer reserves terabytes of shadow address space, so under the asan preset the
    // address-space limit cannot apply; the time limit and the program's own memory ceiling still do.
#if defined(__SANITIZE_ADDRESS__)
    const std::string memory_limit;
#else
    const std::string memory_limit = "ulimit -v " + std::to_string(limits.memory_kb) + "; ";
#endif
    std::vector<std::string> wrapped = {"-c",
                                        memory_limit + "exec timeout -s KILL " + std::to_string(limits.seconds) +
                                            " \"$@\"",
                                        "sh", CAUSTICS_BINARY};
    wrapped.insert(wrapped.end(), args.begin(), args.end());
    const auto start = std::chrono::steady_clock::now();
    ProgramResult r = run_program("/bin/sh", wrapped, scratch);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

// Exit 2, one "caustics: error:" line that mentions every string of `expect`, no file under `out`,
// no entry under `cache`, within the limits.
inline void check_refused(const CaseDir& dir, const std::vector<std::string>& args,
                          const std::vector<std::string>& expect, const RefusalLimits& limits = {}) {
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    SCOPED_TRACE("caustics " + joined);
    double seconds = 0.0;
    const ProgramResult r = run_limited(args, dir.path(), limits, seconds);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("caustics: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    for (const auto& e : expect) EXPECT_NE(r.err.find(e), std::string::npos) << "message does not name '" << e << "': " << r.err;
    EXPECT_LT(seconds, limits.seconds) << "took " << seconds << " s";
    std::error_code ec;
    if (std::filesystem::exists(dir.out(), ec)) {
        EXPECT_TRUE(std::filesystem::is_empty(dir.out(), ec)) << "files written under --out";
    }
    if (std::filesystem::exists(dir.cache(), ec)) {
        for (const auto& entry : std::filesystem::recursive_directory_iterator(dir.cache(), ec)) {
            EXPECT_NE(entry.path().extension(), ".ref") << "cache entry written: " << entry.path();
        }
    }
}

}  // namespace caustics::test_support
