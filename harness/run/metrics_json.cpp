#include <caustics/run/metrics_json.hpp>

#include <cmath>

#include <caustics/api/registry.hpp>
#include <caustics/run/resolved_method.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/run/thread_limit.hpp>
#include <caustics/run/view_table.hpp>
#include <caustics/util/build_info.hpp>

namespace caustics {

using nlohmann::json;

json json_number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// Timed samples to the microsecond (the clock's useful resolution here), so that a run's samples stay a
// short line of results.jsonl.
json samples_json(const std::vector<double>& samples_ms) {
    json out = json::array();
    for (double ms : samples_ms) out.push_back(json_number(std::round(ms * 1000.0) / 1000.0));
    return out;
}

json timing_json(const TimingSummary* t, const std::vector<double>& samples_ms) {
    if (!t || t->samples == 0)
        return {{"median", nullptr}, {"min", nullptr}, {"p90", nullptr}, {"stdev", nullptr}, {"iqr", nullptr}, {"ci_rel", nullptr},
                {"samples", json::array()}};
    return {{"median", json_number(t->median)}, {"min", json_number(t->min)}, {"p90", json_number(t->p90)},
            {"stdev", json_number(t->stdev)}, {"iqr", json_number(t->iqr)},
            {"ci_rel", t->has_interval ? json_number(t->ci_rel) : json(nullptr)}, {"samples", samples_json(samples_ms)}};
}

void timing_to_json(const RunTiming& t, json& j) {
    j["time_ms"] = timing_json(&t.render, t.render_samples_ms);
    j["frame_ms"] = timing_json(&t.frame, t.frame_samples_ms);
    j["frame_time"] = t.animated ? "update+render" : "render";
    j["fps"] = t.frame.median > 0.0 ? json_number(1000.0 / t.frame.median) : json(nullptr);
    j["render_fps"] = t.render.median > 0.0 ? json_number(1000.0 / t.render.median) : json(nullptr);
    j["noisy_timing"] = t.capped;
    j["prepare_ms"] = json_number(t.prepare_ms);
    j["update_ms"] = json_number(t.update_ms);
    json stages = json::object();
    for (const auto& [stage, ms] : t.stages_ms) stages[stage] = json_number(ms);
    j["stages_ms"] = stages;
    j["repeats"] = t.repeats;
}

json claim_json(const AccuracyClaim& claim) {
    json bounds = json::array();
    for (const RegimeBound& b : claim.bounds)
        bounds.push_back({{"quantity", b.quantity}, {"value", json_number(b.value)}, {"limit", json_number(b.limit)},
                          {"upper", b.upper}, {"holds", b.holds()}});
    return {{"inside", claim.inside},
            {"max_error", claim.inside ? json_number(claim.max_error) : json(nullptr)},
            {"bound", nullptr},
            {"reason", claim.inside ? json(nullptr) : json(claim.reason)},
            {"bounds", bounds},
            {"met", nullptr}};
}

// The metrics.json skeleton: every key of docs/design.md section 7, values null until measured.
json metrics_skeleton(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options) {
    json j;
    j["method"] = m.info->name;
    j["scene"] = sf.scene().name;
    j["frame"] = sf.geometry().frame;
    j["params"] = params_json(*m.info, m.params);
    j["radiometric"] = m.info->radiometric_at(m.params);
    j["time_ms"] = timing_json(nullptr);
    j["frame_ms"] = timing_json(nullptr);
    j["frame_time"] = nullptr;
    j["fps"] = nullptr;
    j["render_fps"] = nullptr;
    j["noisy_timing"] = nullptr;
    j["prepare_ms"] = nullptr;
    j["update_ms"] = nullptr;
    j["stages_ms"] = json::object();
    j["threads"] = ThreadLimit::effective();
    // Every view of the table (run/view_table.hpp), null until measured.
    j["error"] = json::object();
    for (const ViewSpec& v : view_table()) j["error"][v.name] = null_view_errors();
    j["reference"] = {{"photons", nullptr}, {"noise_nrmse", nullptr}, {"cache_key", nullptr}};
    j["truth"] = {{"kind", nullptr}, {"noise_nrmse", nullptr}};
    j["baseline"] = {{"kind", nullptr}, {"error", nullptr}};
    j["baseline_volume"] = {{"kind", nullptr}, {"error", nullptr}};
    j["health"] = json::object();
    j["status"] = nullptr;
    j["build_type"] = build_type();
    // A plugin is compiled apart from the program: its own build type (an unoptimised plugin in an
    // optimised program is timed as what it is).
    const std::string plugin_build = method_build_type(m.info->name);
    j["method_build_type"] = plugin_build.empty() ? std::string(build_type()) : plugin_build;
    j["warmup"] = options.warmup;
    j["repeats"] = options.repeats;
    j["below_reference_noise"] = nullptr;
    j["no_better_than_flat"] = nullptr;
    j["claim"] = {{"inside", nullptr}, {"max_error", nullptr}, {"bound", nullptr}, {"reason", nullptr},
                  {"bounds", json::array()}, {"met", nullptr}};
    j["message"] = "";
    return j;
}

}  // namespace caustics
