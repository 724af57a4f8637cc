#include <caustics/api/registry.hpp>

#include <algorithm>
#include <map>
#include <memory>

#include <caustics/util/errors.hpp>

namespace caustics {
namespace {

// Function-local static: registration runs during static initialisation of the method objects, whose
// order relative to this file is unspecified.
std::map<std::string, std::unique_ptr<MethodInfo>>& table() {
    static std::map<std::string, std::unique_ptr<MethodInfo>> methods;
    return methods;
}

}  // namespace

MethodRegistrar::MethodRegistrar(MethodInfo (*make)()) {
    auto info = std::make_unique<MethodInfo>(make());
    std::string name = info->name;
    table()[name] = std::move(info);
}

std::vector<const MethodInfo*> registered_methods() {
    std::vector<const MethodInfo*> out;
    for (const auto& [name, info] : table()) out.push_back(info.get());
    return out;
}

const MethodInfo* find_method(const std::string& name) {
    auto it = table().find(name);
    return it == table().end() ? nullptr : it->second.get();
}

const MethodInfo& require_method(const std::string& name, const std::string& option) {
    if (const MethodInfo* info = find_method(name)) return *info;
    std::string known;
    for (const MethodInfo* info : registered_methods()) known += (known.empty() ? "" : ", ") + info->name;
    throw InputError(option, name, "unknown method; known methods: " + known);
}

}  // namespace caustics
