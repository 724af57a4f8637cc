#pragma once
// The plan a sweep folder records (manifest.json "plan", "plan_hash"): everything that decides what its
// runs measure and against what, so that --resume continues a sweep only with the plan it was started
// with.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/scene/scene.hpp>
#include <caustics/sweep/sweep_spec.hpp>

namespace caustics::sweep_plan {

// The scene file's bytes and every asset's bytes: an edited scene is another plan.
std::string scene_content_hash(const Scene& scene);

// Everything that decides what a run measures and against what: per scene (by name) its file contents,
// frames, reference noise target and truth; the reference settings; the timing protocol (with the
// per-run time limit and threads in effect); every method's axis values; and the runs themselves (count
// and a hash of every run's id, scene, frame, method and parameters). Not the description, the report
// settings, the spec's file name or folder, the cache folder: those may change on --resume.
nlohmann::json sweep_plan(const SweepSpec& spec, const std::vector<PlannedRun>& runs,
                          const std::vector<std::string>& scene_hashes, int threads, double timeout_s);

std::string plan_hash(const nlohmann::json& plan);

// For --resume: the folder's manifest when the sweep in it was started with this plan (an empty object
// when the folder holds no sweep yet); throws InputError naming what differs otherwise, or when the folder
// holds results whose plan cannot be told. Reads only.
nlohmann::json check_resume(const std::filesystem::path& dir, const nlohmann::json& plan, const SweepSpec& spec);

}  // namespace caustics::sweep_plan
