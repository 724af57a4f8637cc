#include "usage_errors.hpp"

#include <cctype>
#include <vector>

#include "options.hpp"

namespace caustics::cli {
namespace {

std::string join(const std::vector<std::string>& items) {
    std::string s;
    for (const auto& item : items) s += (s.empty() ? "" : ", ") + item;
    return s;
}

std::string command_names(const CLI::App& top) {
    std::vector<std::string> names;
    for (const CLI::App* sub : top.get_subcommands([](const CLI::App*) { return true; }))
        if (!sub->get_group().empty()) names.push_back(sub->get_name());   // hidden commands are not offered
    return join(names);
}

// SCENE for the positional `scene`, --photons for an option.
std::string display_name(const CLI::Option* option) {
    if (option->nonpositional()) return option->get_name();
    std::string name = option->get_name(true);
    for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return name;
}

std::vector<std::string> option_names(const CLI::App& app) {
    std::vector<std::string> names;
    for (const CLI::Option* option : app.get_options())
        if (option->nonpositional() && !option->get_name().empty()) names.push_back(option->get_name());
    return names;
}

std::vector<std::string> argument_names(const CLI::App& app) {
    std::vector<std::string> names;
    for (const CLI::Option* option : app.get_options())
        if (!option->nonpositional()) names.push_back(display_name(option));
    return names;
}

std::string valid_or_doc(const CLI::Option* option) {
    const std::string valid = valid_text(option);
    return valid.empty() ? option->get_description() : valid;
}

// A message on one line (CLI11's own texts may hold newlines).
std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

const CLI::App* active_command(const CLI::App& top) {
    const std::vector<CLI::App*> parsed = top.get_subcommands();
    return parsed.empty() ? nullptr : parsed.front();
}

}  // namespace

std::optional<std::string> unknown_argument_message(const CLI::App& top) {
    const CLI::App* where = &top;
    std::vector<std::string> rest = top.remaining();
    if (rest.empty())
        for (const CLI::App* sub : top.get_subcommands()) {
            rest = sub->remaining();
            where = sub;
            if (!rest.empty()) break;
        }
    if (rest.empty()) return std::nullopt;
    // Name an unknown option before a stray value (often the unknown option's own value).
    std::string arg = rest.front();
    for (const std::string& r : rest)
        if (r.size() > 1 && r[0] == '-' && !std::isdigit(static_cast<unsigned char>(r[1]))) {
            arg = r;
            break;
        }
    const bool option = arg.size() > 1 && arg[0] == '-' && !std::isdigit(static_cast<unsigned char>(arg[1]));
    if (where == &top)
        return arg + (option ? ": unknown option" : ": unknown command") + "; valid: a command (" + command_names(top) +
               ") or --help";
    const std::string command = "'caustics " + where->get_name() + "'";
    if (option) return arg + ": unknown option of " + command + "; valid: " + join(option_names(*where));
    const std::vector<std::string> args = argument_names(*where);
    return "'" + arg + "': unexpected argument of " + command + ", which takes " +
           (args.empty() ? std::string("no argument") : join(args)) + "; valid: " +
           (args.empty() ? std::string() : join(args) + " and ") + "the options " + join(option_names(*where));
}

std::string usage_error_message(const CLI::App& top, const CLI::ParseError& error) {
    const CLI::App* command = active_command(top);
    if (dynamic_cast<const CLI::RequiredError*>(&error)) {
        if (!command) return "COMMAND: missing; valid: " + command_names(top);
        for (const CLI::Option* option : command->get_options())
            if (option->get_required() && option->count() == 0)
                return display_name(option) + ": missing; valid: " + valid_or_doc(option);
    }
    if (dynamic_cast<const CLI::ArgumentMismatch*>(&error)) {
        const std::string what = error.what();
        const std::string name = what.substr(0, what.find(':'));
        const CLI::Option* option = (command ? command : &top)->get_option_no_throw(name);
        if (option) {
            if (option->count() > 1)
                return display_name(option) + ": given " + std::to_string(option->count()) + " times; valid: once";
            return display_name(option) + ": value missing; valid: " + valid_or_doc(option);
        }
    }
    return one_line(error.what()) + "; valid: see caustics " + (command ? command->get_name() + " " : std::string()) +
           "--help";
}

std::string unknown_command_message(const CLI::App& top, const std::string& name) {
    return name + ": unknown command; valid: " + command_names(top);
}

}  // namespace caustics::cli
