#include <caustics/run/render_run.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include <tbb/global_control.h>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/run/beauty.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/run/metrics.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/timing.hpp>

#ifndef CAUSTICS_BUILD_TYPE
#define CAUSTICS_BUILD_TYPE "unknown"
#endif

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

json timing_json(const TimingSummary* t) {
    if (!t || t->samples == 0)
        return {{"median", nullptr}, {"min", nullptr}, {"p90", nullptr}, {"stdev", nullptr}, {"iqr", nullptr}, {"ci_rel", nullptr}};
    return {{"median", json_number(t->median)}, {"min", json_number(t->min)}, {"p90", json_number(t->p90)},
            {"stdev", json_number(t->stdev)}, {"iqr", json_number(t->iqr)},
            {"ci_rel", t->has_interval ? json_number(t->ci_rel) : json(nullptr)}};
}

// The metrics.json skeleton: every key of DESIGN.md section 7, values null until measured.
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
    j["error"] = {{"receiver", null_view_errors()}, {"camera", null_view_errors()}};
    j["reference"] = {{"photons", nullptr}, {"noise_nrmse", nullptr}, {"cache_key", nullptr}};
    j["truth"] = {{"kind", nullptr}, {"noise_nrmse", nullptr}};
    j["baseline"] = {{"kind", nullptr}, {"error", nullptr}};
    j["health"] = json::object();
    j["status"] = nullptr;
    j["build_type"] = CAUSTICS_BUILD_TYPE;
    j["warmup"] = options.warmup;
    j["repeats"] = options.repeats;
    j["below_reference_noise"] = nullptr;
    j["no_better_than_flat"] = nullptr;
    j["claim"] = {{"inside", nullptr}, {"error_vs_baseline", nullptr}, {"reason", nullptr}, {"met", nullptr}};
    j["message"] = "";
    return j;
}

std::string join_messages(const std::vector<std::string>& parts) {
    std::string s;
    for (const auto& p : parts) s += (s.empty() ? "" : "; ") + p;
    return s;
}

}  // namespace

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

json json_number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

SceneFrame::SceneFrame(Scene scene, int frame)
    : scene_(std::move(scene)), geometry_(build_frame_geometry(scene_, frame)) {
    tracer_ = std::make_unique<RayTracer>(geometry_);
    chart_ = std::make_unique<ReceiverChart>(geometry_, scene_.receiver.width, scene_.receiver.height);
    gbuffer_ = build_camera_gbuffer(*tracer_, scene_.camera);
}

ResolvedMethod resolve_method(const std::string& name, const std::map<std::string, std::string>& overrides) {
    ResolvedMethod r;
    r.info = &require_method(name);
    r.params = ParamSet::resolve(name, r.info->params, overrides);
    return r;
}

ReferenceSettings reference_settings(const RenderOptions& options) {
    ReferenceSettings settings;
    settings.photons = options.photons;
    settings.seed = options.seed;
    settings.sampler = options.sampler;
    settings.replicas = options.replicas;
    settings.noise_target = options.noise_target;
    settings.photon_cap = options.photon_cap;
    settings.threads = options.threads;
    settings.camera_view = true;
    settings.progress = options.progress;
    return settings;
}

ReferenceResult reference_for(const SceneFrame& sf, const RenderOptions& options) {
    const ReferenceSettings settings = reference_settings(options);
    const std::string cache = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    return load_or_compute_reference(sf.geometry(), sf.tracer(), sf.chart(), &sf.gbuffer(), settings, cache);
}

RenderRun run_method(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options,
                     const ReferenceProvider& reference_provider) {
    const MethodInfo& info = *m.info;
    RenderRun run;
    run.metrics = metrics_skeleton(sf, m, options);
    std::vector<std::string> messages;

    std::unique_ptr<Method> method = info.create(m.params);
    const Capability cap = method->capabilities(sf.scene());
    if (!cap.supported) {
        run.status = "skipped";
        run.message = cap.reason;
        run.metrics["status"] = run.status;
        run.metrics["message"] = run.message;
        return run;
    }

    // Timed regions: prepare, update, each repeat of render (and of update where the scene is animated).
    // Nothing else (DESIGN.md section 6).
    Stopwatch clock;
    method->prepare(sf.scene());
    const double prepare_ms = clock.ms();
    clock.reset();
    method->update(sf.geometry());
    const double first_update_ms = clock.ms();

    RenderRequest request;
    request.receiver = &sf.chart();
    request.camera = &sf.gbuffer();
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
    const std::int64_t nonfinite = count_nonfinite(out.receiver, nullptr) + count_nonfinite(out.camera, &g.covered);
    json health = json::object();
    for (const auto& [name, value] : out.health.counters) health[name] = value;
    health["nonfinite_pixels"] = nonfinite;
    j["health"] = health;
    // What the method claims on this frame (Method::accuracy_claim); `met` is filled once the error is known.
    const AccuracyClaim claim = method->accuracy_claim(sf.geometry());
    j["claim"] = {{"inside", claim.inside},
                  {"error_vs_baseline", claim.inside ? json_number(claim.error_vs_baseline) : json(nullptr)},
                  {"reason", claim.inside ? json(nullptr) : json(claim.reason)},
                  {"met", nullptr}};
    if (!claim.inside) messages.push_back("outside the method's claimed regime: " + claim.reason);
    const bool unstable = nonfinite > 0 || out.health.get("nonfinite") > 0;
    run.status = unstable ? "unstable" : "ok";
    if (unstable)
        messages.push_back("non-finite output (" + std::to_string(nonfinite) + " pixels, method counter " +
                           std::to_string(out.health.get("nonfinite")) + "): error not measured");
    if (out.receiver.empty()) messages.push_back("method produced no receiver map");
    if (out.camera.empty()) messages.push_back("method produced no camera view");

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
                // against the claimed multiple of the baseline's; exact truths only (a noisy one is judged by
                // the net error's interval, which the report shows), and only where there is a caustic to
                // judge (a flat interface within 0.1 % of the truth leaves no multiple of its error to ask).
                if (claim.inside && e.have_baseline && truth.exact() && e.baseline_error > 1e-3) {
                    const char* key = info.radiometric_at(m.params) ? "nrmse" : "nrmse_fit";
                    if (e.json.contains(key) && e.json[key].is_number())
                        j["claim"]["met"] = e.json[key].get<double>() <= claim.error_vs_baseline * e.baseline_error;
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

void write_render_outputs(const std::string& dir, const SceneFrame& sf, const RenderRun& run,
                          const RenderOptions& options) {
    fs::create_directories(dir);
    const fs::path d(dir);
    if (run.status != "skipped") {
        const CausticOutput& out = run.output;
        if (!out.receiver.empty()) write_exr(out.receiver, (d / "receiver.exr").string());
        if (!out.receiver_rgb.empty()) write_exr(out.receiver_rgb, (d / "receiver_rgb.exr").string());
        if (!out.camera.empty()) {
            // Only covered pixels carry a value; the rest is written as 0.
            Image camera = out.camera;
            const auto& covered = sf.gbuffer().covered;
            for (std::size_t p = 0; p < covered.size(); ++p)
                if (!covered[p]) camera.pixels[p] = 0.0f;
            write_exr(camera, (d / "camera.exr").string());
        }
        for (const auto& [name, image] : out.debug)
            if (!image.empty() && (image.channels == 1 || image.channels == 3))
                write_exr(image, (d / ("debug_" + name + ".exr")).string());
        if (options.beauty) {
            BeautyInputs in;
            in.gbuffer = &sf.gbuffer();
            in.camera_ec = &out.camera;
            in.chart = &sf.chart();
            in.receiver_ec = &out.receiver;
            write_beauty_png(render_beauty(sf.tracer(), in), (d / "beauty.png").string());
        }
    }
    // metrics.json last: its presence says the run's files are complete.
    write_text_atomic((d / "metrics.json").string(), run.metrics.dump(2) + "\n");
}

RenderRun run_render(const RenderOptions& options) {
    ThreadLimit limit(options.threads);
    // Every InputError comes from these three steps, before anything is written.
    Scene scene = load_scene(resolve_scene_path(options.scene_path));
    const ResolvedMethod method = resolve_method(options.method, options.overrides);
    const SceneFrame sf(std::move(scene), options.frame);

    std::optional<ReferenceResult> reference;
    ReferenceProvider provider;
    if (!options.no_reference)
        provider = [&]() -> const ReferenceResult* {
            reference = reference_for(sf, options);
            return &*reference;
        };
    RenderRun run = run_method(sf, method, options, provider);
    if (!options.out_dir.empty()) write_render_outputs(options.out_dir, sf, run, options);
    return run;
}

// ---------------------------------------------------------------------------------------------------

nlohmann::json reference_summary_json(const ReferenceResult& ref) {
    return {{"photons", ref.photons},
            {"noise_nrmse", json_number(ref.noise_nrmse)},
            {"noise_nrmse_camera", json_number(ref.noise_nrmse_camera)},
            {"cache_key", ref.cache_key},
            {"sampler", sampler_name(ref.sampler)},
            {"replicas", ref.replicas},
            {"noise_target", ref.noise_target > 0.0 ? json_number(ref.noise_target) : json(nullptr)},
            {"noise_target_met", ref.noise_target > 0.0 ? json(ref.noise_target_met) : json(nullptr)}};
}

nlohmann::json reference_json(const Scene& scene, int frame, const ReferenceResult& ref) {
    const FluxLedger& l = ref.ledger;
    json j = reference_summary_json(ref);
    j["scene"] = scene.name;
    j["scene_path"] = scene.path;
    j["frame"] = frame;
    j["seed"] = ref.seed;
    j["rounds"] = ref.rounds;
    j["round_photons"] = ref.round_photons;
    json noise = json::array();
    for (double v : ref.round_noise) noise.push_back(json_number(v));
    j["round_noise"] = noise;
    j["photons_traced"] = ref.photons_traced;
    j["seconds"] = json_number(ref.seconds);
    j["from_cache"] = ref.from_cache;
    j["photons_per_second"] = ref.seconds > 0.0 ? json_number(static_cast<double>(ref.photons) / ref.seconds)
                                                : json(nullptr);
    j["receiver"] = {{"object", scene.receiver.object}, {"width", ref.receiver.width}, {"height", ref.receiver.height}};
    j["camera"] = {{"width", ref.camera.width}, {"height", ref.camera.height}};
    j["ledger"] = {{"emitted", l.emitted},
                   {"deposited_receiver", l.deposited_receiver},
                   {"deposited_other", l.deposited_other},
                   {"direct", l.direct},
                   {"escaped", l.escaped},
                   {"absorbed", l.absorbed},
                   {"truncated", l.truncated},
                   {"accounted", l.accounted()},
                   {"relative_imbalance",
                    l.emitted > 0.0 ? json_number((l.accounted() - l.emitted) / l.emitted) : json(nullptr)}};
    j["build_type"] = CAUSTICS_BUILD_TYPE;
    j["threads"] = ThreadLimit::effective();
    return j;
}

void write_reference_outputs(const std::string& dir, const Scene& scene, int frame, const ReferenceResult& ref) {
    fs::create_directories(dir);
    const fs::path d(dir);
    if (!ref.receiver.empty()) write_exr(ref.receiver, (d / "reference_receiver.exr").string());
    if (!ref.camera.empty()) write_exr(ref.camera, (d / "reference_camera.exr").string());
    if (!ref.receiver_stderr.empty()) write_exr(ref.receiver_stderr, (d / "reference_stderr.exr").string());
    if (!ref.camera_stderr.empty()) write_exr(ref.camera_stderr, (d / "reference_camera_stderr.exr").string());
    write_text_atomic((d / "reference.json").string(), reference_json(scene, frame, ref).dump(2) + "\n");
}

// ---------------------------------------------------------------------------------------------------

struct ThreadLimit::Impl {
    std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int threads) : impl_(std::make_unique<Impl>()) {
    if (threads > 0)
        impl_->control = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                               static_cast<std::size_t>(threads));
}

ThreadLimit::~ThreadLimit() = default;

int ThreadLimit::effective() {
    return static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace caustics
