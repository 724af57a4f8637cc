#pragma once
// The `render` command's options and action, shared by `caustics render` and the sweep worker, which
// renders its runs with the scene frame and reference of the previous run kept (run/render_run.hpp).
#include <functional>

#include <CLI/CLI.hpp>

#include <caustics/run/render_run.hpp>

namespace caustics::cli {

extern const char* const kRenderName;
extern const char* const kRenderSummary;

// Declares the render options on `app`; the returned action renders with `kept` (may be null).
std::function<int()> setup_render(CLI::App& app, LoadedFrame* kept);

}  // namespace caustics::cli
