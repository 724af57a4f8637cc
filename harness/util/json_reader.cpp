#include <caustics/util/json_reader.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <vector>

#include <caustics/util/errors.hpp>

namespace caustics {

namespace {

std::string format_number(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
}

std::string join(std::initializer_list<const char*> words, const char* quote) {
    std::string out;
    for (const char* w : words) {
        if (!out.empty()) out += ", ";
        out += quote;
        out += w;
        out += quote;
    }
    return out;
}

}  // namespace

void JsonNode::fail(const std::string& problem) const { throw InputError(*file_, path_, problem); }

std::string JsonNode::member_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

std::string describe_json(const nlohmann::json& j) {
    if (j.is_string()) {
        const std::string& text = j.get_ref<const std::string&>();
        if (text.size() <= kMaxQuotedChars)
            return "the string " + j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        return "the string " +
               nlohmann::json(text.substr(0, kMaxQuotedChars)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
               "... (" +
               std::to_string(text.size()) + " characters)";
    }
    if (j.is_number()) return "the number " + j.dump();
    if (j.is_boolean()) return j.dump();
    if (j.is_null()) return "null";
    if (j.is_array()) return "an array of " + std::to_string(j.size()) + " element(s)";
    if (j.is_object()) return "an object";
    return j.type_name();
}

nlohmann::json parse_json_strict(const std::string& text, const std::string& file) {
    struct Level {
        bool object = false;
        std::set<std::string> keys;
        std::string key;
        std::size_t index = 0;
    };
    std::vector<Level> stack;
    const auto key_path = [&stack] {
        std::string path;
        for (const Level& l : stack) {
            if (l.object) path += (path.empty() ? "" : ".") + l.key;
            else path.append("[").append(std::to_string(l.index)).append("]");
        }
        return path;
    };
    auto callback = [&](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using E = nlohmann::json::parse_event_t;
        const auto element_done = [&] {
            if (!stack.empty() && !stack.back().object) ++stack.back().index;
        };
        switch (event) {
        case E::object_start:
        case E::array_start:
            if (stack.size() >= kMaxJsonDepth)
                throw InputError(file, key_path(), "nested deeper than " + std::to_string(kMaxJsonDepth) +
                                                       " arrays and objects; no valid input nests that deep");
            stack.push_back({event == E::object_start, {}, {}, 0});
            break;
        case E::object_end:
        case E::array_end:
            if (!stack.empty()) stack.pop_back();
            element_done();
            break;
        case E::value: element_done(); break;
        case E::key: {
            Level& top = stack.back();
            top.key = parsed.get<std::string>();
            if (!top.keys.insert(top.key).second)
                throw InputError(file, key_path(), "duplicate key: each key may appear once in an object");
            break;
        }
        }
        return true;
    };
    try {
        return nlohmann::json::parse(text, callback);
    } catch (const nlohmann::json::exception& e) {
        // parse_error carries "at line L, column C"; out_of_range 406 is a number literal that overflows.
        throw InputError(file, "", std::string("not valid JSON: ") + e.what());
    }
}

std::size_t json_nesting_depth(std::string_view text, std::size_t limit) {
    std::size_t depth = 0, deepest = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
            continue;
        }
        if (c == '"') in_string = true;
        else if (c == '[' || c == '{') {
            deepest = std::max(deepest, ++depth);
            if (deepest > limit) return deepest;
        } else if ((c == ']' || c == '}') && depth > 0) --depth;
    }
    return deepest;
}

std::string JsonNode::type_name() const { return describe_json(*value_); }

void JsonNode::expect_object() const {
    if (!value_->is_object()) fail("must be a JSON object, not " + type_name());
}

void JsonNode::check_keys(std::initializer_list<const char*> allowed) const {
    expect_object();
    for (const auto& item : value_->items()) {
        bool known = false;
        for (const char* a : allowed) known = known || item.key() == a;
        if (!known) {
            throw InputError(*file_, member_path(item.key()),
                             "unknown key; valid keys here are " + join(allowed, ""));
        }
    }
}

bool JsonNode::has(const std::string& key) const { return value_->is_object() && value_->contains(key); }

JsonNode JsonNode::at(const std::string& key) const {
    expect_object();
    auto it = value_->find(key);
    if (it == value_->end()) throw InputError(*file_, member_path(key), "missing required key");
    return JsonNode(*file_, *it, member_path(key));
}

std::size_t JsonNode::array_size() const {
    if (!value_->is_array()) fail("must be an array, not " + type_name());
    return value_->size();
}

JsonNode JsonNode::at(std::size_t index) const {
    return JsonNode(*file_, value_->at(index), path_ + "[" + std::to_string(index) + "]");
}

double JsonNode::as_number() const {
    if (!value_->is_number()) fail("must be a finite number, not " + type_name());
    const double x = value_->get<double>();
    if (!std::isfinite(x)) fail("must be a finite number");
    return x;
}

double JsonNode::as_number_in(double lo, double hi, bool lo_open, bool hi_open) const {
    std::string range(lo_open ? "(" : "[");
    range += format_number(lo);
    range += ", ";
    range += format_number(hi);
    range += hi_open ? ")" : "]";
    if (!value_->is_number()) fail("must be a finite number in " + range + ", not " + type_name());
    const double x = value_->get<double>();
    const bool ok = std::isfinite(x) && (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
    if (!ok) fail("must be a finite number in " + range + ", got " + describe_json(*value_));
    return x;
}

double JsonNode::as_positive() const {
    if (!value_->is_number()) fail("must be a finite number > 0, not " + type_name());
    const double x = value_->get<double>();
    if (!std::isfinite(x) || !(x > 0.0)) fail("must be a finite number > 0, got " + describe_json(*value_));
    return x;
}

double JsonNode::as_nonnegative() const {
    if (!value_->is_number()) fail("must be a finite number >= 0, not " + type_name());
    const double x = value_->get<double>();
    if (!std::isfinite(x) || !(x >= 0.0)) fail("must be a finite number >= 0, got " + describe_json(*value_));
    return x;
}

std::int64_t JsonNode::as_integer_in(std::int64_t lo, std::int64_t hi) const {
    const std::string range = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (value_->is_number_unsigned()) {
        const std::uint64_t u = value_->get<std::uint64_t>();
        if (u > static_cast<std::uint64_t>(hi) || static_cast<std::int64_t>(u) < lo) fail("must be " + range + ", got " + describe_json(*value_));
        return static_cast<std::int64_t>(u);
    }
    if (value_->is_number_integer()) {
        const std::int64_t i = value_->get<std::int64_t>();
        if (i < lo || i > hi) fail("must be " + range + ", got " + describe_json(*value_));
        return i;
    }
    fail("must be " + range + ", not " + type_name());
}

std::uint64_t JsonNode::as_seed() const {
    if (value_->is_number_unsigned()) return value_->get<std::uint64_t>();
    if (value_->is_number_integer() && value_->get<std::int64_t>() >= 0) return static_cast<std::uint64_t>(value_->get<std::int64_t>());
    fail("must be a non-negative integer, not " + type_name());
}

bool JsonNode::as_bool() const {
    if (!value_->is_boolean()) fail("must be true or false, not " + type_name());
    return value_->get<bool>();
}

std::string JsonNode::as_string() const {
    if (!value_->is_string()) fail("must be a string, not " + type_name());
    return value_->get<std::string>();
}

std::string JsonNode::as_enum(std::initializer_list<const char*> words) const {
    if (!value_->is_string()) fail("must be one of " + join(words, "\"") + ", not " + type_name());
    const std::string s = value_->get<std::string>();
    for (const char* w : words)
        if (s == w) return s;
    fail("must be one of " + join(words, "\"") + ", got " + describe_json(*value_));
}

std::vector<double> JsonNode::numbers(std::size_t count) const {
    const std::string want = "an array of " + std::to_string(count) + " finite numbers";
    if (!value_->is_array() || value_->size() != count) fail("must be " + want + ", not " + type_name());
    std::vector<double> out(count);
    for (std::size_t k = 0; k < count; ++k) {
        const nlohmann::json& e = (*value_)[k];
        if (!e.is_number() || !std::isfinite(e.get<double>()))
            fail("must be " + want + "; element " + std::to_string(k) + " is " + describe_json(e));
        out[k] = e.get<double>();
    }
    return out;
}

glm::dvec2 JsonNode::as_vec2() const {
    const auto n = numbers(2);
    return {n[0], n[1]};
}

glm::dvec3 JsonNode::as_vec3() const {
    const auto n = numbers(3);
    return {n[0], n[1], n[2]};
}

glm::dvec2 JsonNode::as_nonzero_vec2() const {
    const glm::dvec2 v = as_vec2();
    if (!(glm::length(v) > 0.0) || !std::isfinite(glm::length(v))) fail("must be a non-zero vector of 2 finite numbers");
    return v;
}

glm::dvec3 JsonNode::as_nonzero_vec3() const {
    const glm::dvec3 v = as_vec3();
    if (!(glm::length(v) > 0.0) || !std::isfinite(glm::length(v))) fail("must be a non-zero vector of 3 finite numbers");
    return v;
}

glm::ivec2 JsonNode::as_ivec2_in(int lo, int hi) const {
    const std::string want = "an array of 2 integers in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!value_->is_array() || value_->size() != 2) fail("must be " + want + ", not " + type_name());
    glm::ivec2 out;
    for (int k = 0; k < 2; ++k) {
        const nlohmann::json& e = (*value_)[static_cast<std::size_t>(k)];
        if (!e.is_number_integer() || e.get<std::int64_t>() < lo || e.get<std::int64_t>() > hi ||
            (e.is_number_unsigned() && e.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)))
            fail("must be " + want + "; element " + std::to_string(k) + " is " + describe_json(e));
        out[k] = static_cast<int>(e.get<std::int64_t>());
    }
    return out;
}

}  // namespace caustics
