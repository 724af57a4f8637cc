#include <caustics/run/render_run.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/run/beauty.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/run/metrics.hpp>
#include <caustics/run/metrics_json.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::int64_t count_nonfinite(const Image& image, const std::vector<std::uint8_t>* mask) {
    std::int64_t n = 0;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    for (std::size_t p = 0; p < pixels; ++p) {
        if (mask && !(*mask)[p]) continue;
        for (int c = 0; c < image.channels; ++c)
            if (!std::isfinite(image.pixels[p * image.channels + c])) ++n;
    }
    return n;
}

void check_size(const Image& image, int w, int h, const std::string& method, const std::string& what) {
    if (image.empty()) return;
    if (image.width != w || image.height != h || image.channels != 1)
        throw std::runtime_error("method " + method + " returned a " + what + " image of " +
                                 std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                                 std::to_string(image.channels) + ", expected " + std::to_string(w) + "x" +
                                 std::to_string(h) + "x1");
}

// The volume view against the reference's, over every pixel, with the constant baseline (the mean
// radiance over the pixels the reference lights: no caustic structure) as the bar to clear.
void measure_volume_view(const Image& method, const ReferenceResult& reference, bool radiometric, nlohmann::json& j,
                         std::vector<std::string>& messages) {
    const TruthMaps truth{&reference.camera_volume, &reference.camera_volume_replicas, &reference.camera_volume_stderr};
    const Baseline baseline = make_baseline(Image{}, reference.camera_volume);
    const ViewErrors e = measure_view(method, truth, nullptr, radiometric, &baseline.map);
    j["error"]["camera_volume"] = e.json;
    j["baseline_volume"] = {{"kind", baseline.kind}, {"error", e.have_baseline ? json_number(e.baseline_error) : nlohmann::json(nullptr)}};
    if (e.net.valid && e.have_baseline && e.no_better_than_flat)
        messages.push_back("camera_volume: no better than the constant baseline");
}

std::string join_messages(const std::vector<std::string>& parts) {
    std::string s;
    for (const auto& p : parts) s += (s.empty() ? "" : "; ") + p;
    return s;
}

}  // namespace

RenderRun run_method(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options,
                     const ReferenceProvider& reference_provider) {
    const MethodInfo& info = *m.info;
    RenderRun run;
    run.metrics = metrics_skeleton(sf, m, options);
    std::vector<std::string> messages;

    std::unique_ptr<Method> method;
    try {
        method = info.create(m.params);
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        // Named with where it comes from (a plugin's library), before any work: refused like bad input.
        throw InputError(method_origin(info.name), info.name, std::string("creating the method failed: ") + e.what());
    }
    Capability cap = method->capabilities(sf.scene());
    // A scene whose medium scatters has volume caustics, and extinction along every caustic path: only
    // a method that renders the volume view (and so models the medium) is measured on it.
    const bool volume = scene_scatters(sf.scene());
    if (cap.supported && volume) {
        const Capability v = method->volume_capability(sf.scene());
        if (!v.supported)
            cap = Capability::no("the scene's medium scatters (volume caustics, camera_volume, and extinction along "
                                 "every path): " + v.reason);
    }
    if (!cap.supported) {
        run.status = "skipped";
        run.message = cap.reason;
        run.metrics["status"] = run.status;
        run.metrics["message"] = run.message;
        return run;
    }

    // Timed regions: prepare, update, each repeat of render (and of update where the scene is animated).
    // Nothing else (docs/design.md section 6).
    Stopwatch clock;
    method->prepare(sf.scene());
    const double prepare_ms = clock.ms();
    clock.reset();
    method->update(sf.geometry());
    const double first_update_ms = clock.ms();

    RenderRequest request;
    request.receiver = &sf.chart();
    request.camera = &sf.gbuffer();
    request.camera_volume = volume;
    // In an animated scene the geometry changes every frame, so a frame costs update + render; in a
    // static one update runs once and a frame is the render alone.
    const bool animated = sf.scene().animation.frames > 1;
    for (int i = 0; i < options.warmup; ++i) {
        if (animated) method->update(sf.geometry());
        (void)method->render(sf.geometry(), request);
    }
    std::vector<double> render_times, update_times, frame_times;
    std::map<std::string, std::vector<double>> stage_times;
    TimingPolicy policy;
    policy.min_repeats = std::max(1, options.repeats);
    policy.precision = options.timing_precision;
    policy.max_seconds = options.timing_max_s;
    double timed_seconds = 0.0;
    TimingStop stop = TimingStop::Continue;
    while (stop == TimingStop::Continue) {
        double update_ms = 0.0;
        if (animated) {
            clock.reset();
            method->update(sf.geometry());
            update_ms = clock.ms();
            update_times.push_back(update_ms);
        }
        clock.reset();
        CausticOutput out = method->render(sf.geometry(), request);
        const double ms = clock.ms();
        render_times.push_back(ms);
        frame_times.push_back(update_ms + ms);
        timed_seconds += (update_ms + ms) / 1000.0;
        for (const auto& [stage, stage_ms] : out.stages_ms) stage_times[stage].push_back(stage_ms);
        run.output = std::move(out);   // the previous output is freed outside the timed region
        stop = timing_stop(frame_times, timed_seconds, policy);
    }
    const TimingSummary t = summarize_ms(render_times);
    const TimingSummary f = summarize_ms(frame_times);
    json& j = run.metrics;
    j["time_ms"] = timing_json(&t);
    j["frame_ms"] = timing_json(&f);
    j["frame_time"] = animated ? "update+render" : "render";
    j["fps"] = f.median > 0.0 ? json_number(1000.0 / f.median) : json(nullptr);
    j["render_fps"] = t.median > 0.0 ? json_number(1000.0 / t.median) : json(nullptr);
    j["noisy_timing"] = stop == TimingStop::Capped;
    if (stop == TimingStop::Capped)
        messages.push_back("noisy timing: the median's 95 % interval is +-" + std::to_string(100.0 * f.ci_rel).substr(0, 5) +
                           " % after " + std::to_string(f.samples) + " frames (target " +
                           std::to_string(100.0 * options.timing_precision).substr(0, 4) + " %)");
    j["prepare_ms"] = json_number(prepare_ms);
    j["update_ms"] = json_number(animated ? summarize_ms(update_times).median : first_update_ms);
    json stages = json::object();
    for (auto& [stage, samples] : stage_times) stages[stage] = json_number(summarize_ms(samples).median);
    j["stages_ms"] = stages;
    j["repeats"] = static_cast<int>(render_times.size());

    // Output shape and health: non-finite values are counted by the harness too and never averaged in.
    const CausticOutput& out = run.output;
    const CameraGBuffer& g = sf.gbuffer();
    check_size(out.receiver, sf.chart().width(), sf.chart().height(), info.name, "receiver");
    check_size(out.camera, g.width, g.height, info.name, "camera");
    check_size(out.camera_volume, g.width, g.height, info.name, "camera_volume");
    const std::int64_t nonfinite = count_nonfinite(out.receiver, nullptr) + count_nonfinite(out.camera, &g.covered) +
                                   count_nonfinite(out.camera_volume, nullptr);
    json health = json::object();
    for (const auto& [name, value] : out.health.counters) health[name] = value;
    health["nonfinite_pixels"] = nonfinite;
    j["health"] = health;
    // What the method claims on this frame (Method::accuracy_claim); `met` is filled once the error is known.
    const AccuracyClaim claim = method->accuracy_claim(sf.geometry());
    j["claim"] = claim_json(claim);
    if (!claim.inside) messages.push_back("outside the method's claimed regime: " + claim.reason);
    const bool unstable = nonfinite > 0 || out.health.get("nonfinite") > 0;
    run.status = unstable ? "unstable" : "ok";
    if (unstable)
        messages.push_back("non-finite output (" + std::to_string(nonfinite) + " pixels, method counter " +
                           std::to_string(out.health.get("nonfinite")) + "): error not measured");
    if (out.receiver.empty()) messages.push_back("method produced no receiver map");
    if (out.camera.empty()) messages.push_back("method produced no camera view");
    if (volume && out.camera_volume.empty()) messages.push_back("method produced no camera_volume view");

    // The truth and the reference are asked for only now, after the timed region and only for supported
    // runs. The receiver's truth is the analytic closed form where the scene has one (truth auto or
    // analytic), else the Monte Carlo reference; the camera view is always measured against the reference.
    const ReferenceResult* reference = reference_provider ? reference_provider() : nullptr;
    if (reference) {
        run.have_reference = true;
        j["reference"] = reference_summary_json(*reference);
        AnalyticTruth analytic;
        if (options.truth != "reference") analytic = analytic_truth(sf.geometry(), sf.chart());
        if (options.truth == "analytic" && !analytic.available)
            messages.push_back("no analytic truth (" + analytic.reason + "): measured against the reference");
        const TruthMaps truth = analytic.available
                                    ? TruthMaps{&analytic.receiver, nullptr, nullptr}
                                    : TruthMaps{&reference->receiver, &reference->receiver_replicas, &reference->receiver_stderr};
        j["truth"] = {{"kind", analytic.available ? analytic.kind : std::string("reference")},
                      {"noise_nrmse", analytic.available ? json(0.0) : json_number(reference->noise_nrmse)}};
        if (!unstable) {
            if (!out.receiver.empty()) {
                const Baseline baseline = make_baseline(flat_interface_baseline(sf.geometry(), sf.chart()), *truth.mean);
                const ViewErrors e = measure_view(out.receiver, truth, nullptr, info.radiometric_at(m.params), &baseline.map);
                j["error"]["receiver"] = e.json;
                // Only a noisy truth can hide an error; against a closed form the question does not arise.
                if (e.net.valid && !truth.exact()) j["below_reference_noise"] = e.net.includes_zero;
                j["baseline"] = {{"kind", baseline.kind}, {"error", e.have_baseline ? json_number(e.baseline_error) : json(nullptr)}};
                // Judged like the conformance suite: the plain error (after the fit where not radiometric)
                // against the claimed bound (the stated nrmse or half the baseline's, the smaller); exact
                // truths only (a noisy one is judged by the net error's interval, which the report shows),
                // and only where there is a caustic to judge (a flat interface within 0.1 % of the truth
                // leaves no multiple of its error to ask).
                if (claim.inside && e.have_baseline && truth.exact() && e.baseline_error > 1e-3) {
                    const char* key = info.radiometric_at(m.params) ? "nrmse" : "nrmse_fit";
                    j["claim"]["bound"] = json_number(claim.bound(e.baseline_error));
                    if (e.json.contains(key) && e.json[key].is_number())
                        j["claim"]["met"] = e.json[key].get<double>() <= claim.bound(e.baseline_error);
                }
                if (e.net.valid && e.have_baseline) {
                    j["no_better_than_flat"] = e.no_better_than_flat;
                    if (e.no_better_than_flat) messages.push_back("no better than the no-caustic baseline (" + baseline.kind + ")");
                }
            }
            if (!out.camera.empty() && !reference->camera.empty()) {
                std::vector<std::uint8_t> mask = g.covered;
                if (reference->camera_covered.size() == mask.size())
                    for (std::size_t p = 0; p < mask.size(); ++p) mask[p] &= reference->camera_covered[p];
                const TruthMaps camera_truth{&reference->camera, &reference->camera_replicas, &reference->camera_stderr};
                const ViewErrors e = measure_view(out.camera, camera_truth, &mask, info.radiometric_at(m.params), nullptr);
                j["error"]["camera"] = e.json;
                if (e.samples == 0) messages.push_back("camera view: no pixel's primary hit is a diffuse receiver");
            }
            if (!out.camera_volume.empty() && !reference->camera_volume.empty())
                measure_volume_view(out.camera_volume, *reference, info.radiometric_at(m.params), j, messages);
            if (!info.radiometric_at(m.params))
                messages.push_back("not radiometric: nrmse_fit/fit_scale are after a least-squares scale fit");
        }
    } else {
        messages.push_back("no reference: error values are null");
    }
    run.message = join_messages(messages);
    j["status"] = run.status;
    j["message"] = run.message;
    return run;
}

namespace {

LoadedFrame* g_loaded = nullptr;

// What decides the reference besides the scene frame: its settings (as `caustics render` arguments, the
// complete list) and the cache folder it is read from.
std::string reference_store_key(const RenderOptions& options) {
    std::string key = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    for (const std::string& a : reference_arguments(reference_settings(options))) key.append("\n").append(a);
    return key;
}

}  // namespace

void keep_loaded_frame(LoadedFrame* store) { g_loaded = store; }

RenderRun run_render(const RenderOptions& options) {
    ThreadLimit limit(options.threads);
    // Every InputError comes from these three steps, before anything is written: loading the scene,
    // resolving the method, building the frame (in this order). A kept scene frame passed the first and
    // the last already.
    const std::string scene_path = resolve_scene_path(options.scene_path);
    const std::string scene_key = scene_path + "\n" + std::to_string(options.frame);
    LoadedFrame* kept = g_loaded;
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
