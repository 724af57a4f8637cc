#include <caustics/run/run_reference.hpp>

#include <cstdio>
#include <filesystem>

#include <caustics/run/metrics_json.hpp>
#include <caustics/run/thread_limit.hpp>
#include <caustics/util/build_info.hpp>
#include <caustics/util/image_io.hpp>

namespace caustics {

namespace fs = std::filesystem;
using nlohmann::json;

ReferenceSettings reference_settings(const RenderOptions& options) {
    ReferenceSettings settings = options.reference;
    settings.threads = options.threads;
    settings.camera_view = true;
    settings.progress = options.progress;
    return settings;
}

std::vector<std::string> reference_arguments(const ReferenceSettings& s) {
    char target[40];
    std::snprintf(target, sizeof target, "%.17g", s.noise_target);   // exact: the child reads the same double
    return {"--photons", std::to_string(s.photons), "--seed", std::to_string(s.seed), "--sampler", sampler_name(s.sampler),
            "--replicas", std::to_string(s.replicas), "--noise-target", target, "--photon-cap",
            std::to_string(s.photon_cap)};
}

ReferenceResult reference_for(const SceneFrame& sf, const RenderOptions& options) {
    const ReferenceSettings settings = reference_settings(options);
    const std::string cache = options.cache_dir.empty() ? default_cache_dir() : options.cache_dir;
    return load_or_compute_reference(sf.geometry(), sf.tracer(), sf.chart(), &sf.gbuffer(), settings, cache);
}

nlohmann::json reference_summary_json(const ReferenceResult& ref) {
    return {{"photons", ref.photons},
            {"noise_nrmse", json_number(ref.noise_nrmse)},
            {"noise_nrmse_camera", json_number(ref.noise_nrmse_camera)},
            {"noise_nrmse_volume", ref.camera_volume.empty() ? json(nullptr) : json_number(ref.noise_nrmse_volume)},
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
    j["camera_volume"] = {{"measured", !ref.camera_volume.empty()}};
    j["ledger"] = {{"emitted", l.emitted},
                   {"deposited_receiver", l.deposited_receiver},
                   {"deposited_other", l.deposited_other},
                   {"direct", l.direct},
                   {"escaped", l.escaped},
                   {"absorbed", l.absorbed},
                   {"scattered", l.scattered},
                   {"truncated", l.truncated},
                   {"accounted", l.accounted()},
                   {"relative_imbalance",
                    l.emitted > 0.0 ? json_number((l.accounted() - l.emitted) / l.emitted) : json(nullptr)}};
    j["build_type"] = build_type();
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
    if (!ref.camera_volume.empty()) {
        write_exr(ref.camera_volume, (d / "reference_camera_volume.exr").string());
        write_exr(ref.camera_volume_stderr, (d / "reference_camera_volume_stderr.exr").string());
    }
    write_text_atomic((d / "reference.json").string(), reference_json(scene, frame, ref).dump(2) + "\n");
}

}  // namespace caustics
