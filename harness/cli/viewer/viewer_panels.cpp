#include "viewer_panels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <GL/gl.h>
#include <imgui.h>
#include <nlohmann/json.hpp>

#include <caustics/run/beauty.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/util/timing.hpp>
#include <caustics/view/record.hpp>

namespace caustics::viewer {
namespace {

constexpr float kControlsWidth = 330.0f;

double median_of(const std::deque<double>& v) {
    if (v.empty()) return 0.0;
    std::vector<double> s(v.begin(), v.end());
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
    return s[s.size() / 2];
}

void push_window(std::deque<double>& d, double v, std::size_t n = 30) {
    d.push_back(v);
    while (d.size() > n) d.pop_front();
}

}  // namespace

void Texture::upload(const std::vector<std::uint8_t>& rgba, int w, int h, bool nearest) {
    if (!id) glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    const GLint filter = nearest ? GL_NEAREST : GL_LINEAR;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (w == width && h == height)
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    else
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    width = w;
    height = h;
}

Texture::~Texture() {
    if (id) glDeleteTextures(1, &id);
}

Viewer::Viewer(const ViewerOptions& options) : options_(options) {
    session_ = std::make_unique<view::Session>(options.session);
    if (scene_scatters(session_->scene())) space_ = view::Space::Volume;
    if (options.space == "receiver") space_ = view::Space::Receiver;
    if (options.space == "camera") space_ = view::Space::Camera;
    if (options.space == "volume") space_ = view::Space::Volume;
    split_ = options.split;
    playing_ = options.play;
}

std::vector<view::ViewKind> Viewer::visible() const {
    using K = view::ViewKind;
    switch (space_) {
    case view::Space::Receiver: return {K::Beauty, K::MethodReceiver, K::ReferenceReceiver, K::DifferenceReceiver};
    case view::Space::Camera: return {K::Beauty, K::MethodCamera, K::ReferenceCamera, K::DifferenceCamera};
    case view::Space::Volume: return {K::Beauty, K::MethodVolume, K::ReferenceVolume, K::DifferenceVolume};
    }
    return {};
}

void Viewer::step() {
    if (playing_ && session_->frame_count() > 1) {
        session_->set_frame((session_->frame() + 1) % session_->frame_count(), false);
        beauty_dirty_ = true;
    }
    if (!playing_) session_->ensure_reference();
    if (continuous_ || dirty_ || !session_->rendered()) {
        session_->render();
        dirty_ = false;
    } else {
        session_->refresh_errors();   // the reference may have sharpened
    }
    rebuild_panes();
}

void Viewer::rebuild_panes() {
    const bool beauty_visible = !split_;
    if (beauty_visible && session_->rendered() && (beauty_dirty_ || beauty_generation_ != session_->generation())) {
        Stopwatch clock;
        const SceneFrame& sf = session_->scene_frame();
        BeautyInputs in;
        in.gbuffer = &sf.gbuffer();
        in.camera_ec = &session_->output().camera;
        in.chart = &sf.chart();
        in.receiver_ec = &session_->output().receiver;
        in.samples_per_axis = 1;
        beauty_ = render_beauty(sf.tracer(), in);
        beauty_pane_ = view::make_pane(*session_, view::ViewKind::Beauty, display_, &beauty_);
        beauty_ms_ = clock.ms();
        beauty_dirty_ = false;
        beauty_generation_ = session_->generation();
        beauty_uploaded_ = false;
    }
    Stopwatch clock;
    panes_.clear();
    const std::vector<view::ViewKind> kinds = visible();
    const view::SpaceMappings mappings = view::space_mappings(*session_, space_, display_);
    for (view::ViewKind k : kinds)
        panes_.push_back(k == view::ViewKind::Beauty ? beauty_pane_ : view::make_pane(*session_, k, display_, nullptr, &mappings));
    textures_.resize(std::max(textures_.size(), panes_.size()));
    for (std::size_t i = 0; i < panes_.size(); ++i) {
        if (!textures_[i]) textures_[i] = std::make_unique<Texture>();
        const bool beauty = panes_[i].kind == view::ViewKind::Beauty;
        if (!panes_[i].available || (beauty && beauty_uploaded_)) continue;
        textures_[i]->upload(panes_[i].rgba, panes_[i].width, panes_[i].height, !beauty);
        if (beauty) beauty_uploaded_ = true;
    }
    push_window(upload_ms_, clock.ms());
}

void Viewer::record_frame_time(double ms, double draw_ms) {
    push_window(draw_ms_, draw_ms);
    const auto& t = session_->timing();
    push_window(overhead_ms_, std::max(0.0, ms - t.update_ms - t.render_ms - beauty_ms_));
    beauty_ms_ = 0.0;
}

void Viewer::draw(int width, int height) {
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(ImVec2(kControlsWidth, static_cast<float>(height)));
    ImGui::Begin("controls", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                                          ImGuiWindowFlags_NoTitleBar);
    controls();
    ImGui::End();
    ImGui::SetNextWindowPos(ImVec2(kControlsWidth, 0));
    ImGui::SetNextWindowSize(ImVec2(static_cast<float>(width) - kControlsWidth, static_cast<float>(height)));
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(4, 4));
    ImGui::Begin("panes", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                                       ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoScrollbar);
    draw_panes(kControlsWidth + 4, 4, static_cast<float>(width) - kControlsWidth - 8, static_cast<float>(height) - 8);
    ImGui::End();
    ImGui::PopStyleVar();
}

// The image of pane `index` fitted into the cell (x, y, w, h) at an integer zoom where it fits (so that
// every bin is a whole block of pixels), on whole pixels, with its title above and the mapping's colour
// bar below.
void Viewer::place(std::size_t index, float x, float y, float w, float h, float u0, float u1) {
    const view::Pane& p = panes_[index];
    ImGui::SetCursorScreenPos(ImVec2(std::floor(x), std::floor(y)));
    ImGui::TextUnformatted(p.title.c_str());
    if (p.available && p.kind != view::ViewKind::Beauty) {
        ImGui::SameLine();
        ImGui::TextDisabled(p.mapping.signed_range ? "[-%.3g, %.3g]" : "[0, %.3g]", p.mapping.scale, p.mapping.scale);
    }
    const float top = std::floor(y + ImGui::GetTextLineHeightWithSpacing());
    const float avail_h = h - ImGui::GetTextLineHeightWithSpacing() - 14.0f;
    if (!p.available) {
        ImGui::SetCursorScreenPos(ImVec2(std::floor(x), top));
        ImGui::TextDisabled("(%s)", p.missing.c_str());
        return;
    }
    const float iw = static_cast<float>(p.width) * (u1 - u0), ih = static_cast<float>(p.height);
    float zoom = std::min(w / iw, avail_h / ih);
    if (zoom >= 1.0f) zoom = std::floor(zoom);
    const float dw = std::floor(iw * zoom), dh = std::floor(ih * zoom);
    ImGui::SetCursorScreenPos(ImVec2(std::floor(x), top));
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(textures_[index]->id)), ImVec2(dw, dh),
                 ImVec2(u0, 0), ImVec2(u1, 1));
    PlacedPane placed{p, std::floor(x), top, dw, dh, u0, u1};
    placed.pane.rgba.clear();
    if (ImGui::IsItemHovered()) hover(placed);
    placed_.push_back(std::move(placed));
    if (p.kind != view::ViewKind::Beauty && u0 == 0.0f) {
        // The colour bar: 0 (or -s) at the left, s at the right, t of Mapping::normalise.
        ImDrawList* dl = ImGui::GetWindowDrawList();
        const float by = top + dh + 3.0f, bw = dw;
        for (int i = 0; i < 64; ++i) {
            const auto c = view::colormap_rgba(p.mapping.colormap, i / 63.0);
            dl->AddRectFilled(ImVec2(std::floor(x) + bw * i / 64.0f, by), ImVec2(std::floor(x) + bw * (i + 1) / 64.0f, by + 8.0f),
                              IM_COL32(c[0], c[1], c[2], 255));
        }
    }
}

void Viewer::hover(const PlacedPane& p) {
    if (p.pane.kind == view::ViewKind::Beauty) return;
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    const float zoom = p.w / (static_cast<float>(p.pane.width) * (p.u1 - p.u0));
    const int px = static_cast<int>(std::floor((mouse.x - p.x) / zoom + p.u0 * p.pane.width));
    const int py = static_cast<int>(std::floor((mouse.y - p.y) / zoom));
    const view::Readout r = view::readout(*session_, view::space_of(p.pane.kind), px, py);
    if (!r.valid) return;
    ImGui::BeginTooltip();
    ImGui::Text("bin (%d, %d)%s", px, py, r.covered ? "" : "  not a receiver pixel");
    ImGui::Text("method     %.5g", r.method);
    if (r.truth) ImGui::Text("reference  %.5g", *r.truth);
    if (r.stderr_value) ImGui::Text("std. error %.3g", *r.stderr_value);
    if (r.z) ImGui::Text("z          %+.2f", *r.z);
    ImGui::EndTooltip();
}

void Viewer::draw_panes(float x, float y, float w, float h) {
    placed_.clear();
    if (split_) {
        // Method left of the split, reference right of it, one image (Falcor's split screen).
        const std::size_t m = 1, r = 2;
        if (!panes_[m].available || !panes_[r].available) {
            place(panes_[m].available ? m : r, x, y, w, h);   // the one there is (or why neither)
            return;
        }
        const float iw = static_cast<float>(panes_[m].width), ih = static_cast<float>(panes_[m].height);
        float zoom = std::min(w / iw, (h - 40.0f) / ih);
        if (zoom >= 1.0f) zoom = std::floor(zoom);
        const float left = std::floor(iw * zoom * split_at_);
        place(m, x, y, w, h, 0.0f, split_at_);
        place(r, x + left, y, w - left, h, split_at_, 1.0f);
        return;
    }
    const float cw = std::floor(w / 2), ch = std::floor(h / 2);
    for (std::size_t i = 0; i < panes_.size() && i < 4; ++i)
        place(i, x + cw * static_cast<float>(i % 2), y + ch * static_cast<float>(i / 2), cw - 6, ch - 4);
}

std::string Viewer::screenshot_name() const {
    return "caustics_view_" + session_->scene().name + "_" + session_->method_name() + "_f" +
           std::to_string(session_->frame()) + ".png";
}

void Viewer::write_screenshot(const std::string& path, int width, int height, double first_frame_ms) {
    std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width) * height * 4), flipped(rgba.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    const std::size_t row = static_cast<std::size_t>(width) * 4;
    for (int y = 0; y < height; ++y)
        std::copy_n(rgba.begin() + static_cast<std::ptrdiff_t>(row * y), row,
                    flipped.begin() + static_cast<std::ptrdiff_t>(row * (height - 1 - y)));
    for (std::size_t i = 3; i < flipped.size(); i += 4) flipped[i] = 255;
    view::write_rgba8_png(path, width, height, flipped);
    nlohmann::json panes = nlohmann::json::array();
    for (const PlacedPane& p : placed_)
        panes.push_back({{"view", view::to_string(p.pane.kind)}, {"x", p.x}, {"y", p.y}, {"width", p.w}, {"height", p.h},
                         {"u0", p.u0}, {"u1", p.u1}, {"image_width", p.pane.width}, {"image_height", p.pane.height},
                         {"exposure", view::to_string(p.pane.mapping.exposure)}, {"colormap", view::to_string(p.pane.mapping.colormap)},
                         {"scale", p.pane.mapping.scale}, {"decades", p.pane.mapping.decades},
                         {"signed", p.pane.mapping.signed_range}});
    const auto st = session_->reference_status();
    const auto& t = session_->timing();
    nlohmann::json j = {{"image", path}, {"width", width}, {"height", height}, {"panes", panes},
                        {"scene", session_->scene_argument()}, {"method", session_->method_name()},
                        {"frame", session_->frame()}, {"command", view::render_command_line(*session_)},
                        {"time_to_first_frame_ms", first_frame_ms}, {"frame_ms_median", t.median_frame_ms},
                        {"prepare_ms", t.prepare_ms}, {"overhead_ms_median", median_of(overhead_ms_)},
                        {"upload_ms_median", median_of(upload_ms_)}, {"draw_ms_median", median_of(draw_ms_)},
                        {"frames", options_.frames},
                        {"reference", {{"photons", st.photons}, {"target", st.target}, {"rounds", st.rounds},
                                       {"photons_per_second", st.photons_per_second}, {"from_cache", st.from_cache},
                                       {"done", st.done}}}};
    const auto& e = session_->errors();
    for (const auto& [key, view] : {std::pair{"error_receiver_nrmse_net", "receiver"}, std::pair{"error_camera_nrmse_net", "camera"},
                                    std::pair{"error_volume_nrmse_net", "camera_volume"}})
        if (const ViewErrors* v = e.view(view); v && v->net.valid) j[key] = v->net.value;
    write_text_atomic(path + ".json", j.dump(2) + "\n");
}

}  // namespace caustics::viewer
