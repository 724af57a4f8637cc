#include <caustics/run/resolved_method.hpp>

#include <caustics/api/registry.hpp>
#include <caustics/run/metrics_json.hpp>

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
    for (const ParamSpec& spec : info.params) {
        auto it = params.values().find(spec.name);
        if (it == params.values().end()) continue;
        const std::string& text = it->second;
        switch (spec.type) {
        case ParamType::Int: out[spec.name] = std::stoll(text); break;
        case ParamType::Float: out[spec.name] = json_number(std::stod(text)); break;
        case ParamType::Bool: out[spec.name] = text == "true"; break;
        case ParamType::Enum: out[spec.name] = text; break;
        }
    }
    return out;
}

}  // namespace caustics
