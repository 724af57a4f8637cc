#pragma once
// Error kinds that map onto the command line's exit codes (DESIGN.md section 7):
// InputError -> exit 2 (bad input: the message names the file, the key and what would be valid),
// anything else -> exit 1 (internal failure).
#include <stdexcept>
#include <string>

namespace caustics {

class InputError : public std::runtime_error {
public:
    // file: the file (or command-line option) at fault; key: the JSON key path or parameter name;
    // problem: what is wrong and what would be valid.
    InputError(std::string file, std::string key, const std::string& problem)
        : std::runtime_error(format(file, key, problem)), file_(std::move(file)), key_(std::move(key)) {}

    const std::string& file() const { return file_; }
    const std::string& key() const { return key_; }

private:
    static std::string format(const std::string& file, const std::string& key, const std::string& problem) {
        std::string msg = file.empty() ? std::string() : file + ": ";
        if (!key.empty()) msg += "'" + key + "': ";
        return msg + problem;
    }
    std::string file_;
    std::string key_;
};

// A bad value of a command-line option or argument, in the program's one message style:
// "<what>: <problem>; valid: <what would be valid>" (what: the option, or the file at fault).
inline InputError invalid_value(const std::string& what, const std::string& problem, const std::string& valid) {
    return InputError(what, "", problem + "; valid: " + valid);
}

}  // namespace caustics
