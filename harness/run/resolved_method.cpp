#include <caustics/run/resolved_method.hpp>

#include <caustics/api/registry.hpp>

namespace caustics {

using nlohmann::json;

ResolvedMethod resolve_method(const std::string& name, const std::map<std::string, std::string>& overrides) {
    ResolvedMethod r;
    r.info = &require_method(name);
    r.params = ParamSet::resolve(name, r.info->params, overrides);
    return r;
}

json params_json(const MethodInfo& info, const ParamSet& params) {
    json out = json::object();
    for (const ParamSpec& spec : info.params)
        if (auto it = params.values().find(spec.name); it != params.values().end())
            out[spec.name] = param_json(info.name, spec, it->second);
    return out;
}

}  // namespace caustics
