#pragma once
// CLI11's own usage errors (an unknown option, a missing argument or command, a missing value, a
// repeated option) in the program's one message style, built from the parser's state rather than from
// CLI11's wording:
//
//   caustics: error: <option or argument>: <what is wrong>; valid: <what would be valid>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace caustics::cli {

// The first argument nobody took (an unknown option or a stray value) as a message listing the valid
// options of its command; nullopt when there is none. Checked before any other error of a parse, so that
// a misspelt option is named rather than the option it failed to set.
std::optional<std::string> unknown_argument_message(const CLI::App& top);

// Any other parse error of `top`.
std::string usage_error_message(const CLI::App& top, const CLI::ParseError& error);

// A first argument that is not a command (nor an option).
std::string unknown_command_message(const CLI::App& top, const std::string& name);

}  // namespace caustics::cli
