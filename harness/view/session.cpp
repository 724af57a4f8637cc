#include <caustics/view/session.hpp>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>
#include <cmath>

#include <caustics/api/registry.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/statistics.hpp>
#include <caustics/util/timing.hpp>
#include <caustics/run/view_table.hpp>

namespace caustics::view {
namespace {

// The decision runs make (run/view_table.hpp): the method's capabilities and every requested view's.
MethodChoice choice_for(const MethodInfo& info, const Scene& scene) {
    MethodChoice c{info.name, true, {}};
    try {
        const std::unique_ptr<Method> m = info.create(ParamSet::resolve(info.name, info.params, {}));
        const Capability cap = decide_capability(*m, scene);
        c.supported = cap.supported;
        c.reason = cap.reason;
    } catch (const std::exception& e) {
        c.supported = false;
        c.reason = e.what();
    }
    return c;
}

}  // namespace

Session::Session(SessionOptions options) : options_(std::move(options)) {
    Scene scene = load_scene(resolve_scene_path(options_.scene));
    if (options_.frame < 0 || options_.frame >= scene.animation.frames)
        throw invalid_value("--frame", std::to_string(options_.frame) + " is outside the animation",
                            "0 to " + std::to_string(scene.animation.frames - 1));
    frame_index_ = options_.frame;
    frame_ = std::make_unique<SceneFrame>(std::move(scene), frame_index_);
    for (const MethodInfo* info : registered_methods()) methods_.push_back(choice_for(*info, frame_->scene()));
    std::string name = options_.method;
    if (name.empty()) {
        for (const MethodChoice& c : methods_)
            if (c.supported) { name = c.name; break; }
        if (name.empty()) throw InputError(options_.scene, "", "no registered method supports this scene");
    }
    const MethodInfo& info = require_method(name);
    for (const MethodChoice& c : methods_)
        if (c.name == name && !c.supported) throw InputError("--method", "", name + " does not support this scene: " + c.reason);
    params_ = std::make_unique<ParamModel>(info, options_.overrides);
    make_method();
    analytic_ = analytic_truth(frame_->geometry(), frame_->chart());
    start_reference();
}

Session::~Session() = default;

void Session::make_method() {
    // Made and prepared aside, so that a refusal (an exception) leaves the previous instance in place.
    std::unique_ptr<Method> method = params_->info().create(params_->params());
    Stopwatch clock;
    method->prepare(scene());
    const double prepare_ms = clock.ms();
    method_ = std::move(method);
    accepted_ = std::make_unique<ParamModel>(*params_);
    timing_ = {};
    timing_.prepare_ms = prepare_ms;
    frame_times_.clear();
    rendered_ = false;
    ++generation_;
}

void Session::start_reference() {
    reference_.reset();
    errors_ = {};
    measured_at_s_ = -1.0;   // measure again at the next render
    if (options_.reference) progressive_ = std::make_unique<ProgressiveReference>(*frame_, options_.progressive);
}

void Session::ensure_reference() {
    if (!progressive_ && options_.reference) start_reference();
}

void Session::set_frame(int frame, bool with_reference) {
    frame = std::clamp(frame, 0, frame_count() - 1);
    if (frame == frame_index_) return;
    Scene scene = frame_->scene();
    // The old frame's reference finishes its current round in the background (it reads the old
    // SceneFrame, which goes with it) instead of holding the window up.
    if (progressive_) {
        progressive_->cancel();
        retired_.push_back({std::move(frame_), std::move(progressive_)});
    }
    frame_ = std::make_unique<SceneFrame>(std::move(scene), frame);
    frame_index_ = frame;
    analytic_ = analytic_truth(frame_->geometry(), frame_->chart());
    ++generation_;
    reference_.reset();
    errors_ = {};
    if (with_reference) start_reference();
    std::erase_if(retired_, [](const Retired& r) { return r.reference->status().done; });
}

void Session::set_method(const std::string& name) {
    const MethodInfo& info = require_method(name);
    for (const MethodChoice& c : methods_)
        if (c.name == name && !c.supported) throw InputError("--method", "", name + " does not support this scene: " + c.reason);
    std::unique_ptr<ParamModel> previous = std::exchange(params_, std::make_unique<ParamModel>(info));
    try {
        make_method();
    } catch (...) {
        params_ = std::move(previous);
        throw;
    }
    errors_ = {};
}

void Session::parameters_changed() {
    // A refused set (create or prepare threw) goes back to the last one the method accepted.
    try {
        make_method();
    } catch (...) {
        *params_ = *accepted_;
        throw;
    }
    errors_ = {};
}

void Session::render() {
    RenderRequest request;
    request.receiver = &frame_->chart();
    request.camera = &frame_->gbuffer();
    request.camera_volume = scene_scatters(scene());
    Stopwatch clock;
    method_->update(frame_->geometry());
    timing_.update_ms = clock.ms();
    clock.reset();
    CausticOutput out = method_->render(frame_->geometry(), request);
    timing_.render_ms = clock.ms();
    frame_times_.push_back(timing_.update_ms + timing_.render_ms);
    while (frame_times_.size() > std::max<std::size_t>(options_.timing_window, 1)) frame_times_.pop_front();
    timing_.median_frame_ms = summarize_ms({frame_times_.begin(), frame_times_.end()}).median;
    timing_.samples = frame_times_.size();
    output_ = std::move(out);
    rendered_ = true;
    refresh_errors();
}

ProgressiveStatus Session::reference_status() const {
    return progressive_ ? progressive_->status() : ProgressiveStatus{};
}

void Session::wait_for_reference() {
    if (progressive_) progressive_->wait();
    if (progressive_) reference_ = progressive_->latest();
}

const Image* Session::receiver_truth() const {
    if (analytic_.available) return &analytic_.receiver;
    return reference_ ? &reference_->receiver : nullptr;
}

const Image* Session::receiver_truth_stderr() const {
    if (analytic_.available) return nullptr;
    return reference_ ? &reference_->receiver_stderr : nullptr;
}

void Session::refresh_errors(bool force) {
    if (progressive_) reference_ = progressive_->latest();
    const std::uint64_t photons = reference_ ? reference_->photons : 0;
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    if (!force && rendered_ && measured_at_s_ >= 0.0 && measured_generation_ == generation_ && measured_photons_ == photons &&
        now - measured_at_s_ < 0.5)
        return;
    measured_generation_ = generation_;
    measured_photons_ = photons;
    measured_at_s_ = now;
    errors_ = {};
    status_ = "ok";
    if (!rendered_) return;
    // The run's checks and evaluation (run/view_table.hpp), against the newest reference.
    // A wrong-sized image (a parameter change the method does not handle) is the session's status, not the
    // viewer's end.
    std::int64_t nonfinite = 0;
    try {
        nonfinite = check_views(output_, view_sources(*frame_, nullptr, nullptr), method_name());
    } catch (const std::runtime_error& e) {
        status_ = std::string("failed: ") + e.what();
        return;
    }
    if (nonfinite > 0 || output_.health.get("nonfinite") > 0) {
        status_ = "unstable: non-finite output, error not measured";
        return;
    }
    if (flat_.empty() || flat_frame_ != frame_index_) {   // the no-caustic baseline's expensive part, once per frame
        flat_ = flat_interface_baseline(frame_->geometry(), frame_->chart());
        flat_frame_ = frame_index_;
    }
    const ViewSources sources = view_sources(*frame_, reference_.get(), &analytic_, &flat_);
    const bool radiometric = params_->info().radiometric_at(params_->params());
    for (EvaluatedView& v : evaluate_views(output_, sources, radiometric)) {
        if (v.spec->primary) errors_.truth_kind = v.truth_kind;
        errors_.by_view[v.spec->name] = std::move(v.errors);
    }
    if (reference_) {
        errors_.photons = reference_->photons;
        if (errors_.truth_kind.empty()) errors_.truth_kind = "reference";
    }
}

}  // namespace caustics::view
