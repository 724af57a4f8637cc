#pragma once
// The typed record of one run (run_method, render_run.hpp): what the harness decided and measured, kept as
// data until metrics.json is written (metrics_json.hpp serialises it at the edge).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <caustics/api/method.hpp>
#include <caustics/run/render_options.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/run/view_table.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {

enum class RunStatus {
    Ok,         // rendered with finite output
    Skipped,    // the method does not support the scene (Capability::no)
    Unstable,   // rendered, with non-finite output: its error is not measured
};
// "ok", "skipped", "unstable" (metrics.json's and results.csv's status).
const char* status_name(RunStatus status);

// The timed region (docs/design.md section 6): prepare, update, the warm-up renders untimed, then timed
// frames until the timing policy stops.
struct RunTiming {
    TimingSummary render;                      // render() per frame
    TimingSummary frame;                       // update + render (animated scenes) or render
    bool animated = false;                     // the frame's geometry changes: update() is timed per frame
    bool capped = false;                       // stopped by the time cap before the median was precise
    double prepare_ms = 0.0;
    double update_ms = 0.0;                    // median per frame (animated) or the one update
    std::map<std::string, double> stages_ms;   // the method's stages, median per frame
    int repeats = 0;                           // timed frames
    // Every timed frame's render and frame time in order (metrics.json's time_ms.samples and
    // frame_ms.samples), so that two runs can be compared by a test on their samples, not only medians.
    std::vector<double> render_samples_ms, frame_samples_ms;
};

// Times `method` on the frame; `last` receives the last timed render's output (the previous one is freed
// outside the timed region).
RunTiming time_method(Method& method, const SceneFrame& sf, const RenderRequest& request, const RenderOptions& options,
                      CausticOutput& last);

// The output's shape and finiteness over the view table's rows (view_table.hpp): the harness counts
// non-finite values itself (never averaged in) and names requested views the method did not produce.
// Throws when an image has the wrong size.
struct OutputCheck {
    std::int64_t nonfinite = 0;          // over the pixels each view reads
    bool unstable = false;               // non-finite values, or the method's own `nonfinite` counter
    std::vector<std::string> messages;   // non-finite output, missing views
};
OutputCheck check_output(const CausticOutput& out, const SceneFrame& sf, const std::string& method);

}  // namespace caustics
