#pragma once
// The pipeline behind `caustics render` (docs/design.md sections 6 and 7), reusable by the sweep runner:
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
#include <caustics/run/metrics_json.hpp>
#include <caustics/run/render_options.hpp>
#include <caustics/run/resolved_method.hpp>
#include <caustics/run/run_record.hpp>
#include <caustics/run/run_reference.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/run/thread_limit.hpp>

namespace caustics {


// One run's record: the typed decisions and timings (run_record.hpp), and the metrics.json document they are
// serialised into with the error blocks (docs/design.md section 7).
struct RenderRun {
    RunStatus status = RunStatus::Ok;
    std::string message;           // every note of the run, "; "-separated
    RunTiming timing;              // supported runs only
    AccuracyClaim claim;           // supported runs only
    nlohmann::json metrics;        // the metrics.json document
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

// Writes DIR/receiver.exr, DIR/camera.exr, DIR/beauty.png (when options.beauty), DIR/metrics.json and
// any debug images (DIR/debug_<name>.exr).
void write_render_outputs(const std::string& dir, const SceneFrame& sf, const RenderRun& run,
                          const RenderOptions& options);

struct LoadedFrame;
// The whole `caustics render`: every InputError is thrown before anything is written. `kept` (may be null):
// the scene frame and reference a process that renders many runs keeps between them (below).
RenderRun run_render(const RenderOptions& options, LoadedFrame* kept = nullptr);

// What a process that renders many runs in sequence (the sweep worker, sweep/worker.hpp) keeps between
// them: the scene frame of its last run (by resolved scene path and frame) and the reference of its last
// reference settings and cache folder. run_render, given one, loads, builds or reads only what differs from the last run. The results are the same as a fresh
// process's: the scene frame is built from the same file by the same deterministic code, and a cached
// reference is rebuilt from the integer sums the cache stores (reference.hpp), the same values every time
// it is read. A scene file edited while the store holds it is not noticed: a sweep fixes its scenes'
// contents when it starts (its plan hashes them).
struct LoadedFrame {
    std::string scene_key;                 // resolved scene path and frame
    std::unique_ptr<SceneFrame> frame;
    std::string reference_key;             // reference settings and cache folder
    std::unique_ptr<ReferenceResult> reference;
};

}  // namespace caustics
