// caustics render SCENE --method NAME [--set KEY=VALUE]... [--frame F] [--out DIR] [--no-reference]
//                [--photons N] [--warmup W] [--repeats R] [--threads T] [--seed S] [--cache DIR]
#include <filesystem>
#include <iostream>
#include <memory>

#include "command.hpp"
#include "render_run.hpp"

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

int run_render_command(RenderArgs a) {
    RenderOptions& o = a.options;
    o.overrides = parse_assignments(a.sets, "--set");
    if (o.out_dir.empty())
        o.out_dir = (fs::path("results") / "render" / fs::path(resolve_scene_path(o.scene_path)).stem() / o.method)
                        .string();
    const RenderRun run = run_render(o);
    const nlohmann::json& m = run.metrics;
    std::cout << m["method"].get<std::string>() << " on " << m["scene"].get<std::string>() << " frame "
              << m["frame"].get<int>() << ": " << run.status;
    if (run.status != "skipped") {
        std::cout << ", median " << value_text(m["time_ms"]["median"]) << " ms (" << value_text(m["fps"])
                  << " fps, " << m["threads"].get<int>() << " threads)";
        if (run.have_reference) {
            const bool fit = !m["radiometric"].get<bool>();
            const auto& e = m["error"]["receiver"];
            std::cout << ", receiver " << (fit ? "nrmse_fit " : "nrmse ") << value_text(fit ? e["nrmse_fit"] : e["nrmse"])
                      << " (reference noise " << value_text(m["reference"]["noise_nrmse"]) << ")";
        }
    }
    std::cout << "\n";
    if (!run.message.empty()) std::cout << "  " << run.message << "\n";
    std::cout << "wrote " << o.out_dir << "/metrics.json\n";
    return 0;
}

Command make_render_command() {
    Command c;
    c.name = "render";
    c.summary = "Time one method on a scene frame, measure it against the reference, write images and metrics.json";
    c.order = 30;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto a = std::make_shared<RenderArgs>();
        RenderOptions& o = a->options;
        app.add_option("scene", o.scene_path, "Scene file, or a scene name in scenes/ (e.g. sine)")->required();
        app.add_option("--method", o.method, "Method name (see caustics list)")->required();
        app.add_option("--set", a->sets, "Method parameter KEY=VALUE (repeatable)")
            ->expected(1)
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        app.add_option("--frame", o.frame, "Animation frame")->check(CLI::NonNegativeNumber)->capture_default_str();
        app.add_option("--out", o.out_dir, "Output folder (default results/render/<scene>/<method>)");
        app.add_flag("--no-reference", o.no_reference, "Do not compute the reference; error values are null");
        app.add_option("--photons", o.photons, "Reference photons")->check(CLI::PositiveNumber)->capture_default_str();
        app.add_option("--warmup", o.warmup, "Untimed renders before timing")->check(CLI::NonNegativeNumber)->capture_default_str();
        app.add_option("--repeats", o.repeats, "Timed renders")->check(CLI::PositiveNumber)->capture_default_str();
        app.add_option("--threads", o.threads, "Worker threads (0: all cores)")->check(CLI::NonNegativeNumber);
        app.add_option("--seed", o.seed, "Reference photon RNG seed")->capture_default_str();
        app.add_option("--cache", o.cache_dir, "Reference cache folder (default $CAUSTICS_CACHE_DIR or results/cache)");
        return [a]() { return run_render_command(*a); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_render_command);

}  // namespace caustics::cli
