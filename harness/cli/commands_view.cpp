// caustics view SCENE [--method NAME] [--set KEY=VALUE]... [--frame F] [--screenshot FILE --frames N]:
// the interactive viewer (harness/view is its model, harness/cli/viewer its window). Built without the
// viewer (CAUSTICS_BUILD_VIEWER off), the command exists and says so (exit 2).
#include <iostream>

#include "command.hpp"
#include <caustics/reference/reference.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/view/session.hpp>
#ifdef CAUSTICS_HAVE_VIEWER
#include "viewer/viewer_app.hpp"
#endif

namespace caustics::cli {
namespace {

Command make_view_command() {
    Command c;
    c.name = "view";
    c.summary = "explore a method live beside the reference in a window (GLFW, OpenGL 3.3, ImGui)";
    c.order = 60;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        struct Args {
            std::string scene, method, screenshot, cache;
            std::vector<std::string> sets;
            int frame = 0, frames = 1;
            bool wait_reference = false, no_reference = false, split = false, play = false;
            std::string space;
            ReferenceSettings reference{.photons = 4'000'000};
        };
        auto a = std::make_shared<Args>();
        app.add_option("scene", a->scene, "scene name (scenes/NAME.json) or path")->required();
        app.add_option("--method", a->method, "method to start with (default: the first that supports the scene)");
        app.add_option("--set", a->sets, "method parameter KEY=VALUE (repeatable)");
        add_frame_option(app, a->frame);
        add_reference_options(app, a->reference);
        add_cache_option(app, a->cache);
        app.add_flag("--no-reference", a->no_reference, "no reference (no reference, difference or error)");
        add_output_file_option(app, "--screenshot", a->screenshot,
                               "write the window as PNG (and FILE.json) after --frames frames, then exit");
        app.add_option("--frames", a->frames, "frames (each: update + render) before the screenshot")
            ->check(CLI::Range(1, 100000));
        app.add_option("--space", a->space, "the panes' space to start with (default: volume where the medium scatters, else receiver)")
            ->check(CLI::IsMember({"receiver", "camera", "volume"}));
        app.add_flag("--split", a->split, "start in the split view (method | reference)");
        app.add_flag("--play", a->play, "start playing the animation (each window frame: the next scene frame, update + render)");
        app.add_flag("--wait-reference", a->wait_reference, "the screenshot waits for the final reference");
        return [a]() -> int {
#ifdef CAUSTICS_HAVE_VIEWER
            viewer::ViewerOptions o;
            o.session.scene = a->scene;
            o.session.method = a->method;
            o.session.overrides = parse_assignments(a->sets, "--set");
            o.session.frame = a->frame;
            o.session.reference = !a->no_reference;
            o.session.progressive.reference = a->reference;
            o.session.progressive.cache_dir = a->cache.empty() ? default_cache_dir() : a->cache;
            o.screenshot = a->screenshot;
            o.frames = a->frames;
            o.wait_reference = a->wait_reference;
            o.space = a->space;
            o.split = a->split;
            o.play = a->play;
            return viewer::run_viewer(o);
#else
            throw InputError("view", "", "this build has no viewer (CAUSTICS_BUILD_VIEWER is off: GLFW, OpenGL or Dear ImGui was "
                                         "not found when it was configured); install them (scripts/setup.sh) and reconfigure");
#endif
        };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_view_command);

}  // namespace caustics::cli
