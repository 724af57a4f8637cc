#pragma once
// The viewer's ImGui panels over the window-free model: controls (time, method, parameters, display,
// numbers, record) and the panes, with their textures.
#include <array>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <caustics/util/image.hpp>
#include <caustics/view/session.hpp>
#include <caustics/view/views.hpp>

#include "viewer_app.hpp"

namespace caustics::viewer {

// One RGBA8 texture (GL_NEAREST for maps, so that one bin is a block of whole window pixels).
struct Texture {
    unsigned id = 0;
    int width = 0, height = 0;
    void upload(const std::vector<std::uint8_t>& rgba, int w, int h, bool nearest);
    ~Texture();
};

// Where a pane landed in the window (window pixels, top-left origin), for the screenshot's sidecar.
struct PlacedPane {
    view::Pane pane;           // its pixels are dropped after upload
    float x = 0, y = 0, w = 0, h = 0;
    float u0 = 0, u1 = 1;      // the part of the image shown (split view)
};

class Viewer {
public:
    explicit Viewer(const ViewerOptions& options);
    view::Session& session() { return *session_; }
    void step();                           // animation, update + render, panes to textures
    void draw(int width, int height);      // the ImGui windows
    bool idle() const { return !continuous_ && !playing_ && !dirty_; }
    // A window frame's time and the part of it spent drawing (ImGui's draw lists through OpenGL, finished).
    void record_frame_time(double ms, double draw_ms);
    // The window as PNG, and FILE.json: panes (position, size, mapping), timings, reference.
    void write_screenshot(const std::string& path, int width, int height, double first_frame_ms);

    // The "screenshot" button was pressed since the last call; where to write it.
    bool take_screenshot_request() { const bool r = screenshot_requested_; screenshot_requested_ = false; return r; }
    std::string screenshot_name() const;
    void set_message(std::string m) { message_ = std::move(m); }

private:
    void rebuild_panes();
    void guarded(const std::function<void()>& action);
    void controls();
    void draw_panes(float x, float y, float w, float h);
    void place(std::size_t index, float x, float y, float w, float h, float u0 = 0.0f, float u1 = 1.0f);
    void hover(const PlacedPane& p);
    std::vector<view::ViewKind> visible() const;

    ViewerOptions options_;
    std::unique_ptr<view::Session> session_;
    view::DisplaySettings display_;
    view::Space space_ = view::Space::Receiver;
    bool split_ = false;
    float split_at_ = 0.5f;
    bool playing_ = false, continuous_ = true, dirty_ = true, beauty_dirty_ = true;
    Image beauty_;
    view::Pane beauty_pane_;
    std::uint64_t beauty_generation_ = 0;
    bool beauty_uploaded_ = false;
    double beauty_ms_ = 0.0;
    std::vector<view::Pane> panes_;
    std::vector<std::unique_ptr<Texture>> textures_;
    std::vector<PlacedPane> placed_;
    std::deque<double> overhead_ms_;       // frame time minus update + render (upload + draw + UI)
    std::deque<double> upload_ms_;         // panes: colour mapping and texture upload
    std::deque<double> draw_ms_;
    std::string record_text_;
    std::string message_;
    bool screenshot_requested_ = false;
};

}  // namespace caustics::viewer
