#include "command.hpp"

#include <algorithm>

#include "params.hpp"

namespace caustics::cli {
namespace {

// Function-local static: registrars run during static initialisation in an unspecified order.
std::vector<Command>& table() {
    static std::vector<Command> commands;
    return commands;
}

}  // namespace

CommandRegistrar::CommandRegistrar(Command (*make)()) { table().push_back(make()); }

std::vector<Command> registered_commands() {
    std::vector<Command> out = table();
    std::sort(out.begin(), out.end(), [](const Command& a, const Command& b) {
        return a.order != b.order ? a.order < b.order : a.name < b.name;
    });
    return out;
}

std::map<std::string, std::string> parse_assignments(const std::vector<std::string>& sets, const std::string& option) {
    std::map<std::string, std::string> out;
    for (const std::string& text : sets) {
        auto [key, value] = parse_assignment(text, option);
        out[key] = value;
    }
    return out;
}

}  // namespace caustics::cli
