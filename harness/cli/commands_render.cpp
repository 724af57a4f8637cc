// caustics render SCENE --method NAME [--set KEY=VALUE]... [--frame F] [--out DIR] [--no-reference]
//                [--photons N] [--warmup W] [--repeats R] [--threads T] [--seed S] [--cache DIR]
//                [--sampler S] [--replicas R] [--noise-target X] [--photon-cap N] [--truth T]
//                [--timing-precision P] [--max-time S]
#include <filesystem>
#include <iostream>
#include <memory>

#include "command.hpp"
#include "render_command.hpp"
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene_catalog.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

struct RenderArgs {
    RenderOptions options;
    std::vector<std::string> sets;
};

std::string value_text(const nlohmann::json& v) {
    if (v.is_null()) return "n/a";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", v.get<double>());
    return buf;
}

int run_render_command(RenderArgs a, LoadedFrame* kept) {
    RenderOptions& o = a.options;
    o.overrides = parse_assignments(a.sets, "--set");
    if (o.out_dir.empty()) {
        // The default output folder is checked like a given --out, before any work.
        o.out_dir = (fs::path("results") / "render" / fs::path(resolve_scene_path(o.scene_path)).stem() / o.method)
                        .string();
        check_output_folder("--out", o.out_dir);
    }
    const RenderRun run = run_render(o, kept);
    const nlohmann::json& m = run.metrics;
    std::cout << m["method"].get<std::string>() << " on " << m["scene"].get<std::string>() << " frame "
              << m["frame"].get<int>() << ": " << status_name(run.status);
    if (run.status != RunStatus::Skipped) {
        std::cout << ", frame " << value_text(m["frame_ms"]["median"]) << " ms (" << m["frame_time"].get<std::string>()
                  << ", " << value_text(m["fps"]) << " fps, " << m["threads"].get<int>() << " threads)";
        if (run.have_reference) {
            const bool fit = !m["radiometric"].get<bool>();
            const auto& e = m["error"]["receiver"];
            const std::string key = fit ? "nrmse_fit_net" : "nrmse_net";
            std::cout << ", receiver " << key << " " << value_text(e[key]) << " [" << value_text(e[key + "_lo"]) << ", "
                      << value_text(e[key + "_hi"]) << "] against " << m["truth"]["kind"].get<std::string>()
                      << " (noise " << value_text(m["truth"]["noise_nrmse"]) << "), baseline "
                      << value_text(m["baseline"]["error"]);
        }
    }
    std::cout << "\n";
    if (!run.message.empty()) std::cout << "  " << run.message << "\n";
    std::cout << "wrote " << o.out_dir << "/metrics.json\n";
    return 0;
}

Command make_render_command() {
    Command c;
    c.name = kRenderName;
    c.summary = kRenderSummary;
    c.order = 30;
    c.setup = [](CLI::App& app) { return setup_render(app, nullptr); };
    return c;
}

}  // namespace

const char* const kRenderName = "render";
const char* const kRenderSummary =
    "Time one method on a scene frame, measure it against the reference, write images and metrics.json";

std::function<int()> setup_render(CLI::App& app, LoadedFrame* kept) {
    auto a = std::make_shared<RenderArgs>();
    RenderOptions& o = a->options;
    add_scene_argument(app, o.scene_path, "Scene file, or a scene name in scenes/ (e.g. sine)")->required();
    add_method_option(app, o.method, "Method name (see caustics list)")->required();
    add_assignment_option(app, "--set", a->sets, "Method parameter KEY=VALUE (repeatable, each KEY once)");
    add_frame_option(app, o.frame);
    add_output_folder_option(app, "--out", o.out_dir, "Output folder (default results/render/<scene>/<method>)");
    app.add_flag("--no-reference", o.no_reference, "Do not compute the reference; error values are null");
    add_integer_option(app, "--warmup", o.warmup, 0, kMaxWarmup, "Untimed renders before timing")->capture_default_str();
    add_integer_option(app, "--repeats", o.repeats, 1, kMaxRepeats, "Timed renders at least")->capture_default_str();
    add_threads_option(app, o.threads, "Worker threads (0: all cores)");
    add_cache_option(app, o.cache_dir);
    add_reference_options(app, o.reference);
    add_choice_option(app, "--truth", o.truth, {"auto", "analytic", "reference"},
                      "Receiver ground truth: auto (the analytic closed form where the scene has one, else the "
                      "reference), analytic (say so where there is none) or reference")
        ->capture_default_str();
    add_number_option(app, "--timing-precision", o.timing_precision, 0.001, 1.0,
                      "Time frames until the median's 95 % interval is within this relative half-width")
        ->capture_default_str();
    add_number_option(app, "--max-time", o.timing_max_s, 0.0, 3600.0,
                      "Time cap of the timed frames in seconds (then flagged noisy_timing)")
        ->capture_default_str();
    return [a, kept]() { return run_render_command(*a, kept); };
}

CAUSTICS_REGISTER_COMMAND(make_render_command);

}  // namespace caustics::cli
