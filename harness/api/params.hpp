#pragma once
// Typed method parameters (docs/design.md section 4). Each method declares a table of ParamSpec; values are
// read only through ParamSet, which rejects unknown keys and out-of-range values with an InputError
// naming the key and what would be valid.
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace caustics {

enum class ParamType { Int, Float, Enum, Bool };

struct ParamSpec {
    std::string name;
    ParamType type = ParamType::Float;
    std::string default_value;
    double min = -std::numeric_limits<double>::infinity();  // Int/Float: inclusive range
    double max = std::numeric_limits<double>::infinity();
    std::vector<std::string> choices;   // Enum: valid values
    std::string doc;
    // The values a sweep of every method ("methods": "all" in a sweep spec) runs this parameter at, as
    // text: a quick survey of its effect. Empty: such a sweep keeps the default.
    std::vector<std::string> sweep = {};   // (initialised so that tables may leave it out)

    std::string valid_text() const;    // "integer in [1, 4096]", "one of approx|newton", ...
};

const char* to_string(ParamType t);

class ParamSet {
public:
    ParamSet() = default;
    // Resolves defaults and overrides against the table. `owner` (the method name) prefixes messages.
    static ParamSet resolve(const std::string& owner, const std::vector<ParamSpec>& specs,
                            const std::map<std::string, std::string>& overrides);

    long long get_int(const std::string& name) const;
    double get_float(const std::string& name) const;
    const std::string& get_enum(const std::string& name) const;
    bool get_bool(const std::string& name) const;
    // The canonical text of every parameter, defaults included (result rows record it).
    const std::map<std::string, std::string>& values() const { return values_; }

private:
    const std::string& raw(const std::string& name, ParamType expected) const;
    std::string owner_;
    std::map<std::string, std::string> values_;
    std::map<std::string, ParamType> types_;
};

// A value of `spec` as the JSON value of its type (integer, number, boolean or string), checked and
// canonicalised as ParamSet::resolve does; throws InputError naming `owner` and the key otherwise.
nlohmann::json param_json(const std::string& owner, const ParamSpec& spec, const std::string& text);

// Parses "key=value" (from --set); throws InputError naming `option` when there is no '='.
std::pair<std::string, std::string> parse_assignment(const std::string& text, const std::string& option);

}  // namespace caustics
