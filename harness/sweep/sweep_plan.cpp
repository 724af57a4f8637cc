#include "detail/sweep_plan.hpp"

#include <fstream>

#include <caustics/reference/reference.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/hash.hpp>

#include "detail/sweep_files.hpp"

namespace caustics::sweep_plan {
namespace fs = std::filesystem;
using nlohmann::json;
using sweep_files::differences;
using sweep_files::listed;

namespace {

constexpr int kPlanVersion = 1;

// An axis value's canonical text as JSON (a number or boolean where it reads as one), for readable plans.
json value_json(const std::string& canonical) {
    const json v = json::parse(canonical, nullptr, false);
    return v.is_discarded() || !v.is_primitive() || v.is_null() ? json(canonical) : v;
}

}  // namespace

std::string scene_content_hash(const Scene& scene) {
    Hash128 h;
    hash_scene_contents(h, scene);
    return h.hex();
}

json sweep_plan(const SweepSpec& spec, const std::vector<PlannedRun>& runs, const std::vector<std::string>& scene_hashes,
                int threads, double timeout_s) {
    json plan;
    plan["version"] = kPlanVersion;
    json scenes = json::object();
    for (std::size_t i = 0; i < spec.scenes.size(); ++i) {
        const SweepScene& scene = spec.scenes[i];
        scenes[fs::path(scene.path).stem().string()] = {
            {"file_hash", scene_hashes[i]},
            {"frames", scene.frames},
            {"noise_target", scene.noise_target >= 0.0 ? scene.noise_target : spec.reference.noise_target},
            {"truth", scene.truth.empty() ? spec.truth : scene.truth}};
    }
    plan["scenes"] = scenes;
    const ReferenceSettings& r = spec.reference;
    plan["reference"] = {{"photons", r.photons}, {"seed", r.seed}, {"photon_cap", r.photon_cap},
                         {"sampler", sampler_name(r.sampler)}, {"replicas", r.replicas}};
    plan["timing"] = {{"warmup", spec.warmup}, {"repeats", spec.repeats}, {"precision", spec.timing_precision},
                      {"max_time_s", spec.timing_max_s}, {"timeout_s", timeout_s}, {"threads", threads}};
    json methods = json::object();
    for (const auto& m : spec.methods) {
        json axes = json::object();
        for (const auto& a : m.axes) {
            json values = json::array();
            for (const auto& v : a.values) values.push_back(value_json(v));
            axes[a.name] = values;
        }
        methods[m.method] = axes;
    }
    plan["methods"] = methods;
    Hash128 h;
    for (const PlannedRun& run : runs) {
        h.text(run.id);
        h.text(run.scene_name);
        h.u64(static_cast<std::uint64_t>(run.frame));
        h.text(run.method);
        h.u64(run.params.size());
        for (const auto& [k, v] : run.params) {
            h.text(k);
            h.text(v);
        }
        h.f64(run.noise_target);
        h.text(run.truth);
    }
    plan["runs"] = {{"count", runs.size()}, {"hash", h.hex()}};
    return plan;
}

std::string plan_hash(const json& plan) {
    Hash128 h;
    h.text(plan.dump());
    return h.hex();
}

json check_resume(const fs::path& dir, const json& plan, const SweepSpec& spec) {
    const fs::path manifest_path = dir / "manifest.json";
    std::error_code ec;
    const auto refuse = [&](const std::string& why) {
        return InputError("--resume", dir.string(), why + "; resume with the spec (and --axis, --threads, --timeout) "
                                                          "it was started with, or choose another --out folder");
    };
    if (!fs::exists(manifest_path, ec)) {
        if (fs::exists(dir / "results.jsonl", ec))
            throw refuse("the folder holds results.jsonl but no manifest.json, so the plan its rows were measured "
                         "with cannot be checked");
        return json::object();
    }
    std::ifstream in(manifest_path, std::ios::binary);
    const json manifest = json::parse(in, nullptr, false);
    if (manifest.is_discarded() || !manifest.is_object())
        throw refuse("manifest.json is not readable JSON, so the plan the sweep was started with cannot be checked");
    std::vector<std::string> diff;
    if (manifest.contains("plan")) {
        json was = manifest["plan"], current = plan;
        const json was_runs = was.value("runs", json()), now_runs = current.value("runs", json());
        was.erase("runs");
        current.erase("runs");
        differences(was, current, "", diff);
        if (diff.empty()) differences(was_runs, now_runs, "runs", diff);   // derived: named only alone
    } else if (manifest.contains("spec")) {
        // A folder from before plans were recorded: the spec as run must be the same.
        json was = manifest["spec"], current = spec.as_run;
        for (const char* free : {"description", "report"}) {
            if (was.is_object()) was.erase(free);
            if (current.is_object()) current.erase(free);
        }
        differences(was, current, "spec", diff);
    } else {
        throw refuse("manifest.json records neither the plan nor the spec the sweep was started with");
    }
    if (!diff.empty()) throw refuse("the sweep in this folder was started with another plan: " + listed(diff));
    return manifest;
}

}  // namespace caustics::sweep_plan
