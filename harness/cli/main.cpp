// The `caustics` program (DESIGN.md section 7). Subcommands register themselves (command.hpp).
// Exit codes: 0 success, 2 bad input or usage (one line "caustics: error: <message>" on stderr),
// 1 internal failure.
#include <exception>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.hpp"
#include "errors.hpp"

namespace {

int report(const std::string& message, int code) {
    std::cerr << "caustics: error: " << message << "\n";
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        CLI::App app{"caustics: a benchmarking harness for real-time caustics methods against an Embree reference",
                     "caustics"};
        app.require_subcommand(1, 1);
        struct Entry {
            CLI::App* app;
            std::function<int()> action;
        };
        std::vector<Entry> entries;
        std::string names;
        bool known = argc < 2 || argv[1][0] == '-';
        for (const auto& command : caustics::cli::registered_commands()) {
            CLI::App* sub = app.add_subcommand(command.name, command.summary);
            entries.push_back({sub, command.setup(*sub)});
            names += (names.empty() ? "" : ", ") + command.name;
            known = known || command.name == argv[1];
        }
        if (!known) return report(std::string("unknown command '") + argv[1] + "'; valid commands: " + names, 2);
        try {
            app.parse(argc, argv);
        } catch (const CLI::Success& e) {
            return app.exit(e);   // --help, --help-all (CallForHelp derives from Success)
        } catch (const CLI::ParseError& e) {
            return report(e.what(), 2);
        }
        for (const Entry& entry : entries)
            if (entry.app->parsed()) return entry.action();
        return report("no subcommand given; run caustics --help", 2);
    } catch (const caustics::InputError& e) {
        return report(e.what(), 2);
    } catch (const std::exception& e) {
        return report(std::string("internal failure: ") + e.what(), 1);
    } catch (...) {
        return report("internal failure: unknown exception", 1);
    }
}
