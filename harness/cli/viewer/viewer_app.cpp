// The window loop: poll, advance the animation when playing, update + render the method, upload the
// panes as textures, draw the controls and the panes with ImGui, and (for --screenshot) read the back
// buffer after the last frame. The window is 1024 x 768 by default: a control column on the left, the
// panes on the right (a 2 x 2 grid of beauty, method, reference and difference of one space, or one pane
// split between method and reference, Falcor's split screen).
#include "viewer_app.hpp"
#include "viewer_panels.hpp"

#include <cstdio>
#include <iostream>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <caustics/util/statistics.hpp>
#include <caustics/util/timing.hpp>

namespace caustics::viewer {
namespace {

std::string g_glfw_error;
void on_glfw_error(int, const char* text) { g_glfw_error = text ? text : "unknown GLFW error"; }

}  // namespace

std::string no_display_message(const std::string& why) {
    return "caustics: error: view: no display (" + why +
           "); run it on a display or under a virtual one: xvfb-run -a caustics view SCENE ...";
}

int run_viewer(const ViewerOptions& options) {
    const Stopwatch since_start;
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        std::cerr << no_display_message(g_glfw_error.empty() ? "glfwInit failed" : g_glfw_error) << "\n";
        return 2;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    GLFWwindow* window = glfwCreateWindow(options.width, options.height, "caustics view", nullptr, nullptr);
    if (!window) {
        const std::string why = g_glfw_error.empty() ? "no OpenGL 3.3 core context" : g_glfw_error;
        glfwTerminate();
        std::cerr << no_display_message(why) << "\n";
        return 2;
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(options.screenshot.empty() ? 1 : 0);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;   // the layout is the program's, not a file's
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");

    int code = 0;
    {
        Viewer v(options);   // loads the scene and the method (InputError leaves through the caller)
        int frames_done = 0;
        double first_frame_ms = -1.0;
        while (!glfwWindowShouldClose(window)) {
            // Idle (nothing to render until a change): wait for input, waking a few times a second to
            // show the reference's progress; the reference thread then has the cores.
            if (v.idle() && options.screenshot.empty()) glfwWaitEventsTimeout(0.25);
            else glfwPollEvents();
            const bool last = !options.screenshot.empty() && frames_done + 1 >= options.frames;
            if (last && options.wait_reference) v.session().wait_for_reference();
            Stopwatch frame_clock;
            v.step();                 // animation, update + render, panes
            ImGui_ImplOpenGL3_NewFrame();
            ImGui_ImplGlfw_NewFrame();
            ImGui::NewFrame();
            int fb_w = 0, fb_h = 0;
            glfwGetFramebufferSize(window, &fb_w, &fb_h);
            v.draw(fb_w, fb_h);
            Stopwatch draw_clock;
            ImGui::Render();
            glViewport(0, 0, fb_w, fb_h);
            glClearColor(0.08f, 0.08f, 0.09f, 1.0f);
            glClear(GL_COLOR_BUFFER_BIT);
            ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
            glFinish();
            v.record_frame_time(frame_clock.ms(), draw_clock.ms());
            if (first_frame_ms < 0.0) first_frame_ms = since_start.ms();
            ++frames_done;
            if (v.take_screenshot_request()) {
                const std::string name = v.screenshot_name();
                v.write_screenshot(name, fb_w, fb_h, first_frame_ms);
                v.set_message("wrote " + name + " (and .json)");
            }
            if (last) {
                v.write_screenshot(options.screenshot, fb_w, fb_h, first_frame_ms);
                break;
            }
            if (!options.screenshot.empty()) continue;   // no swap needed before the read-back
            glfwSwapBuffers(window);
        }
    }
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(window);
    glfwTerminate();
    return code;
}

}  // namespace caustics::viewer
