// The control column: time, method and its parameters (generated from the table), display, numbers
// (frame time, stages, health, errors, reference) and the record actions.
#include "viewer_panels.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <caustics/run/view_table.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/view/record.hpp>

namespace caustics::viewer {
namespace {

void tooltip(const std::string& text) {
    if (!text.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", text.c_str());
}

void error_line(const char* label, const std::optional<ViewErrors>& e) {
    if (!e || !e->net.valid) {
        ImGui::TextDisabled("%s: -", label);
        return;
    }
    ImGui::Text("%s nrmse_net %.4f [%.4f, %.4f]", label, e->net.value, e->net.lo, e->net.hi);
    if (e->have_baseline) ImGui::TextDisabled("   baseline %.4f%s", e->baseline_error, e->no_better_than_flat ? "  (no better)" : "");
}

}  // namespace

// A method that refuses its new parameters or scene (an exception from create or prepare) leaves the
// window open: the message is shown and the previous instance keeps rendering.
void Viewer::guarded(const std::function<void()>& action) {
    try {
        action();
        message_.clear();
    } catch (const std::exception& e) {
        message_ = std::string("refused: ") + e.what();
    }
}

void Viewer::controls() {
    view::Session& s = *session_;
    ImGui::PushItemWidth(-120.0f);   // room for the parameter names
    ImGui::Text("%s  (frame %d of %d)", s.scene().name.c_str(), s.frame(), s.frame_count());
    // Time: play / pause / step / scrub.
    if (ImGui::Button(playing_ ? "pause" : "play")) playing_ = !playing_;
    ImGui::SameLine();
    if (ImGui::Button("<")) { s.set_frame(s.frame() - 1); beauty_dirty_ = dirty_ = true; }
    ImGui::SameLine();
    if (ImGui::Button(">")) { s.set_frame(s.frame() + 1); beauty_dirty_ = dirty_ = true; }
    ImGui::SameLine();
    ImGui::Checkbox("continuous", &continuous_);
    tooltip("render every window frame (the frame time's median needs repeats); off: only on a change");
    int frame = s.frame();
    if (s.frame_count() > 1 && ImGui::SliderInt("frame", &frame, 0, s.frame_count() - 1, "%d", ImGuiSliderFlags_AlwaysClamp) &&
        frame != s.frame()) {
        s.set_frame(frame);
        beauty_dirty_ = dirty_ = true;
    }
    ImGui::Separator();
    // Method picker: only methods whose capabilities accept the scene can be chosen.
    if (ImGui::BeginCombo("method", s.method_name().c_str())) {
        for (const view::MethodChoice& c : s.methods()) {
            ImGui::BeginDisabled(!c.supported);
            if (ImGui::Selectable(c.name.c_str(), c.name == s.method_name()) && c.name != s.method_name()) {
                guarded([&] { s.set_method(c.name); });
                beauty_dirty_ = dirty_ = true;
            }
            ImGui::EndDisabled();
            if (!c.supported && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("%s", c.reason.c_str());
        }
        ImGui::EndCombo();
    }
    ImGui::Separator();
    // Numbers.
    const view::RenderTiming& t = s.timing();
    ImGui::Text("frame %.2f ms median of %zu (update %.2f, render %.2f)", t.median_frame_ms, t.samples, t.update_ms, t.render_ms);
    ImGui::TextDisabled("prepare %.1f ms; viewer overhead %.2f ms", t.prepare_ms, overhead_ms_.empty() ? 0.0 : overhead_ms_.back());
    for (const auto& [stage, ms] : s.output().stages_ms) ImGui::BulletText("%s %.2f ms", stage.c_str(), ms);
    if (!s.output().health.counters.empty() && ImGui::TreeNode("health")) {
        for (const auto& [name, n] : s.output().health.counters) ImGui::Text("%s %lld", name.c_str(), static_cast<long long>(n));
        ImGui::TreePop();
    }
    const view::LiveErrors& e = s.errors();
    ImGui::Text("truth: %s", e.truth_kind.empty() ? "(none yet)" : e.truth_kind.c_str());
    if (s.status() != "ok") ImGui::TextColored(ImVec4(1, 0.4f, 0.4f, 1), "%s", s.status().c_str());
    for (const ViewSpec* v : requested_views(s.scene())) {   // the view table's rows the scene asks for
        const auto it = e.by_view.find(v->name);
        error_line(v->name.c_str(), it == e.by_view.end() ? std::nullopt : std::optional<ViewErrors>(it->second));
    }
    const view::ProgressiveStatus st = s.reference_status();
    ImGui::Text("reference %.3g / %.3g photons%s", static_cast<double>(st.photons), static_cast<double>(st.target),
                st.from_cache ? " (cache)" : "");
    if (st.photons_per_second > 0.0) ImGui::TextDisabled("  %d rounds, %.3g photons/s%s", st.rounds, st.photons_per_second, st.done ? ", done" : "");
    if (!st.error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.4f, 1), "%s", st.error.c_str());
    ImGui::Separator();
    // Display.
    int space = static_cast<int>(space_);
    if (ImGui::Combo("space", &space, "receiver map\0camera view\0volume (camera_volume)\0")) {
        space_ = static_cast<view::Space>(space);
    }
    ImGui::Checkbox("split method | reference", &split_);
    if (split_) ImGui::SliderFloat("split", &split_at_, 0.02f, 0.98f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    int exposure = static_cast<int>(display_.exposure);
    ImGui::RadioButton("linear", &exposure, 0);
    ImGui::SameLine();
    ImGui::RadioButton("log", &exposure, 1);
    display_.exposure = static_cast<view::Exposure>(exposure);
    if (display_.exposure == view::Exposure::Log) {
        float decades = static_cast<float>(display_.decades);
        if (ImGui::SliderFloat("decades", &decades, 1.0f, 6.0f, "%.1f", ImGuiSliderFlags_AlwaysClamp)) display_.decades = decades;
    }
    float gain = static_cast<float>(display_.exposure_gain);
    if (ImGui::SliderFloat("gain", &gain, 0.05f, 20.0f, "%.2f", ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp)) {
        display_.exposure_gain = gain;
        beauty_dirty_ = true;
    }
    int cmap = static_cast<int>(display_.colormap);
    if (ImGui::Combo("colour map", &cmap, "inferno\0viridis\0grey\0")) display_.colormap = static_cast<view::ColorMap>(cmap);
    ImGui::Separator();
    ImGui::Separator();
    // Parameters, generated from the method's table (view/param_model.hpp).
    ImGui::TextDisabled("parameters of %s", s.method_name().c_str());
    view::ParamModel& pm = s.params();
    bool changed = false;
    for (std::size_t i = 0; i < pm.widgets().size(); ++i) {
        const view::ParamWidget& w = pm.widgets()[i];
        const int flags = ImGuiSliderFlags_AlwaysClamp | (w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0);
        switch (w.kind) {
        case view::WidgetKind::IntSlider: {
            long long v = w.int_value, lo = static_cast<long long>(std::ceil(w.lo)), hi = static_cast<long long>(std::floor(w.hi));
            if (ImGui::SliderScalar(w.name.c_str(), ImGuiDataType_S64, &v, &lo, &hi, "%lld", flags)) changed |= pm.set_int(i, v);
            break;
        }
        case view::WidgetKind::FloatSlider: {
            double v = w.float_value, lo = w.lo, hi = w.hi;
            if (ImGui::SliderScalar(w.name.c_str(), ImGuiDataType_Double, &v, &lo, &hi, "%.4g", flags)) changed |= pm.set_float(i, v);
            break;
        }
        case view::WidgetKind::Combo: {
            int c = w.choice;
            std::string items;
            for (const auto& choice : w.choices) items += choice + '\0';
            if (ImGui::Combo(w.name.c_str(), &c, items.c_str())) changed |= pm.set_choice(i, c);
            break;
        }
        case view::WidgetKind::Checkbox: {
            bool b = w.bool_value;
            if (ImGui::Checkbox(w.name.c_str(), &b)) changed |= pm.set_bool(i, b);
            break;
        }
        }
        tooltip(w.doc + (w.declared_unbounded ? "\n(slider span chosen: the table's range is unbounded; use --set beyond it)" : ""));
    }
    if (changed) {
        guarded([&] { s.parameters_changed(); });
        beauty_dirty_ = dirty_ = true;
    }
    ImGui::Separator();
    // Record.
    if (ImGui::Button("render command")) {
        record_text_ = view::render_command_line(s);
        std::cout << record_text_ << std::endl;
        glfwSetClipboardString(nullptr, record_text_.c_str());
    }
    ImGui::SameLine();
    if (ImGui::Button("sweep fragment")) {
        record_text_ = view::sweep_fragment(s).dump(2);
        std::cout << record_text_ << std::endl;
        glfwSetClipboardString(nullptr, record_text_.c_str());
    }
    ImGui::SameLine();
    if (ImGui::Button("screenshot")) screenshot_requested_ = true;
    if (!record_text_.empty()) {
        ImGui::TextDisabled("(printed and copied to the clipboard)");
        ImGui::TextWrapped("%s", record_text_.c_str());
    }
    if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
    ImGui::PopItemWidth();
}

}  // namespace caustics::viewer
