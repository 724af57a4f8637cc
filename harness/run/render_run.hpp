#pragma once
// The pipeline behind `caustics render` (DESIGN.md sections 6 and 7), reusable by the sweep runner:
// load scene -> resolve method and parameters (every InputError before any output is written) ->
// frame geometry, RayTracer, ReceiverChart, camera G-buffer -> capabilities -> create, prepare (timed),
// update (timed), warm-up renders, timed repeats -> reference (cached; never inside a timed region) ->
// metrics, health, status -> files (all written atomically).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

struct RenderOptions {
    std::string scene_path;
    std::string method;
    std::map<std::string, std::string> overrides;   // --set KEY=VALUE
    int frame = 0;
    std::string out_dir;                            // empty: write no files
    int warmup = 3;
    int repeats = 10;                               // timed frames at least (then until precise or capped)
    double timing_precision = 0.05;                 // relative half-width of the median's 95 % interval
    double timing_max_s = 3.0;                      // time cap of the timed frames [s]
    std::uint64_t photons = 4'000'000;              // reference photons (the first round with a noise target)
    std::uint64_t seed = 1;                         // reference seed
    SamplerKind sampler = SamplerKind::Sobol;       // reference sampler
    int replicas = ReferenceSettings::kDefaultReplicas;
    double noise_target = 0.0;                      // > 0: reference photons until noise_nrmse <= target
    std::uint64_t photon_cap = ReferenceSettings::kDefaultPhotonCap;
    std::string truth = "auto";                     // receiver truth: auto | analytic | reference
    bool no_reference = false;                      // skip the reference: error values are null
    std::string cache_dir;                          // reference cache; empty: default_cache_dir()
    int threads = 0;                                // 0: every core
    bool beauty = true;                             // render beauty.png when writing files
    bool progress = true;                           // reference progress bar on stderr
};

// Everything about one (scene, frame) that does not depend on the method. Neither copyable nor
// movable: the frame geometry, tracer and chart point into it.
class SceneFrame {
public:
    SceneFrame(Scene scene, int frame);   // throws InputError for a frame out of range
    SceneFrame(const SceneFrame&) = delete;
    SceneFrame& operator=(const SceneFrame&) = delete;

    const Scene& scene() const { return scene_; }
    const FrameGeometry& geometry() const { return geometry_; }
    const RayTracer& tracer() const { return *tracer_; }
    const ReceiverChart& chart() const { return *chart_; }
    const CameraGBuffer& gbuffer() const { return gbuffer_; }

private:
    Scene scene_;
    FrameGeometry geometry_;
    std::unique_ptr<RayTracer> tracer_;
    std::unique_ptr<ReceiverChart> chart_;
    CameraGBuffer gbuffer_;
};

struct ResolvedMethod {
    const MethodInfo* info = nullptr;
    ParamSet params;
};
// require_method + ParamSet::resolve: InputError for an unknown method, key or value.
ResolvedMethod resolve_method(const std::string& name, const std::map<std::string, std::string>& overrides);

struct RenderRun {
    std::string status;            // "ok", "skipped" (unsupported scene), "unstable" (non-finite output)
    std::string message;
    nlohmann::json metrics;        // the metrics.json document (DESIGN.md section 7)
    CausticOutput output;          // the last timed render's output
    bool have_reference = false;   // error values were measured against a reference
};

// Called by run_method after the timed region, only for supported runs; returns the reference of the
// same scene frame, or null for none. Lets a caller compute it lazily or share a cached one.
using ReferenceProvider = std::function<const ReferenceResult*()>;

// Times the method on the scene frame and measures it against the provided reference (an empty
// provider: no reference). Writes nothing. Thread limits are the caller's (see ThreadLimit).
RenderRun run_method(const SceneFrame& sf, const ResolvedMethod& method, const RenderOptions& options,
                     const ReferenceProvider& reference);

// The reference settings the options ask for (photons, seed, sampler, replicas, noise target, threads).
ReferenceSettings reference_settings(const RenderOptions& options);
// The reference for a scene frame with the options' settings and cache folder.
ReferenceResult reference_for(const SceneFrame& sf, const RenderOptions& options);

// Writes DIR/receiver.exr, DIR/camera.exr, DIR/beauty.png (when options.beauty), DIR/metrics.json and
// any debug images (DIR/debug_<name>.exr).
void write_render_outputs(const std::string& dir, const SceneFrame& sf, const RenderRun& run,
                          const RenderOptions& options);

// The whole `caustics render`: every InputError is thrown before anything is written.
RenderRun run_render(const RenderOptions& options);

// reference_receiver.exr, reference_camera.exr, reference_stderr.exr (receiver standard error) and
// reference.json (photons, seed, noise, cache key, flux ledger, timing).
nlohmann::json reference_json(const Scene& scene, int frame, const ReferenceResult& ref);
// metrics.json's `reference` block: photons, noise, cache key, sampler, replicas, noise target and whether met.
nlohmann::json reference_summary_json(const ReferenceResult& ref);
void write_reference_outputs(const std::string& dir, const Scene& scene, int frame, const ReferenceResult& ref);

// Limits TBB to `threads` workers for its lifetime (0: no limit) and reports the effective count.
class ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;
    static int effective();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The resolved parameters as typed JSON (ints, numbers, booleans, strings): metrics.json's `params`.
nlohmann::json params_json(const MethodInfo& info, const ParamSet& params);

// JSON number, or null when not finite (metrics.json never holds NaN or Inf).
nlohmann::json json_number(double v);

}  // namespace caustics
