#include "options.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <system_error>

#include <caustics/util/errors.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/scene_catalog.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

std::map<const CLI::Option*, std::function<std::string()>>& valid_texts() {
    static std::map<const CLI::Option*, std::function<std::string()>> texts;
    return texts;
}

std::string join(const std::vector<std::string>& items, const std::string& sep = ", ") {
    std::string s;
    for (const auto& item : items) s += (s.empty() ? "" : sep) + item;
    return s;
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// A value as the user wrote it, quoted, so that an empty or odd value shows.
std::string shown(const std::string& text) { return "'" + text + "'"; }

// Plain digits, with the power of ten or two it is when that is easier to read ("100000000000 (1e11)").
std::string human_integer(std::int64_t v) {
    std::string s = std::to_string(v);
    if (v < 1'000'000) return s;
    std::int64_t p = 1;
    int e = 0;
    while (p < v && p <= INT64_MAX / 10) p *= 10, ++e;
    if (p == v) return s + " (1e" + std::to_string(e) + ")";
    if ((v & (v - 1)) == 0) {
        int b = 0;
        while ((std::int64_t{1} << b) != v) ++b;
        return s + " (2^" + std::to_string(b) + ")";
    }
    return s;
}

std::string human_number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

enum class IntegerParse { Ok, NotInteger, OutOfRange };

// Decimal integers, optionally written with a fraction and exponent that make an exact integer
// ("1e7", "2.5e6"); anything past 64 bits is out of range (never clamped or wrapped).
IntegerParse parse_integer(const std::string& text, std::int64_t& out) {
    std::size_t i = 0;
    bool negative = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
    std::string digits;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) digits += text[i++];
    std::size_t frac_digits = 0;
    if (i < text.size() && text[i] == '.') {
        ++i;
        while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) digits += text[i++], ++frac_digits;
    }
    if (digits.empty()) return IntegerParse::NotInteger;
    long long exponent = 0;
    if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
        ++i;
        bool exp_negative = false;
        if (i < text.size() && (text[i] == '+' || text[i] == '-')) exp_negative = text[i++] == '-';
        const std::size_t start = i;
        while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
        if (i == start) return IntegerParse::NotInteger;
        // Past 6 digits the exponent alone decides (a zero mantissa aside, handled below).
        const std::string exp_text = text.substr(start, std::min<std::size_t>(i - start, 7));
        exponent = std::stoll(exp_text) * (exp_negative ? -1 : 1);
    }
    if (i != text.size()) return IntegerParse::NotInteger;
    // value = digits * 10^(exponent - frac_digits)
    long long shift = exponent - static_cast<long long>(frac_digits);
    while (shift < 0 && !digits.empty() && digits.back() == '0') digits.pop_back(), ++shift;
    digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size()));
    if (digits.empty()) {
        out = 0;
        return IntegerParse::Ok;
    }
    if (shift < 0) return IntegerParse::NotInteger;   // a fraction
    if (static_cast<long long>(digits.size()) + shift > 19) return IntegerParse::OutOfRange;
    digits.append(static_cast<std::size_t>(shift), '0');
    if (negative) digits.insert(digits.begin(), '-');
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), out);
    if (ec == std::errc::result_out_of_range) return IntegerParse::OutOfRange;
    if (ec != std::errc() || end != digits.data() + digits.size()) return IntegerParse::NotInteger;
    return IntegerParse::Ok;
}

// The first component below the root of an absolute path ("proc" for /proc/x).
std::string top_folder(const fs::path& p) {
    auto it = p.begin();
    if (it == p.end() || *it != p.root_path()) return {};
    ++it;
    return it == p.end() ? std::string() : it->string();
}

bool is_loop(const std::error_code& ec) { return ec == std::errc::too_many_symbolic_link_levels; }

}  // namespace

std::string valid_text(const CLI::Option* option) {
    const auto it = valid_texts().find(option);
    return it == valid_texts().end() ? std::string() : it->second();
}

void set_valid_text(CLI::Option* option, std::function<std::string()> text) { valid_texts()[option] = std::move(text); }

void forget_valid_texts() { valid_texts().clear(); }

std::string integer_range_text(std::int64_t lo, std::int64_t hi, const std::string& note) {
    return "an integer from " + human_integer(lo) + " to " + human_integer(hi) + (note.empty() ? "" : " (" + note + ")");
}

void check_integer(const std::string& option, std::string& text, std::int64_t lo, std::int64_t hi, const std::string& note) {
    const std::string valid = integer_range_text(lo, hi, note);
    std::int64_t v = 0;
    switch (parse_integer(text, v)) {
    case IntegerParse::NotInteger: throw invalid_value(option, shown(text) + " is not an integer", valid);
    case IntegerParse::OutOfRange: throw invalid_value(option, text + " is out of range", valid);
    case IntegerParse::Ok: break;
    }
    if (v < lo || v > hi) throw invalid_value(option, text + " is out of range", valid);
    text = std::to_string(v);   // plain decimal for CLI11's own conversion
}

CLI::Option* check_integer_option(CLI::Option* option, std::int64_t lo, std::int64_t hi, const std::string& note) {
    const std::string name = option->get_name();
    option->transform(CLI::Validator(
        [name, lo, hi, note](std::string& text) {
            check_integer(name, text, lo, hi, note);
            return std::string();
        },
        std::to_string(lo) + ".." + std::to_string(hi)));
    set_valid_text(option, [lo, hi, note] { return integer_range_text(lo, hi, note); });
    return option;
}

CLI::Option* add_number_option(CLI::App& app, const std::string& name, double& value, double lo, double hi,
                               const std::string& doc, const std::string& note) {
    const std::string valid = "a number from " + human_number(lo) + " to " + human_number(hi) + (note.empty() ? "" : " (" + note + ")");
    CLI::Option* option = app.add_option(name, value, doc);
    option->check(CLI::Validator(
        [name, lo, hi, valid](std::string& text) {
            const char* begin = text.c_str();
            char* end = nullptr;
            errno = 0;
            const double v = std::strtod(begin, &end);
            if (text.empty() || end != begin + text.size() || std::isspace(static_cast<unsigned char>(text[0])))
                throw invalid_value(name, shown(text) + " is not a number", valid);
            if (!std::isfinite(v)) throw invalid_value(name, text + " is not a finite number", valid);
            if (v < lo || v > hi) throw invalid_value(name, text + " is out of range", valid);
            return std::string();
        },
        human_number(lo) + ".." + human_number(hi)));
    set_valid_text(option, [valid] { return valid; });
    return option;
}

CLI::Option* add_choice_option(CLI::App& app, const std::string& name, std::string& value,
                               const std::vector<std::string>& choices, const std::string& doc) {
    std::vector<std::pair<std::string, std::string>> same;
    for (const auto& c : choices) same.emplace_back(c, c);
    return check_enum_option(app.add_option(name, value, doc), same);
}

CLI::Option* check_enum_option(CLI::Option* option, const std::vector<std::pair<std::string, std::string>>& choices) {
    const std::string name = option->get_name();
    std::vector<std::string> names;
    for (const auto& c : choices) names.push_back(c.first);
    const std::string valid = join(names);
    option->transform(CLI::Validator(
        [name, choices, valid](std::string& text) {
            for (const auto& [choice, stored] : choices)
                if (lower(text) == lower(choice)) {
                    text = stored;
                    return std::string();
                }
            throw invalid_value(name, shown(text) + " is not a choice", valid);
        },
        join(names, "|")));
    set_valid_text(option, [valid] { return valid; });
    return option;
}

namespace {

std::string method_names() {
    std::vector<std::string> names;
    for (const MethodInfo* info : registered_methods()) names.push_back(info->name);
    return join(names);
}

}  // namespace

CLI::Option* add_method_option(CLI::App& app, std::string& value, const std::string& doc) {
    CLI::Option* option = app.add_option("--method", value, doc);
    option->check(CLI::Validator(
        [](std::string& text) {
            if (!find_method(text)) throw invalid_value("--method", "unknown method " + shown(text), method_names());
            return std::string();
        },
        "METHOD"));
    set_valid_text(option, method_names);
    return option;
}

CLI::Option* add_scene_argument(CLI::App& app, std::string& value, const std::string& doc) {
    CLI::Option* option = app.add_option("scene", value, doc);
    set_valid_text(option, scene_argument_valid_text);
    return option;
}

CLI::Option* add_input_file_argument(CLI::App& app, const std::string& name, std::string& value, const std::string& doc,
                                     const std::string& what) {
    CLI::Option* option = app.add_option(name, value, doc);
    option->check(CLI::Validator(
        [what](std::string& text) {
            std::error_code ec;
            const fs::file_status st = fs::status(text, ec);
            if (text.empty()) throw invalid_value(what, "empty path", "the path of " + what);
            if (is_loop(ec)) throw invalid_value(text, "symbolic link loop", "the path of " + what);
            if (!fs::exists(st)) {
                const bool dangling = fs::is_symlink(fs::symlink_status(text, ec));
                throw invalid_value(text, dangling ? "a symbolic link to a file that does not exist" : "no such file",
                                    "the path of " + what);
            }
            if (fs::is_directory(st)) throw invalid_value(text, "a folder, not a file", "the path of " + what);
            if (::access(text.c_str(), R_OK) != 0) throw invalid_value(text, "cannot be read", "a readable " + what);
            return std::string();
        },
        "FILE"));
    set_valid_text(option, [what] { return "the path of " + what; });
    return option;
}

CLI::Option* add_assignment_option(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                                   const std::string& doc) {
    CLI::Option* option = app.add_option(name, values, doc);
    option->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    const std::string valid = "KEY=VALUE with KEY a parameter of the method (caustics list), each KEY once";
    option->check(CLI::Validator(
        [name, valid](std::string& text) {
            const auto eq = text.find('=');
            if (eq == std::string::npos) throw invalid_value(name, shown(text) + " has no '='", valid);
            if (eq == 0) throw invalid_value(name, shown(text) + " has no KEY before '='", valid);
            return std::string();
        },
        "KEY=VALUE"));
    set_valid_text(option, [valid] { return valid; });
    return option;
}

void check_output_folder(const std::string& option, const std::string& path) {
    const std::string valid = "a folder that exists or can be created, and can be written, outside /proc and /sys";
    if (path.empty()) throw invalid_value(option, "empty path", valid);
    std::error_code ec;
    const fs::path absolute = fs::absolute(path, ec);
    if (ec) throw invalid_value(option, path + ": " + ec.message(), valid);
    // Virtual file systems, as written and as resolved through links.
    for (const fs::path& p : {absolute.lexically_normal(), fs::weakly_canonical(absolute, ec)}) {
        const std::string top = top_folder(p);
        if (top == "proc" || top == "sys")
            throw invalid_value(option, path + " is in /" + top + ", a virtual file system", valid);
    }
    // The path itself, else its nearest ancestor that exists: a folder we may write into.
    for (fs::path p = absolute.lexically_normal(); !p.empty(); p = p.parent_path()) {
        const fs::file_status st = fs::status(p, ec);
        const bool self = p == absolute.lexically_normal();
        // A dangling symbolic link neither exists nor can be created as a folder (creating it fails only
        // after the work: a reference computed and cached first).
        std::error_code link_ec;
        if (!fs::exists(st) && fs::is_symlink(fs::symlink_status(p, link_ec))) {
            const std::string target = fs::read_symlink(p, link_ec).string();
            throw invalid_value(option,
                                path + (self ? " is" : " lies under " + p.string() + ", which is") +
                                    " a symbolic link to " + target + ", which does not exist",
                                valid);
        }
        if (is_loop(ec)) {
            // Name the outermost link of the loop: "out/loop/sub" lies under "out/loop".
            fs::path loop = p;
            for (std::error_code up; loop.has_relative_path(); loop = loop.parent_path()) {
                (void)fs::status(loop.parent_path(), up);
                if (!is_loop(up)) break;
            }
            throw invalid_value(option,
                                path + (loop == absolute.lexically_normal() ? "" : " lies under " + loop.string() + ", which") +
                                    " is a symbolic link loop",
                                valid);
        }
        if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
            throw invalid_value(option, path + ": " + p.string() + ": " + ec.message(), valid);
        if (fs::exists(st)) {
            if (self && !fs::is_directory(st))
                throw invalid_value(option, path + (fs::is_regular_file(st) ? " is a file, not a folder" : " exists and is not a folder"),
                                    valid);
            if (!self && !fs::is_directory(st))
                throw invalid_value(option, path + " lies under " + p.string() + ", which is a file, not a folder", valid);
            if (::access(p.c_str(), W_OK | X_OK) != 0)
                throw invalid_value(option,
                                    path + (self ? " cannot be written" : " cannot be created: " + p.string() + " cannot be written"),
                                    valid);
            return;
        }
        if (p == p.root_path()) break;
    }
    throw invalid_value(option, path + " cannot be created", valid);
}

void check_output_file(const std::string& option, const std::string& path) {
    const std::string valid = "a file path in an existing writable folder, not a folder, outside /proc and /sys";
    if (path.empty()) throw invalid_value(option, "empty path", valid);
    std::error_code ec;
    const fs::path absolute = fs::absolute(path, ec).lexically_normal();
    if (ec) throw invalid_value(option, path + ": " + ec.message(), valid);
    if (fs::is_directory(fs::status(absolute, ec)))
        throw invalid_value(option, path + " is a folder, not a file", valid);
    const fs::path folder = absolute.parent_path();
    const fs::file_status st = fs::status(folder, ec);
    if (!fs::exists(st)) throw invalid_value(option, path + ": the folder " + folder.string() + " does not exist", valid);
    // The folder passes the output-folder checks (not a file, in /proc or /sys, writable).
    check_output_folder(option, folder.string());
}

CLI::Option* add_output_file_option(CLI::App& app, const std::string& name, std::string& value, const std::string& doc) {
    CLI::Option* option = app.add_option(name, value, doc);
    option->check(CLI::Validator(
        [name](std::string& text) {
            check_output_file(name, text);
            return std::string();
        },
        "FILE"));
    set_valid_text(option, [] { return std::string("a file path in an existing writable folder, not a folder"); });
    return option;
}

CLI::Option* add_output_folder_option(CLI::App& app, const std::string& name, std::string& value, const std::string& doc) {
    CLI::Option* option = app.add_option(name, value, doc);
    option->check(CLI::Validator(
        [name](std::string& text) {
            check_output_folder(name, text);
            return std::string();
        },
        "DIR"));
    set_valid_text(option, [] { return std::string("a folder that exists or can be created, and can be written"); });
    return option;
}

}  // namespace caustics::cli
