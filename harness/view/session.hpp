#pragma once
// The viewer's state without a window: scene, animation frame, method and its live parameters, the last
// render and its timing, the reference of the current frame (progressive) and the errors against it.
// The GLFW/ImGui layer (harness/cli/viewer) only draws what this holds and calls its setters.
//
// Per animation frame, as `caustics render` does: SceneFrame(scene, f), then the method's update(frame)
// and render(frame, request); prepare(scene) runs once per method instance (a new method or a parameter
// change creates a new instance, since parameters are fixed at creation, method.hpp).
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <caustics/api/method.hpp>
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/view/param_model.hpp>
#include <caustics/view/progressive_reference.hpp>

namespace caustics::view {

struct SessionOptions {
    std::string scene;                                // a scene name or path
    std::string method;                               // empty: the first method that supports the scene
    std::map<std::string, std::string> overrides;     // --set
    int frame = 0;
    bool reference = true;                            // trace/load the reference of each frame
    ProgressiveSettings progressive;                  // its photons, rounds, cache folder
    std::size_t timing_window = 15;                   // renders in the frame-time median
};

// One method name and whether it accepts the scene (capabilities and, on a scattering scene,
// volume_capability, as the run layer decides).
struct MethodChoice {
    std::string name;
    bool supported = true;
    std::string reason;
};

struct RenderTiming {
    double update_ms = 0.0, render_ms = 0.0;
    double median_frame_ms = 0.0;   // update + render, median of the last timing_window renders
    std::size_t samples = 0;
    double prepare_ms = 0.0;        // of the current method instance
};

// Errors of the last render against the current truth (run_errors.hpp measure_view: net of the
// reference's noise where the truth is Monte Carlo).
struct LiveErrors {
    std::map<std::string, ViewErrors> by_view;   // every measured view, by view-table row name
    // The view's errors, null where it was not measured.
    const ViewErrors* view(const std::string& name) const {
        const auto it = by_view.find(name);
        return it == by_view.end() ? nullptr : &it->second;
    }
    std::string truth_kind;         // "analytic:sine", "reference" or "" (none yet)
    std::uint64_t photons = 0;      // of the reference the errors were measured against
};

class Session {
public:
    explicit Session(SessionOptions options);   // InputError for a bad scene, method, parameter or frame
    ~Session();

    const Scene& scene() const { return frame_->scene(); }
    const SceneFrame& scene_frame() const { return *frame_; }
    int frame() const { return frame_index_; }
    int frame_count() const { return scene().animation.frames; }
    const std::vector<MethodChoice>& methods() const { return methods_; }
    const std::string& method_name() const { return params_->info().name; }
    const ParamModel& params() const { return *params_; }
    ParamModel& params() { return *params_; }

    // Clamps into the animation. The new frame's reference starts unless `with_reference` is false
    // (while the animation plays: ensure_reference() starts it once it stops).
    void set_frame(int frame, bool with_reference = true);
    void ensure_reference();
    void set_method(const std::string& name);        // defaults of its table; InputError when unsupported
    // After a ParamModel setter returned true: a new instance with the new parameters. If the method
    // refuses them (create or prepare throws), the model returns to the accepted set and it rethrows.
    void parameters_changed();

    // One update + render of the current frame (timed), then the errors against the newest reference.
    void render();
    const CausticOutput& output() const { return output_; }
    const RenderTiming& timing() const { return timing_; }
    bool rendered() const { return rendered_; }
    std::string status() const { return status_; }   // "ok", or why the output is not measured

    // The reference the last render was measured against (null: none yet) and the background's state.
    std::shared_ptr<const ReferenceResult> reference() const { return reference_; }
    ProgressiveStatus reference_status() const;
    const ProgressiveReference* progressive() const { return progressive_.get(); }
    void wait_for_reference();                        // blocks until the frame's reference is final
    // The receiver's truth: the closed form where the scene has one, else the reference mean (null: none).
    const Image* receiver_truth() const;
    const Image* receiver_truth_stderr() const;      // null for a closed form
    const LiveErrors& errors() const { return errors_; }
    // Measures the last render against the newest reference. Measuring (net errors over the replicas)
    // costs as much as a fast method's render, so it is skipped when nothing it depends on changed (the
    // frame, method, parameters or the reference's photons) and the last measure is under half a second
    // old; `force` measures regardless.
    void refresh_errors(bool force = false);
    // Bumped by every change of frame, method or parameters (what the panes and the beauty depend on).
    std::uint64_t generation() const { return generation_; }

    // The scene argument as given (for the record actions).
    const std::string& scene_argument() const { return options_.scene; }
    const SessionOptions& options() const { return options_; }

private:
    void make_method();
    void start_reference();
    SessionOptions options_;
    std::unique_ptr<SceneFrame> frame_;
    int frame_index_ = 0;
    std::vector<MethodChoice> methods_;
    std::unique_ptr<ParamModel> params_;
    std::unique_ptr<ParamModel> accepted_;   // the parameters of the current method instance
    std::unique_ptr<Method> method_;
    bool prepared_for_frame_ = false;
    CausticOutput output_;
    bool rendered_ = false;
    std::string status_;
    RenderTiming timing_;
    std::deque<double> frame_times_;
    AnalyticTruth analytic_;
    std::unique_ptr<ProgressiveReference> progressive_;
    // Abandoned references still finishing a round, each with the frame it reads (destroyed first).
    struct Retired {
        std::unique_ptr<SceneFrame> frame;
        std::unique_ptr<ProgressiveReference> reference;
    };
    std::vector<Retired> retired_;
    std::shared_ptr<const ReferenceResult> reference_;
    LiveErrors errors_;
    std::uint64_t generation_ = 1, measured_generation_ = 0, measured_photons_ = 0;
    double measured_at_s_ = -1.0;
    Image flat_;   // flat_interface_baseline of frame flat_frame_
    int flat_frame_ = -1;
};

}  // namespace caustics::view
