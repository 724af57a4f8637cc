#pragma once
// The thin window layer of `caustics view`: GLFW (OpenGL 3.3 core) and Dear ImGui draw what the
// window-free model (harness/view) holds. Built only with CAUSTICS_BUILD_VIEWER.
#include <string>

#include <caustics/view/session.hpp>

namespace caustics::viewer {

struct ViewerOptions {
    view::SessionOptions session;
    std::string screenshot;       // non-empty: write the window here after `frames` frames, then exit
    int frames = 1;               // UI frames (each: update + render) before the screenshot
    bool wait_reference = false;  // the screenshot waits for the final reference
    int width = 1024, height = 768;
    std::string space;            // receiver | camera | volume; empty: volume on a scattering scene, else receiver
    bool split = false;           // start in the split view
    bool play = false;            // start playing the animation (one scene frame per window frame)
};

// Exit code: 0, or 2 when there is no display (one message on stderr, before any other work).
int run_viewer(const ViewerOptions& options);

// The message printed without a display.
std::string no_display_message(const std::string& why);

}  // namespace caustics::viewer
