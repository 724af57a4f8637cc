#pragma once
// Small helpers shared by the tests that drive the `caustics` program through a shell.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace caustics::test_support {

// A temporary folder (name + process id) removed when it goes out of scope, also when the test fails
// or returns early on a failed ASSERT.
class ScopedTempDir {
public:
    explicit ScopedTempDir(const std::string& name)
        : path_(std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path_);
    }
    ~ScopedTempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    ScopedTempDir(const ScopedTempDir&) = delete;
    ScopedTempDir& operator=(const ScopedTempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// The whole file as bytes ("" if it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Single-quoted for /bin/sh, embedded quotes escaped.
inline std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// What one run of a program returned: exit code (-1 if it did not exit normally) and its output.
struct ProgramResult {
    int code = -1;
    std::string out, err;
};

// Runs `program` with `args` through /bin/sh; stdout and stderr go through files in `scratch_dir`.
inline ProgramResult run_program(const std::string& program, const std::vector<std::string>& args,
                                 const std::filesystem::path& scratch_dir) {
    std::string cmd = quote(program);
    for (const auto& a : args) cmd.append(" ").append(quote(a));
    const std::filesystem::path out = scratch_dir / "stdout.txt", err = scratch_dir / "stderr.txt";
    cmd.append(" >").append(quote(out.string())).append(" 2>").append(quote(err.string()));
    const int status = std::system(cmd.c_str());
    ProgramResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

}  // namespace caustics::test_support
