#include "dispatch.hpp"

#include <exception>
#include <iostream>

#include "usage_errors.hpp"
#include <caustics/util/errors.hpp>

namespace caustics::cli {

int report_error(const std::string& message, int code) {
    std::cerr << "caustics: error: " << message << "\n";
    return code;
}

int parse_and_run(CLI::App& app, const std::vector<ParsedCommand>& commands, int argc, const char* const* argv) {
    try {
        try {
            app.parse(argc, argv);
        } catch (const CLI::Success& e) {
            return app.exit(e);   // --help, --help-all (CallForHelp derives from Success)
        } catch (const CLI::ParseError& e) {
            // An unknown option is named first: it is usually why something else looks missing.
            if (auto unknown = unknown_argument_message(app)) return report_error(*unknown, 2);
            return report_error(usage_error_message(app, e), 2);
        } catch (const InputError&) {   // a value refused by its option's check (options.hpp)
            if (auto unknown = unknown_argument_message(app)) return report_error(*unknown, 2);
            throw;
        }
        for (const ParsedCommand& command : commands)
            if (command.app->parsed()) return command.action();
        return report_error(usage_error_message(app, CLI::RequiredError::Subcommand(1)), 2);
    } catch (const InputError& e) {
        return report_error(e.what(), 2);
    } catch (const std::exception& e) {
        return report_error(std::string("internal failure: ") + e.what(), 1);
    } catch (...) {
        return report_error("internal failure: unknown exception", 1);
    }
}

}  // namespace caustics::cli
