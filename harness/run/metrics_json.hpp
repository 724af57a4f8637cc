#pragma once
// The metrics.json document of one run (docs/design.md section 7): its skeleton and JSON helpers.
#include <nlohmann/json.hpp>

#include <caustics/api/method.hpp>
#include <caustics/run/render_options.hpp>
#include <caustics/run/resolved_method.hpp>
#include <caustics/run/run_record.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {

// JSON number, or null when not finite (metrics.json never holds NaN or Inf).
nlohmann::json json_number(double v);

// metrics.json's timing block of one timed section (all null for none).
// `samples_ms`: every timed frame, written to the microsecond (empty where not timed).
nlohmann::json timing_json(const TimingSummary* t, const std::vector<double>& samples_ms = {});

// The timed region's keys of metrics.json (time_ms, frame_ms, frame_time, fps, render_fps, noisy_timing,
// prepare_ms, update_ms, stages_ms, repeats) from the typed record.
void timing_to_json(const RunTiming& t, nlohmann::json& j);

// metrics.json's claim block: inside, max_error (the stated absolute nrmse), bound (the error the run is held
// to once the baseline's is known: null until then), reason (outside only), bounds (the regime's quantities
// with this frame's values and limits) and met (null until judged against an exact truth).
nlohmann::json claim_json(const AccuracyClaim& claim);

// The metrics.json skeleton: every key of docs/design.md section 7, values null until measured.
nlohmann::json metrics_skeleton(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options);

}  // namespace caustics
