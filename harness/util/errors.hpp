#pragma once
// Error kinds that map onto the command line's exit codes (docs/design.md section 7):
// InputError -> exit 2 (bad input: the message names the file, the key and what would be valid),
// anything else -> exit 1 (internal failure).
#include <algorithm>
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
    // A key path is built from the input's own keys, which may be arbitrarily long (a 5000-character key 200
    // levels down): the message shows its start and end, so that the top-level key and the innermost key stay
    // recognisable, and how long it was. (Inline, for plugins that link no harness code.)
    static std::string format(const std::string& file, const std::string& key, const std::string& problem) {
        constexpr std::size_t kHead = 120, kTail = 100;
        std::string msg;
        msg.reserve(file.size() + std::min(key.size(), kHead + kTail + 40) + problem.size() + 8);
        if (!file.empty()) msg.append(file).append(": ");
        if (!key.empty()) {
            msg.push_back('\'');
            if (key.size() <= kHead + kTail) {
                msg.append(key);
            } else {
                msg.append(key, 0, kHead).append("...(").append(std::to_string(key.size())).append(" characters)...");
                msg.append(key, key.size() - kTail, kTail);
            }
            msg.append("': ");
        }
        msg.append(problem);
        // Any message stays short enough to read whatever the input quoted into it (a megabyte scene name, a
        // long object name in a list of valid ones): an overlong one keeps its start (file, key) and its end
        // (what would be valid) and says how long it was.
        constexpr std::size_t kMessageHead = 1300, kMessageTail = 600;
        if (msg.size() <= kMessageHead + kMessageTail) return msg;
        return msg.substr(0, kMessageHead) + "...(" + std::to_string(msg.size()) + " characters)..." +
               msg.substr(msg.size() - kMessageTail);
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
