#pragma once
// The program's one way of parsing a command line and reporting what went wrong (main.cpp; the sweep
// worker, which parses each run's `caustics render` line in-process): every error is one line on stderr,
//   caustics: error: <option or file>: <what is wrong>; valid: <what would be valid>
// with exit code 2 for bad input or usage and 1 for an internal failure.
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace caustics::cli {

// Writes the error line and returns `code`.
int report_error(const std::string& message, int code);

// A subcommand of the parser with the action its setup returned.
struct ParsedCommand {
    CLI::App* app = nullptr;
    std::function<int()> action;
};

// Parses argv with `app` (its subcommands added, one of them required) and runs the parsed subcommand's
// action; returns its exit status or the error's exit code (--help: CLI11's own, 0). Exceptions of the
// parse and of the action are reported here; none leaves.
int parse_and_run(CLI::App& app, const std::vector<ParsedCommand>& commands, int argc, const char* const* argv);

}  // namespace caustics::cli
