#include <caustics/run/run_record.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <caustics/frame/receiver_chart.hpp>

namespace caustics {

const char* status_name(RunStatus status) {
    switch (status) {
    case RunStatus::Ok: return "ok";
    case RunStatus::Skipped: return "skipped";
    case RunStatus::Unstable: return "unstable";
    }
    return "?";
}

Capability decide_capability(const Method& method, const Scene& scene) {
    Capability cap = method.capabilities(scene);
    if (cap.supported && scene_scatters(scene)) {
        const Capability v = method.volume_capability(scene);
        if (!v.supported)
            cap = Capability::no("the scene's medium scatters (volume caustics, camera_volume, and extinction along "
                                 "every path): " + v.reason);
    }
    return cap;
}

RunTiming time_method(Method& method, const SceneFrame& sf, const RenderRequest& request, const RenderOptions& options,
                      CausticOutput& last) {
    RunTiming t;
    Stopwatch clock;
    method.prepare(sf.scene());
    t.prepare_ms = clock.ms();
    clock.reset();
    method.update(sf.geometry());
    const double first_update_ms = clock.ms();
    // In an animated scene the geometry changes every frame, so a frame costs update + render; in a
    // static one update runs once and a frame is the render alone.
    t.animated = sf.scene().animation.frames > 1;
    for (int i = 0; i < options.warmup; ++i) {
        if (t.animated) method.update(sf.geometry());
        (void)method.render(sf.geometry(), request);
    }
    std::vector<double> render_times, update_times, frame_times;
    std::map<std::string, std::vector<double>> stage_times;
    TimingPolicy policy;
    policy.min_repeats = std::max(1, options.repeats);
    policy.precision = options.timing_precision;
    policy.max_seconds = options.timing_max_s;
    double timed_seconds = 0.0;
    TimingStop stop = TimingStop::Continue;
    while (stop == TimingStop::Continue) {
        double update_ms = 0.0;
        if (t.animated) {
            clock.reset();
            method.update(sf.geometry());
            update_ms = clock.ms();
            update_times.push_back(update_ms);
        }
        clock.reset();
        CausticOutput out = method.render(sf.geometry(), request);
        const double ms = clock.ms();
        render_times.push_back(ms);
        frame_times.push_back(update_ms + ms);
        timed_seconds += (update_ms + ms) / 1000.0;
        for (const auto& [stage, stage_ms] : out.stages_ms) stage_times[stage].push_back(stage_ms);
        last = std::move(out);   // the previous output is freed outside the timed region
        stop = timing_stop(frame_times, timed_seconds, policy);
    }
    t.render = summarize_ms(render_times);
    t.frame = summarize_ms(frame_times);
    t.capped = stop == TimingStop::Capped;
    t.update_ms = t.animated ? summarize_ms(update_times).median : first_update_ms;
    for (auto& [stage, samples] : stage_times) t.stages_ms[stage] = summarize_ms(samples).median;
    t.repeats = static_cast<int>(render_times.size());
    return t;
}

namespace {

std::int64_t count_nonfinite(const Image& image, const std::vector<std::uint8_t>* mask) {
    std::int64_t n = 0;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    for (std::size_t p = 0; p < pixels; ++p) {
        if (mask && !(*mask)[p]) continue;
        for (int c = 0; c < image.channels; ++c)
            if (!std::isfinite(image.pixels[p * image.channels + c])) ++n;
    }
    return n;
}

void check_size(const Image& image, int w, int h, const std::string& method, const std::string& what) {
    if (image.empty()) return;
    if (image.width != w || image.height != h || image.channels != 1)
        throw std::runtime_error("method " + method + " returned a " + what + " image of " +
                                 std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                                 std::to_string(image.channels) + ", expected " + std::to_string(w) + "x" +
                                 std::to_string(h) + "x1");
}

}  // namespace

OutputCheck check_output(const CausticOutput& out, const SceneFrame& sf, const std::string& method, bool volume) {
    const CameraGBuffer& g = sf.gbuffer();
    check_size(out.receiver, sf.chart().width(), sf.chart().height(), method, "receiver");
    check_size(out.camera, g.width, g.height, method, "camera");
    check_size(out.camera_volume, g.width, g.height, method, "camera_volume");
    OutputCheck c;
    c.nonfinite = count_nonfinite(out.receiver, nullptr) + count_nonfinite(out.camera, &g.covered) +
                  count_nonfinite(out.camera_volume, nullptr);
    c.unstable = c.nonfinite > 0 || out.health.get("nonfinite") > 0;
    if (c.unstable)
        c.messages.push_back("non-finite output (" + std::to_string(c.nonfinite) + " pixels, method counter " +
                             std::to_string(out.health.get("nonfinite")) + "): error not measured");
    if (out.receiver.empty()) c.messages.push_back("method produced no receiver map");
    if (out.camera.empty()) c.messages.push_back("method produced no camera view");
    if (volume && out.camera_volume.empty()) c.messages.push_back("method produced no camera_volume view");
    return c;
}

}  // namespace caustics
