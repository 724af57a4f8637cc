#pragma once
// The reference of a run: its settings from the run's options (one place for that rule), the cached
// computation, and the files and JSON that describe it.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/reference/reference.hpp>
#include <caustics/run/render_options.hpp>
#include <caustics/run/scene_frame.hpp>

namespace caustics {

// The reference settings the options ask for: options.reference with the run's threads and progress.
ReferenceSettings reference_settings(const RenderOptions& options);
// The `caustics render` arguments that ask for `settings` (--photons, --seed, --sampler, --replicas,
// --noise-target, --photon-cap), for a parent that starts runs as child processes.
std::vector<std::string> reference_arguments(const ReferenceSettings& settings);
// The reference for a scene frame with the options' settings and cache folder.
ReferenceResult reference_for(const SceneFrame& sf, const RenderOptions& options);

// reference_receiver.exr, reference_camera.exr, reference_stderr.exr (receiver standard error) and
// reference.json (photons, seed, noise, cache key, flux ledger, timing).
nlohmann::json reference_json(const Scene& scene, int frame, const ReferenceResult& ref);
// metrics.json's `reference` block: photons, noise, cache key, sampler, replicas, noise target and whether met.
nlohmann::json reference_summary_json(const ReferenceResult& ref);
void write_reference_outputs(const std::string& dir, const Scene& scene, int frame, const ReferenceResult& ref);

}  // namespace caustics
