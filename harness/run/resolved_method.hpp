#pragma once
// A method name and --set overrides resolved against the registry and the method's parameter table.
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>

namespace caustics {

struct ResolvedMethod {
    const MethodInfo* info = nullptr;
    ParamSet params;
};
// require_method + ParamSet::resolve: InputError for an unknown method, key or value.
ResolvedMethod resolve_method(const std::string& name, const std::map<std::string, std::string>& overrides);

// The resolved parameters as typed JSON (ints, numbers, booleans, strings): metrics.json's `params`.
nlohmann::json params_json(const MethodInfo& info, const ParamSet& params);

}  // namespace caustics
