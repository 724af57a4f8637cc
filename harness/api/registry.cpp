#include <caustics/api/registry.hpp>

#include <map>
#include <memory>

#include <caustics/util/errors.hpp>

namespace caustics {
namespace {

struct Entry {
    std::unique_ptr<MethodInfo> info;
    std::string origin;
    std::string build_type;   // "" for a method compiled into the program
};

// Function-local statics: registration runs during static initialisation of the method objects, whose
// order relative to this file is unspecified.
std::map<std::string, Entry>& table() {
    static std::map<std::string, Entry> methods;
    return methods;
}

std::vector<std::string>& conflicts() {
    static std::vector<std::string> messages;
    return messages;
}

}  // namespace

void add_method(MethodFactory make, const std::string& origin, const std::string& build_type) {
    std::unique_ptr<MethodInfo> info;
    try {
        info = std::make_unique<MethodInfo>(make());
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        // A plugin's method table that throws is the plugin's fault: named, as bad input.
        throw InputError(origin, "", std::string("describing its method failed: ") + e.what());
    }
    const std::string name = info->name;
    if (auto it = table().find(name); it != table().end())
        throw InputError(origin, name,
                         "a method of this name is already registered by " + it->second.origin +
                             "; method names must be unique: rename one of them");
    table()[name] = Entry{std::move(info), origin, build_type};
}

MethodRegistrar::MethodRegistrar(MethodFactory make, const char* origin) {
    try {
        add_method(make, origin);
    } catch (const InputError& e) {
        conflicts().push_back(e.what());
    }
}

std::vector<std::string> registration_conflicts() { return conflicts(); }

std::vector<const MethodInfo*> registered_methods() {
    std::vector<const MethodInfo*> out;
    for (const auto& [name, entry] : table()) out.push_back(entry.info.get());
    return out;
}

const MethodInfo* find_method(const std::string& name) {
    auto it = table().find(name);
    return it == table().end() ? nullptr : it->second.info.get();
}

std::string method_origin(const std::string& name) {
    auto it = table().find(name);
    return it == table().end() ? std::string() : it->second.origin;
}

std::string method_build_type(const std::string& name) {
    auto it = table().find(name);
    return it == table().end() ? std::string() : it->second.build_type;
}

const MethodInfo& require_method(const std::string& name, const std::string& option) {
    if (const MethodInfo* info = find_method(name)) return *info;
    std::string known;
    for (const MethodInfo* info : registered_methods()) known += (known.empty() ? "" : ", ") + info->name;
    throw InputError(option, name, "unknown method; known methods: " + known);
}

}  // namespace caustics
