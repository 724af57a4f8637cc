// caustics synth SCENE --method NAME [--frames 32] [--out DIR] [--set KEY=VALUE]... [--size 512]
//                [--depth D] [--threads T] [--no-gif]
#include <filesystem>
#include <iostream>
#include <memory>

#include "command.hpp"
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/synth/synth.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

struct SynthArgs {
    SynthOptions options;
    std::vector<std::string> sets;
    bool no_gif = false;
};

int run_synth_command(SynthArgs a) {
    SynthOptions& o = a.options;
    o.overrides = parse_assignments(a.sets, "--set");
    o.gif = !a.no_gif;
    if (o.out_dir.empty()) {
        // The default output folder is checked like a given --out, before any work.
        o.out_dir = (fs::path("results") / "synth" / fs::path(resolve_scene_path(o.scene_path)).stem() / o.method).string();
        check_output_folder("--out", o.out_dir);
    }
    const SynthResult r = run_synth(o);
    const auto& m = r.manifest;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d frames of %d x %d over a %.4g s period, depth %.4g m: %.1f ms total (median %.2f ms/frame, %d threads)",
                  m["frames"].get<int>(), m["size"][0].get<int>(), m["size"][1].get<int>(), m["period"].get<double>(),
                  m["depth"].get<double>(), r.total_ms, m["timing"]["frame_ms"]["median"].get<double>(),
                  m["threads"].get<int>());
    std::cout << m["method"].get<std::string>() << " on " << m["scene"].get<std::string>() << ": " << buf << "\n";
    if (m["files"].contains("preview_gif_skipped"))
        std::cout << "  no preview.gif: " << m["files"]["preview_gif_skipped"].get<std::string>() << "\n";
    std::cout << "wrote " << o.out_dir << "/manifest.json\n";
    return 0;
}

Command make_synth_command() {
    Command c;
    c.name = "synth";
    c.summary = "Synthesise caustic textures that tile in space and loop in time (Stam's periodic caustic textures)";
    c.order = 35;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto a = std::make_shared<SynthArgs>();
        SynthOptions& o = a->options;
        add_scene_argument(app, o.scene_path, "Scene file, or a scene name in scenes/ (e.g. ocean_tile); its water "
                                              "surface must use the periodic 'noise' generator")->required();
        add_method_option(app, o.method, "Method name; it must synthesise periodic textures (one that cannot is refused with its reason)")
            ->required();
        add_integer_option(app, "--frames", o.frames, 1, 10000, "Frames per time period (frame i at time i * period / frames)")
            ->capture_default_str();
        add_integer_option(app, "--size", o.size, 8, 8192, "Texture width in pixels (height follows the tile's aspect)")
            ->capture_default_str();
        add_number_option(app, "--depth", o.depth, 0.0, 1000.0,
                          "Texture plane depth below the water's base height [m] (default: the receiver's)",
                          "0: the receiver's depth");
        add_assignment_option(app, "--set", a->sets, "Method parameter KEY=VALUE (repeatable, each KEY once)");
        add_output_folder_option(app, "--out", o.out_dir, "Output folder (default results/synth/<scene>/<method>)");
        add_threads_option(app, o.threads, "Worker threads (0: all cores)");
        app.add_flag("--no-gif", a->no_gif, "Do not write preview.gif (the PNG frames are the preview)");
        return [a]() { return run_synth_command(*a); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_synth_command);

}  // namespace caustics::cli
