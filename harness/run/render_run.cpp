#include <caustics/run/render_run.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/run/beauty.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/run/metrics.hpp>
#include <caustics/run/metrics_json.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/run/view_table.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string join_messages(const std::vector<std::string>& parts) {
    std::string s;
    for (const auto& p : parts) s += (s.empty() ? "" : "; ") + p;
    return s;
}

std::unique_ptr<Method> create_method(const ResolvedMethod& m) {
    try {
        return m.info->create(m.params);
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        // Named with where it comes from (a plugin's library), before any work: refused like bad input.
        throw InputError(method_origin(m.info->name), m.info->name, std::string("creating the method failed: ") + e.what());
    }
}

std::string noisy_timing_message(const RunTiming& t, const RenderOptions& options) {
    return "noisy timing: the median's 95 % interval is +-" + std::to_string(100.0 * t.frame.ci_rel).substr(0, 5) +
           " % after " + std::to_string(t.frame.samples) + " frames (target " +
           std::to_string(100.0 * options.timing_precision).substr(0, 4) + " %)";
}

// metrics.json's `truth`: the primary view's (the receiver's) truth, the analytic closed form where the scene
// has one (truth auto or analytic), else the Monte Carlo reference.
json truth_json(const AnalyticTruth& analytic, const ReferenceResult& reference) {
    return {{"kind", analytic.available ? analytic.kind : std::string("reference")},
            {"noise_nrmse", analytic.available ? json(0.0) : json_number(reference.noise_nrmse)}};
}

// Every measured view's errors, its baseline's, and on the primary view the claim's judgement.
void judge_views(const std::vector<EvaluatedView>& views, const AccuracyClaim& claim, bool radiometric, json& j,
                 std::vector<std::string>& messages) {
    for (const EvaluatedView& v : views) {
        const ViewSpec& spec = *v.spec;
        const ViewErrors& e = v.errors;
        j["error"][spec.name] = e.json;
        if (v.has_baseline && !spec.baseline_key.empty())
            j[spec.baseline_key] = {{"kind", v.baseline_kind},
                                    {"error", e.have_baseline ? json_number(e.baseline_error) : json(nullptr)}};
        if (spec.primary) {
            // Only a noisy truth can hide an error; against a closed form the question does not arise.
            if (e.net.valid && !v.exact_truth) j["below_reference_noise"] = e.net.includes_zero;
            // Judged like the conformance suite: the plain error (after the fit where not radiometric)
            // against the claimed bound (the stated nrmse or half the baseline's, the smaller); exact truths
            // only (a noisy one is judged by the net error's interval, which the report shows), and only
            // where there is a caustic to judge (a flat interface within 0.1 % of the truth leaves no
            // multiple of its error to ask).
            if (claim.inside && e.have_baseline && v.exact_truth && e.baseline_error > 1e-3) {
                const char* key = radiometric ? "nrmse" : "nrmse_fit";
                const bool measured = e.json.contains(key) && e.json[key].is_number();
                const ClaimJudgement c = judge_claim(claim, measured ? e.json[key].get<double>() : NAN, e.baseline_error);
                j["claim"]["bound"] = json_number(c.bound);
                if (measured) j["claim"]["met"] = c.met;
            }
            if (e.net.valid && e.have_baseline) j["no_better_than_flat"] = e.no_better_than_flat;
        }
        if (e.net.valid && e.have_baseline && e.no_better_than_flat && spec.no_better_note)
            messages.push_back(spec.no_better_note(v.baseline_kind));
        if (e.samples == 0 && !spec.empty_note.empty()) messages.push_back(spec.empty_note);
    }
}

}  // namespace

RenderRun run_method(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options,
                     const ReferenceProvider& reference_provider) {
    const MethodInfo& info = *m.info;
    RenderRun run;
    run.metrics = metrics_skeleton(sf, m, options);
    json& j = run.metrics;
    std::unique_ptr<Method> method = create_method(m);
    const Capability cap = decide_capability(*method, sf.scene());
    if (!cap.supported) {
        run.status = RunStatus::Skipped;
        run.message = cap.reason;
        j["status"] = status_name(run.status);
        j["message"] = run.message;
        return run;
    }

    // Timed regions: prepare, update, each repeat of render (and of update where the scene is animated).
    // Nothing else (docs/design.md section 6).
    RenderRequest request;
    request.receiver = &sf.chart();
    request.camera = &sf.gbuffer();
    request.camera_volume = scene_scatters(sf.scene());
    run.timing = time_method(*method, sf, request, options, run.output);
    timing_to_json(run.timing, j);
    std::vector<std::string> messages;
    if (run.timing.capped) messages.push_back(noisy_timing_message(run.timing, options));

    // Output shape and health: non-finite values are counted by the harness too and never averaged in.
    const CausticOutput& out = run.output;
    const OutputCheck check = check_output(out, sf, info.name);
    json health = json::object();
    for (const auto& [name, value] : out.health.counters) health[name] = value;
    health["nonfinite_pixels"] = check.nonfinite;
    j["health"] = health;
    // What the method claims on this frame (Method::accuracy_claim); `met` is filled once the error is known.
    run.claim = method->accuracy_claim(sf.geometry());
    j["claim"] = claim_json(run.claim);
    if (!run.claim.inside) messages.push_back("outside the method's claimed regime: " + run.claim.reason);
    run.status = check.unstable ? RunStatus::Unstable : RunStatus::Ok;
    messages.insert(messages.end(), check.messages.begin(), check.messages.end());

    // The truth and the reference are asked for only now, after the timed region and only for supported runs.
    const ReferenceResult* reference = reference_provider ? reference_provider() : nullptr;
    if (reference) {
        run.have_reference = true;
        j["reference"] = reference_summary_json(*reference);
        AnalyticTruth analytic;
        if (options.truth != "reference") analytic = analytic_truth(sf.geometry(), sf.chart());
        if (options.truth == "analytic" && !analytic.available)
            messages.push_back("no analytic truth (" + analytic.reason + "): measured against the reference");
        j["truth"] = truth_json(analytic, *reference);
        const bool radiometric = info.radiometric_at(m.params);
        if (!check.unstable) {
            const ViewSources sources = view_sources(sf, reference, &analytic);
            judge_views(evaluate_views(out, sources, radiometric), run.claim, radiometric, j, messages);
            if (!radiometric) messages.push_back("not radiometric: nrmse_fit/fit_scale are after a least-squares scale fit");
        }
    } else {
        messages.push_back("no reference: error values are null");
    }
    run.message = join_messages(messages);
    j["status"] = status_name(run.status);
    j["message"] = run.message;
    return run;
}

namespace {

// What decides the reference besides the scene frame: its settings (as `caustics render` arguments, the
// complete list) and the cache folder it is read from.
std::string reference_store_key(const RenderOptions& options) {
    std::string key = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    for (const std::string& a : reference_arguments(reference_settings(options))) key.append("\n").append(a);
    return key;
}

}  // namespace

RenderRun run_render(const RenderOptions& options, LoadedFrame* kept) {
    ThreadLimit limit(options.threads);
    // Every InputError comes from these three steps, before anything is written: loading the scene,
    // resolving the method, building the frame (in this order). A kept scene frame passed the first and
    // the last already.
    const std::string scene_path = resolve_scene_path(options.scene_path);
    const std::string scene_key = scene_path + "\n" + std::to_string(options.frame);
    std::unique_ptr<SceneFrame> own;
    const SceneFrame* sf = nullptr;
    std::optional<ResolvedMethod> method;
    if (kept && kept->frame && kept->scene_key == scene_key) {
        method = resolve_method(options.method, options.overrides);
        sf = kept->frame.get();
    } else {
        if (kept) *kept = LoadedFrame{};   // free the old frame and reference before building the new one
        Scene scene = load_scene(scene_path);
        method = resolve_method(options.method, options.overrides);
        own = std::make_unique<SceneFrame>(std::move(scene), options.frame);
        sf = own.get();
        if (kept) {
            kept->scene_key = scene_key;
            kept->frame = std::move(own);
        }
    }

    std::optional<ReferenceResult> reference;
    ReferenceProvider provider;
    if (!options.no_reference)
        provider = [&]() -> const ReferenceResult* {
            if (!kept) {
                reference = reference_for(*sf, options);
                return &*reference;
            }
            const std::string key = reference_store_key(options);
            if (!kept->reference || kept->reference_key != key) {
                kept->reference.reset();
                kept->reference = std::make_unique<ReferenceResult>(reference_for(*sf, options));
                kept->reference_key = key;
            }
            return kept->reference.get();
        };
    RenderRun run = run_method(*sf, *method, options, provider);
    if (!options.out_dir.empty()) write_render_outputs(options.out_dir, *sf, run, options);
    return run;
}

}  // namespace caustics
