// The `caustics` program (DESIGN.md section 7). Subcommands register themselves (command.hpp).
// Exit codes: 0 success, 2 bad input or usage, 1 internal failure. Every error is one line on stderr,
//   caustics: error: <option or file>: <what is wrong>; valid: <what would be valid>
// (options.hpp checks option values; usage_errors.hpp words CLI11's own usage errors; InputError
// carries the rest).
//
// Before anything else the program loads the method plugins in CAUSTICS_PLUGIN_PATH (plugins.hpp) and
// refuses to start (exit 2) while two methods, built in or loaded, share a name.
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.hpp"
#include "plugins.hpp"
#include "usage_errors.hpp"
#include <caustics/api/registry.hpp>
#include <caustics/util/errors.hpp>

namespace {

int report(const std::string& message, int code) {
    std::cerr << "caustics: error: " << message << "\n";
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (const auto conflicts = caustics::registration_conflicts(); !conflicts.empty()) return report(conflicts.front(), 2);
        if (const char* plugins = std::getenv("CAUSTICS_PLUGIN_PATH")) caustics::cli::load_plugins(plugins);
        CLI::App app{"caustics: a benchmarking harness for real-time caustics methods against an Embree reference",
                     "caustics"};
        app.require_subcommand(1, 1);
        struct Entry {
            CLI::App* app;
            std::function<int()> action;
        };
        std::vector<Entry> entries;
        bool known = argc < 2 || argv[1][0] == '-';
        for (const auto& command : caustics::cli::registered_commands()) {
            CLI::App* sub = app.add_subcommand(command.name, command.summary);
            entries.push_back({sub, command.setup(*sub)});
            known = known || command.name == argv[1];
        }
        if (!known) return report(caustics::cli::unknown_command_message(app, argv[1]), 2);
        try {
            app.parse(argc, argv);
        } catch (const CLI::Success& e) {
            return app.exit(e);   // --help, --help-all (CallForHelp derives from Success)
        } catch (const CLI::ParseError& e) {
            // An unknown option is named first: it is usually why something else looks missing.
            if (auto unknown = caustics::cli::unknown_argument_message(app)) return report(*unknown, 2);
            return report(caustics::cli::usage_error_message(app, e), 2);
        } catch (const caustics::InputError& e) {   // a value refused by its option's check (options.hpp)
            if (auto unknown = caustics::cli::unknown_argument_message(app)) return report(*unknown, 2);
            throw;
        }
        for (const Entry& entry : entries)
            if (entry.app->parsed()) return entry.action();
        return report(caustics::cli::usage_error_message(app, CLI::RequiredError::Subcommand(1)), 2);
    } catch (const caustics::InputError& e) {
        return report(e.what(), 2);
    } catch (const std::exception& e) {
        return report(std::string("internal failure: ") + e.what(), 1);
    } catch (...) {
        return report("internal failure: unknown exception", 1);
    }
}
