#pragma once
// Checked command-line options: every value is checked as text when the command line is parsed, before
// any work, and a bad one is refused with InputError (exit 2) in the one message style of the program:
//
//   caustics: error: <option or file>: <what is wrong>; valid: <what would be valid>
//
// Integer options are parsed strictly (no wrap-around of -1, no clamping past 64 bits; 1e7 is read as
// 10000000) against a range stated in human terms; numbers must be finite and in range; choices, methods
// and folders list what would be valid. Each option also records its "valid" text, which the usage
// errors of CLI11 itself (a missing value, a repeated option; usage_errors.hpp) quote.
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

namespace caustics::cli {

// The "valid" text recorded for an option ("" if none).
std::string valid_text(const CLI::Option* option);
void set_valid_text(CLI::Option* option, std::function<std::string()> text);
// Forgets every option's text: for a process that builds parser after parser (the sweep worker), whose
// options' addresses are the keys and can be reused by the next parser's options.
void forget_valid_texts();

// "an integer from 1000 to 100000000000 (1e11)", with `note` in parentheses after it when given.
std::string integer_range_text(std::int64_t lo, std::int64_t hi, const std::string& note = "");
// Checks `text` as an integer in [lo, hi] and rewrites it in plain decimal; throws InputError naming `option`.
void check_integer(const std::string& option, std::string& text, std::int64_t lo, std::int64_t hi,
                   const std::string& note = "");

// Adds the integer check to an option (see add_integer_option).
CLI::Option* check_integer_option(CLI::Option* option, std::int64_t lo, std::int64_t hi, const std::string& note);

// An integer option in [lo, hi] (both representable in T). `note` explains special values ("0: every core").
template <class T>
CLI::Option* add_integer_option(CLI::App& app, const std::string& name, T& value, std::int64_t lo, std::int64_t hi,
                                const std::string& doc, const std::string& note = "") {
    static_assert(std::is_integral_v<T>);
    return check_integer_option(app.add_option(name, value, doc), lo, hi, note);
}

// A finite number in [lo, hi].
CLI::Option* add_number_option(CLI::App& app, const std::string& name, double& value, double lo, double hi,
                               const std::string& doc, const std::string& note = "");

// One of `choices` (case-insensitive); the value stored is the choice's own spelling.
CLI::Option* add_choice_option(CLI::App& app, const std::string& name, std::string& value,
                               const std::vector<std::string>& choices, const std::string& doc);

// Adds the choice check to an option bound to an enumeration: `choices` maps each name to the
// enumerator's integer value as text.
CLI::Option* check_enum_option(CLI::Option* option, const std::vector<std::pair<std::string, std::string>>& choices);

// One of `choices`, mapped to an enumerator (case-insensitive).
template <class E>
CLI::Option* add_enum_option(CLI::App& app, const std::string& name, E& value,
                             const std::vector<std::pair<std::string, E>>& choices, const std::string& doc) {
    std::vector<std::pair<std::string, std::string>> as_text;
    for (const auto& [text, e] : choices) as_text.emplace_back(text, std::to_string(static_cast<long long>(e)));
    return check_enum_option(app.add_option(name, value, doc), as_text);
}

// A registered method's name (the list of methods when it is not one).
CLI::Option* add_method_option(CLI::App& app, std::string& value, const std::string& doc);

// The SCENE argument: a scene file or a name in scenes/ (checked when the command runs, by
// resolve_scene_path; recorded here for the message of a missing SCENE).
CLI::Option* add_scene_argument(CLI::App& app, std::string& value, const std::string& doc);

// An existing, readable file (a sweep spec); `what` says what it is for the message.
CLI::Option* add_input_file_argument(CLI::App& app, const std::string& name, std::string& value,
                                     const std::string& doc, const std::string& what);

// KEY=VALUE assignments, repeatable (--set): each must have a KEY and '='.
CLI::Option* add_assignment_option(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                                   const std::string& doc);

// An output folder (--out, --cache): not empty, not an existing file, not under a file, not through a
// symbolic link loop, not in /proc or /sys, and either an existing writable folder or creatable under
// one. Checked as given, before any work; nothing is created.
CLI::Option* add_output_folder_option(CLI::App& app, const std::string& name, std::string& value, const std::string& doc);
// The same check of a folder chosen by the program (a default --out); throws InputError naming `option`.
void check_output_folder(const std::string& option, const std::string& path);

// An output file (--screenshot): not empty, not a folder, in an existing folder that passes the output
// folder's checks. Checked as given, before any work.
CLI::Option* add_output_file_option(CLI::App& app, const std::string& name, std::string& value, const std::string& doc);
void check_output_file(const std::string& option, const std::string& path);

}  // namespace caustics::cli
