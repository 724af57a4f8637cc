// caustics list [--json]: methods with their parameter tables, and the scenes in scenes/.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "command.hpp"
#include <caustics/api/registry.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene_catalog.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json methods_json() {
    json methods = json::array();
    for (const MethodInfo* info : registered_methods()) {
        json params = json::array();
        for (const ParamSpec& p : info->params) {
            json j;
            j["name"] = p.name;
            j["type"] = to_string(p.type);
            j["default"] = param_json(info->name, p, p.default_value);
            j["valid"] = p.valid_text();
            if (p.type == ParamType::Int || p.type == ParamType::Float) {
                j["min"] = json_number(p.min);   // null: unbounded
                j["max"] = json_number(p.max);
            }
            if (p.type == ParamType::Enum) j["choices"] = p.choices;
            j["doc"] = p.doc;
            // What "methods": "all" in a sweep spec runs (the default alone where empty).
            j["sweep"] = json::array();
            for (const std::string& v : p.sweep) j["sweep"].push_back(param_json(info->name, p, v));
            params.push_back(j);
        }
        methods.push_back({{"name", info->name}, {"doc", info->doc}, {"radiometric", info->radiometric},
                           {"params", params}, {"origin", method_origin(info->name)}});
    }
    return methods;
}

// The scene files in the scenes folder with their description (read without full validation, which
// would generate height fields and load meshes).
json scenes_json() {
    json scenes = json::array();
    const fs::path dir = scenes_directory();
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return scenes;
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir, ec))
        if (entry.is_regular_file() && entry.path().extension() == ".json") files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
        json s = {{"name", f.stem().string()}, {"path", f.string()}, {"description", ""}};
        std::ifstream in(f);
        const json doc = json::parse(in, nullptr, false, true);
        if (doc.is_object() && doc.contains("description") && doc["description"].is_string())
            s["description"] = doc["description"];
        if (doc.is_discarded()) s["description"] = "(not valid JSON)";
        scenes.push_back(s);
    }
    return scenes;
}

void print_text(const json& methods, const json& scenes) {
    std::cout << "Methods (" << methods.size() << "):\n";
    for (const json& m : methods) {
        std::cout << "\n  " << m["name"].get<std::string>()
                  << (m["radiometric"].get<bool>() ? "  [radiometric]" : "  [relative values: errors after a scale fit]")
                  << "\n    " << m["doc"].get<std::string>() << "\n    registered by "
                  << m["origin"].get<std::string>() << "\n";
        for (const json& p : m["params"]) {
            char line[512];
            std::snprintf(line, sizeof line, "    --set %-18s %-5s default %-10s %s", p["name"].get<std::string>().c_str(),
                          p["type"].get<std::string>().c_str(),
                          (p["default"].is_string() ? p["default"].get<std::string>() : p["default"].dump()).c_str(),
                          p["valid"].get<std::string>().c_str());
            std::cout << line << "\n        " << p["doc"].get<std::string>() << "\n";
            if (!p["sweep"].empty()) {
                std::string values;
                for (const json& v : p["sweep"]) values += (values.empty() ? "" : ", ") + (v.is_string() ? v.get<std::string>() : v.dump());
                std::cout << "        swept at " << values << " where a sweep spec says \"methods\": \"all\"\n";
            }
        }
    }
    std::cout << "\nScenes (" << scenes_directory().string() << "):\n";
    for (const json& s : scenes) {
        char line[512];
        std::snprintf(line, sizeof line, "  %-12s %s", s["name"].get<std::string>().c_str(),
                      s["description"].get<std::string>().c_str());
        std::cout << line << "\n";
    }
}

Command make_list_command() {
    Command c;
    c.name = "list";
    c.summary = "List the methods (with their parameter tables) and the scenes";
    c.order = 10;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto as_json = std::make_shared<bool>(false);
        app.add_flag("--json", *as_json, "Print JSON: {methods: [{name, doc, radiometric, params: [{name, type, default, valid, doc, sweep, ...}]}], scenes: [...]}");
        return [as_json]() {
            const json methods = methods_json();
            const json scenes = scenes_json();
            if (*as_json)
                std::cout << json{{"methods", methods}, {"scenes", scenes}}.dump(2) << "\n";
            else
                print_text(methods, scenes);
            return 0;
        };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_list_command);

}  // namespace caustics::cli
