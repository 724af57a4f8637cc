// caustics reference SCENE [--photons N] [--frame F] [--out DIR] [--threads T] [--seed S] [--cache DIR]
//                          [--sampler S] [--replicas R] [--noise-target X] [--photon-cap N]
#include <filesystem>
#include <iostream>
#include <memory>

#include "command.hpp"
#include <caustics/reference/reference.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene_catalog.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

struct ReferenceArgs {
    std::string scene;
    int frame = 0;
    std::string out;
    int threads = 0;
    std::string cache;
    ReferenceSettings reference;
};

int run_reference(const ReferenceArgs& a) {
    const std::string path = resolve_scene_path(a.scene);
    // The default output folder is checked like a given --out, before any work.
    const std::string out = a.out.empty() ? (fs::path("results") / "reference" / fs::path(path).stem() /
                                             ("frame" + std::to_string(a.frame))).string()
                                          : a.out;
    if (a.out.empty()) check_output_folder("--out", out);
    ThreadLimit limit(a.threads);
    Scene scene = load_scene(path);
    const SceneFrame sf(std::move(scene), a.frame);
    RenderOptions options;
    options.reference = a.reference;
    options.threads = a.threads;
    options.cache_dir = a.cache;
    const ReferenceResult ref = reference_for(sf, options);
    write_reference_outputs(out, sf.scene(), a.frame, ref);
    std::cout << "reference " << sf.scene().name << " frame " << a.frame << ": " << ref.photons << " photons, "
              << (ref.from_cache ? "from cache" : std::to_string(ref.seconds) + " s") << ", noise_nrmse "
              << ref.noise_nrmse << ", flux emitted " << ref.ledger.emitted << " W, on receiver "
              << ref.ledger.deposited_receiver << " W\n";
    if (ref.noise_target > 0.0)
        std::cout << "noise target " << ref.noise_target << (ref.noise_target_met ? " met" : " NOT met (photon cap reached)")
                  << " after " << ref.rounds << " round(s)\n";
    std::cout << "wrote " << out << "/reference.json\n";
    return 0;
}

Command make_reference_command() {
    Command c;
    c.name = "reference";
    c.summary = "Compute (or load from the cache) the Embree reference of a scene frame and write its files";
    c.order = 20;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto a = std::make_shared<ReferenceArgs>();
        add_scene_argument(app, a->scene, "Scene file, or a scene name in scenes/ (e.g. pool)")->required();
        add_frame_option(app, a->frame);
        add_output_folder_option(app, "--out", a->out, "Output folder (default results/reference/<scene>/frame<F>)");
        add_threads_option(app, a->threads, "Worker threads (0: all cores)");
        add_cache_option(app, a->cache);
        add_reference_options(app, a->reference);
        return [a]() { return run_reference(*a); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_reference_command);

}  // namespace caustics::cli
