#pragma once
// A small key-path-aware JSON reader for input validation: every value knows its path
// ("objects[2].material.ior") and the file it came from, so any problem becomes
// InputError(file, path, what would be valid). Objects reject keys they do not know.
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace caustics {

// The deepest nesting of arrays and objects an input file may have (scene files and sweep specs nest a few
// levels); deeper input is refused before it is used, so no later step recurses through it.
inline constexpr std::size_t kMaxJsonDepth = 64;
// The most characters of a string value a message quotes.
inline constexpr std::size_t kMaxQuotedChars = 60;

// Parses an input file's text: InputError(file, "", ...) for invalid JSON, InputError(file, key path, ...) for
// a key repeated inside one object (nlohmann would silently keep one) or nesting deeper than kMaxJsonDepth.
nlohmann::json parse_json_strict(const std::string& text, const std::string& file);

// The deepest nesting of arrays and objects in JSON text, counted by scanning (strings and their escapes
// skipped, nothing parsed or built), for text handed to a parser this project does not control; stops
// counting once past `limit`. Malformed text gives some count: the parser refuses it afterwards.
std::size_t json_nesting_depth(std::string_view text, std::size_t limit);

// A value in a message: strings (cut to kMaxQuotedChars), numbers and booleans as written, arrays and objects
// by kind and size only (never serialised: they can be arbitrarily large or deep).
std::string describe_json(const nlohmann::json& value);

class JsonNode {
public:
    JsonNode(const std::string& file, const nlohmann::json& value, std::string path = {})
        : file_(&file), value_(&value), path_(std::move(path)) {}

    const std::string& path() const { return path_; }
    const std::string& file() const { return *file_; }
    const nlohmann::json& json() const { return *value_; }

    // Throws InputError(file, path, problem).
    [[noreturn]] void fail(const std::string& problem) const;
    // The path of a (possibly absent) member, for messages.
    std::string member_path(const std::string& key) const;

    // Objects.
    void expect_object() const;
    // Must be an object whose keys are all in `allowed` (else names the unknown key and the valid ones).
    void check_keys(std::initializer_list<const char*> allowed) const;
    bool has(const std::string& key) const;
    JsonNode at(const std::string& key) const;  // required member: fails if absent

    // Arrays.
    std::size_t array_size() const;  // fails unless an array
    JsonNode at(std::size_t index) const;

    // Scalars. Numbers must be JSON numbers (never strings such as "NaN") and finite.
    double as_number() const;
    // A finite number in a range: lo/hi bounds are inclusive unless the *_open flag is set.
    double as_number_in(double lo, double hi, bool lo_open = false, bool hi_open = false) const;
    double as_positive() const;      // finite, > 0
    double as_nonnegative() const;   // finite, >= 0
    std::int64_t as_integer_in(std::int64_t lo, std::int64_t hi) const;
    std::uint64_t as_seed() const;   // a non-negative integer
    bool as_bool() const;
    std::string as_string() const;
    // One of the given words.
    std::string as_enum(std::initializer_list<const char*> words) const;
    glm::dvec2 as_vec2() const;
    glm::dvec3 as_vec3() const;
    glm::dvec2 as_nonzero_vec2() const;
    glm::dvec3 as_nonzero_vec3() const;
    glm::ivec2 as_ivec2_in(int lo, int hi) const;

private:
    std::vector<double> numbers(std::size_t count) const;
    std::string type_name() const;

    const std::string* file_;
    const nlohmann::json* value_;
    std::string path_;
};

}  // namespace caustics
