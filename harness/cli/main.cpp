// The `caustics` program (docs/design.md section 7). Subcommands register themselves (command.hpp).
// Exit codes: 0 success, 2 bad input or usage, 1 internal failure. Every error is one line on stderr,
//   caustics: error: <option or file>: <what is wrong>; valid: <what would be valid>
// (options.hpp checks option values; usage_errors.hpp words CLI11's own usage errors; InputError
// carries the rest; dispatch.hpp parses and reports).
//
// Before anything else the program loads the method plugins in CAUSTICS_PLUGIN_PATH (plugins.hpp) and
// refuses to start (exit 2) while two methods, built in or loaded, share a name. It fixes the heap's
// limits first (util/heap_policy.hpp), so that a run's timing does not depend on the process's history.
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.hpp"
#include "dispatch.hpp"
#include "plugins.hpp"
#include "usage_errors.hpp"
#include <caustics/api/registry.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/heap_policy.hpp>

int main(int argc, char** argv) {
    using caustics::cli::report_error;
    caustics::apply_heap_policy();
    try {
        if (const auto conflicts = caustics::registration_conflicts(); !conflicts.empty()) return report_error(conflicts.front(), 2);
        if (const char* plugins = std::getenv("CAUSTICS_PLUGIN_PATH")) caustics::cli::load_plugins(plugins);
        CLI::App app{"caustics: a benchmarking harness for real-time caustics methods against an Embree reference",
                     "caustics"};
        app.require_subcommand(1, 1);
        std::vector<caustics::cli::ParsedCommand> commands;
        bool known = argc < 2 || argv[1][0] == '-';
        for (const auto& command : caustics::cli::registered_commands()) {
            CLI::App* sub = app.add_subcommand(command.name, command.summary);
            commands.push_back({sub, command.setup(*sub)});
            known = known || command.name == argv[1];
        }
        if (!known) return report_error(caustics::cli::unknown_command_message(app, argv[1]), 2);
        return caustics::cli::parse_and_run(app, commands, argc, argv);
    } catch (const caustics::InputError& e) {   // loading the plugins, setting the commands up
        return report_error(e.what(), 2);
    } catch (const std::exception& e) {
        return report_error(std::string("internal failure: ") + e.what(), 1);
    } catch (...) {
        return report_error("internal failure: unknown exception", 1);
    }
}
