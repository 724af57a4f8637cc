#pragma once
// The metrics.json document of one run (DESIGN.md section 7): its skeleton and JSON helpers.
#include <nlohmann/json.hpp>

#include <caustics/run/render_options.hpp>
#include <caustics/run/resolved_method.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {

// JSON number, or null when not finite (metrics.json never holds NaN or Inf).
nlohmann::json json_number(double v);

// metrics.json's timing block of one timed section (all null for none).
nlohmann::json timing_json(const TimingSummary* t);

// The metrics.json skeleton: every key of DESIGN.md section 7, values null until measured.
nlohmann::json metrics_skeleton(const SceneFrame& sf, const ResolvedMethod& m, const RenderOptions& options);

}  // namespace caustics
