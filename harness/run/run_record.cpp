#include <caustics/run/run_record.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>


namespace caustics {

const char* status_name(RunStatus status) {
    switch (status) {
    case RunStatus::Ok: return "ok";
    case RunStatus::Skipped: return "skipped";
    case RunStatus::Unstable: return "unstable";
    }
    return "?";
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
    t.render_samples_ms = std::move(render_times);
    t.frame_samples_ms = std::move(frame_times);
    return t;
}

OutputCheck check_output(const CausticOutput& out, const SceneFrame& sf, const std::string& method) {
    OutputCheck c;
    c.nonfinite = check_views(out, view_sources(sf, nullptr, nullptr), method);
    c.unstable = c.nonfinite > 0 || out.health.get("nonfinite") > 0;
    if (c.unstable)
        c.messages.push_back("non-finite output (" + std::to_string(c.nonfinite) + " pixels, method counter " +
                             std::to_string(out.health.get("nonfinite")) + "): error not measured");
    for (const ViewSpec* v : requested_views(sf.scene()))
        if (!v->output(out) && !v->missing_note.empty()) c.messages.push_back(v->missing_note);
    return c;
}

}  // namespace caustics
