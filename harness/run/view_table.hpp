#pragma once
// The views a method is measured on, as data (docs/design.md section 3): one row per view with its size,
// unit, when a scene asks for it, what a method must support to render it, where its image is in a
// CausticOutput, which pixels are read, and what it is measured against (truth, mask, baseline). Runs
// (run_method), the viewer (view/session) and the conformance suite evaluate views through this table
// alone, so a further view is one row (register_view) plus the method's output in CausticOutput::views.
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <caustics/api/method.hpp>
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/run/scene_frame.hpp>

namespace caustics {

// What a view is measured against on one frame. `maps` points into the sources (which must outlive it) or
// into `owned`, where a row keeps a truth it derives for this frame (a resampled or filtered image).
struct ViewTruth {
    TruthMaps maps;
    std::vector<std::shared_ptr<const Image>> owned;
    std::string kind;                   // "analytic:sine", "reference", ...
    std::vector<std::uint8_t> mask;     // pixels compared (empty: all)
    bool has_baseline = false;          // compare with a no-caustic baseline
    Baseline baseline;
};

// Everything a view's size and truth may come from on one frame. scene, geometry and chart are required;
// gbuffer, reference and analytic may be null (a view that needs them is then not measured).
struct ViewSources {
    const Scene* scene = nullptr;
    const FrameGeometry* geometry = nullptr;
    const ReceiverChart* chart = nullptr;
    const CameraGBuffer* gbuffer = nullptr;
    const ReferenceResult* reference = nullptr;
    const AnalyticTruth* analytic = nullptr;   // the receiver's closed form, where available
    const Image* flat = nullptr;                // flat_interface_baseline of the frame (null: computed when asked)
};
// A run's or the viewer's sources: the scene frame's, with its G-buffer.
ViewSources view_sources(const SceneFrame& sf, const ReferenceResult* reference, const AnalyticTruth* analytic,
                         const Image* flat = nullptr);

struct ViewSpec {
    std::string name;   // metrics.json's error.<name>; CausticOutput::views key for rows beyond the built-ins
    std::string unit;   // of the view's values when radiometric
    // Whether a scene asks for the view (the built-in camera_volume: where the medium scatters).
    std::function<bool(const Scene&)> requested = [](const Scene&) { return true; };
    // What the method must also support to be run on a scene that asks for the view (empty: nothing more);
    // `refusal` prefixes the method's reason.
    std::function<Capability(const Method&, const Scene&)> capability;
    std::string refusal;
    // The view's image in an output (null: the method did not produce it).
    std::function<const Image*(const CausticOutput&)> output;
    // Its expected size on the frame ({-1, -1}: not known from these sources, not checked), and the pixels
    // whose values are read (null: all).
    std::function<std::pair<int, int>(const ViewSources&)> size;
    std::function<const std::vector<std::uint8_t>*(const ViewSources&)> read_mask;
    // Fills the truth from the sources; false where there is none on this frame.
    std::function<bool(const ViewSources&, ViewTruth&)> truth;
    // The run's notes: when the method produced no image, when nothing was compared, when the run is no
    // better than its baseline (given the baseline's kind). Empty: no note.
    std::string missing_note;
    std::string empty_note;
    std::function<std::string(const std::string&)> no_better_note;
    std::string baseline_key;   // metrics.json's key for the baseline block (empty: none)
    // The view the method's accuracy claim speaks of (the receiver): metrics.json's top-level truth,
    // below_reference_noise, claim judgement and no_better_than_flat are its.
    bool primary = false;
};

// The built-in rows (receiver, camera, camera_volume), then every registered one. A deque: pointers to rows
// stay valid when a row is added.
const std::deque<ViewSpec>& view_table();
// Adds a row (a view name already in the table is refused with std::invalid_argument). Not thread-safe:
// register before runs start (at static initialisation, or at the start of a test).
void register_view(ViewSpec spec);

// The rows `scene` asks for.
std::vector<const ViewSpec*> requested_views(const Scene& scene);

// The requested views `method` supports on `scene` (none where it refuses the scene itself), in table order.
std::vector<const ViewSpec*> supported_views(const Method& method, const Scene& scene);

// Whether `method` renders `scene`: its capabilities, and every requested view's (a run measures all the
// views a scene asks for, or is refused with the first unsupported view's reason). The one decision runs,
// sweeps, the viewer and the conformance suite share.
Capability decide_capability(const Method& method, const Scene& scene);

// Throws std::runtime_error when a produced view has the wrong size; returns the non-finite values over
// the pixels each view reads.
std::int64_t check_views(const CausticOutput& out, const ViewSources& sources, const std::string& method);

// One view measured: its errors and the truth's and baseline's kinds.
struct EvaluatedView {
    const ViewSpec* spec = nullptr;
    ViewErrors errors;
    std::string truth_kind;
    std::string baseline_kind;
    bool has_baseline = false;
    bool exact_truth = false;
};
// Every requested view the output holds and the sources have a truth for, in table order.
std::vector<EvaluatedView> evaluate_views(const CausticOutput& out, const ViewSources& sources, bool radiometric);

// The claim's judgement (docs/conformance.md; metrics.json's claim.bound and claim.met): `error` is the plain
// nrmse of the primary view (after the scale fit where the output is not radiometric) against the exact
// truth; the bound is AccuracyClaim::bound: the claim's stated error or half the no-caustic baseline's,
// the smaller, but never below min(stated error, 0.01).
struct ClaimJudgement {
    double bound = 0.0;
    bool met = false;
};
ClaimJudgement judge_claim(const AccuracyClaim& claim, double error, double baseline_error);

}  // namespace caustics
