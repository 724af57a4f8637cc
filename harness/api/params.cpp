#include <caustics/api/params.hpp>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include <caustics/util/errors.hpp>

namespace caustics {
namespace {

// Shortest text that reads back to the same double ("0.1", "1e-12"), so tables and result rows show
// what the user typed.
std::string format_number(double v) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, result.ptr);
}

bool parse_double(const std::string& text, double& out) {
    if (text.empty()) return false;
    errno = 0;
    char* end = nullptr;
    out = std::strtod(text.c_str(), &end);
    return errno == 0 && end == text.c_str() + text.size() && std::isfinite(out);
}

bool parse_integer(const std::string& text, long long& out) {
    if (text.empty()) return false;
    errno = 0;
    char* end = nullptr;
    out = std::strtoll(text.c_str(), &end, 10);
    if (errno == 0 && end == text.c_str() + text.size()) return true;
    // Accept integral floating forms such as "256.0" or "1e3" that sweep ranges produce.
    double d = 0.0;
    if (parse_double(text, d) && d == std::floor(d) && std::fabs(d) < 9e15) {
        out = static_cast<long long>(d);
        return true;
    }
    return false;
}

bool parse_bool(const std::string& text, bool& out) {
    if (text == "true" || text == "1" || text == "on" || text == "yes") { out = true; return true; }
    if (text == "false" || text == "0" || text == "off" || text == "no") { out = false; return true; }
    return false;
}

// Validates `text` against `spec` and returns its canonical text; throws InputError otherwise.
std::string canonical(const std::string& owner, const ParamSpec& spec, const std::string& text) {
    auto fail = [&]() -> std::string {
        throw InputError(owner, spec.name, "invalid value '" + text + "'; valid: " + spec.valid_text());
    };
    switch (spec.type) {
    case ParamType::Int: {
        long long v = 0;
        if (!parse_integer(text, v) || v < spec.min || v > spec.max) return fail();
        return std::to_string(v);
    }
    case ParamType::Float: {
        double v = 0.0;
        if (!parse_double(text, v) || v < spec.min || v > spec.max) return fail();
        return format_number(v);
    }
    case ParamType::Enum:
        for (const auto& c : spec.choices)
            if (c == text) return text;
        return fail();
    case ParamType::Bool: {
        bool v = false;
        if (!parse_bool(text, v)) return fail();
        return v ? "true" : "false";
    }
    }
    return fail();
}

}  // namespace

const char* to_string(ParamType t) {
    switch (t) {
    case ParamType::Int: return "int";
    case ParamType::Float: return "float";
    case ParamType::Enum: return "enum";
    case ParamType::Bool: return "bool";
    }
    return "?";
}

std::string ParamSpec::valid_text() const {
    auto bound = [](double v) { return std::isinf(v) ? std::string(v < 0 ? "-inf" : "inf") : format_number(v); };
    switch (type) {
    case ParamType::Int: return "integer in [" + bound(min) + ", " + bound(max) + "]";
    case ParamType::Float: return "number in [" + bound(min) + ", " + bound(max) + "]";
    case ParamType::Bool: return "true or false";
    case ParamType::Enum: {
        std::string s = "one of ";
        for (std::size_t i = 0; i < choices.size(); ++i) s += (i ? "|" : "") + choices[i];
        return s;
    }
    }
    return "";
}

ParamSet ParamSet::resolve(const std::string& owner, const std::vector<ParamSpec>& specs,
                           const std::map<std::string, std::string>& overrides) {
    ParamSet set;
    set.owner_ = owner;
    for (const auto& spec : specs) {
        set.types_[spec.name] = spec.type;
        set.values_[spec.name] = canonical(owner, spec, spec.default_value);
    }
    for (const auto& [key, text] : overrides) {
        const ParamSpec* spec = nullptr;
        for (const auto& s : specs)
            if (s.name == key) spec = &s;
        if (!spec) {
            std::string known;
            for (const auto& s : specs) known += (known.empty() ? "" : ", ") + s.name;
            throw InputError(owner, key, "unknown parameter; valid parameters: " + known);
        }
        set.values_[key] = canonical(owner, *spec, text);
    }
    return set;
}

const std::string& ParamSet::raw(const std::string& name, ParamType expected) const {
    auto it = values_.find(name);
    if (it == values_.end() || types_.at(name) != expected)
        throw std::logic_error(owner_ + ": parameter '" + name + "' read as " + to_string(expected) +
                               " but not declared so in the parameter table");
    return it->second;
}

long long ParamSet::get_int(const std::string& name) const { return std::stoll(raw(name, ParamType::Int)); }
double ParamSet::get_float(const std::string& name) const { return std::stod(raw(name, ParamType::Float)); }
const std::string& ParamSet::get_enum(const std::string& name) const { return raw(name, ParamType::Enum); }
bool ParamSet::get_bool(const std::string& name) const { return raw(name, ParamType::Bool) == "true"; }

nlohmann::json param_json(const std::string& owner, const ParamSpec& spec, const std::string& text) {
    const std::string canonical_text = canonical(owner, spec, text);
    switch (spec.type) {
    case ParamType::Int: return std::stoll(canonical_text);
    case ParamType::Float: return std::stod(canonical_text);
    case ParamType::Bool: return canonical_text == "true";
    case ParamType::Enum: break;
    }
    return canonical_text;
}

std::pair<std::string, std::string> parse_assignment(const std::string& text, const std::string& option) {
    auto eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError(option, text, "expected KEY=VALUE");
    return {text.substr(0, eq), text.substr(eq + 1)};
}

}  // namespace caustics
