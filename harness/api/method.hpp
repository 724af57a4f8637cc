#pragma once
// The plugin interface every caustics method implements (docs/design.md section 4).
//
// Life cycle, as the harness drives it (docs/design.md section 6):
//   auto m = info.create(params);           // parameters already validated against info.params
//   m->capabilities(scene)                  // supported, or a human-readable reason
//   m->prepare(scene)                       // once per scene: timed, reported as prepare_ms
//   per frame: m->update(frame)             // dynamic-geometry work: timed, update_ms
//              m->render(frame, request)    // timed; warm-up then repeats
#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/util/image.hpp>
#include <caustics/api/params.hpp>
#include <caustics/frame/receiver_chart.hpp>

namespace caustics {

struct Capability {
    bool supported = true;
    std::string reason;   // why not, when unsupported
    static Capability yes() { return {}; }
    static Capability no(std::string why) { return {false, std::move(why)}; }
};

// Health counters are data, not logs. Conventional names (use them where they apply):
//   nonfinite        values that came out NaN/Inf (the harness also counts them in the output)
//   lost_samples     estimator lookups that fell off the receiver, refracted rays that missed it
//   not_converged    iterative estimates that did not converge
//   clamped          steps or values clamped to stay finite
//   not_covered      requested receiver points the method cannot shade (e.g. walls)
struct Health {
    std::map<std::string, std::int64_t> counters;
    void add(const std::string& name, std::int64_t n = 1) { counters[name] += n; }
    std::int64_t get(const std::string& name) const {
        auto it = counters.find(name);
        return it == counters.end() ? 0 : it->second;
    }
};

// A periodic caustic texture (Stam, "Periodic Caustic Textures"; `caustics synth`): the caustic
// irradiance on a horizontal plane `depth` metres below the water surface's base level, over exactly one
// spatial period of the water height field (its rectangle), so that the texture tiles the plane.
// Texel (i, j) is centred at world x = x0 + (i + 1/2) Lx / width, y = y0 + (j + 1/2) Ly / height, where
// (x0, y0) is the rectangle's corner of least x and y and Lx x Ly its size (row 0 at the least y).
// Light leaving the tile on one side re-enters on the other (toroidal accumulation).
struct TextureRequest {
    int width = 512;
    int height = 512;
    double depth = 1.0;   // [m] below the water's base height
};

// One measurable quantity of a frame that bounds a claimed regime: the frame's value as the method measures
// it and the limit the claim holds to (inside while value <= limit, or >= limit for a lower bound). The
// conformance suite recomputes the quantities it knows independently of the method (tilt_deg,
// depth_over_first_focus, ior: tests/conformance_regime.hpp) and checks a case called outside really lies
// beyond the stated limit; it also widens each bound to check the regime is not wider than the method.
struct RegimeBound {
    std::string quantity;   // e.g. "tilt_deg", "depth_over_first_focus", "finest_grid"
    double value = 0.0;
    double limit = 0.0;
    bool upper = true;      // true: inside while value <= limit; false: inside while value >= limit
    bool holds() const { return upper ? value <= limit : value >= limit; }
};

// The error a method claims where it states nothing else: an absolute nrmse against the exact truth.
inline constexpr double kDefaultClaimError = 0.10;
// The rms ripple allowed where the truth is flat or nearly so (std/mean over the lit bins, or nrmse where
// half the no-caustic baseline's error is below it).
inline constexpr double kFlatTolerance = 0.01;

// The accuracy a method claims on one frame of a scene at its current parameters: an absolute bound a user
// can rely on. Inside the claimed regime the receiver error against the exact truth (nrmse; after the
// least-squares scale fit where the output is not radiometric) is at most `max_error`, and at most half of
// the error of drawing no caustic (the flat interface's irradiance, harness/frame/baseline.hpp), whichever is
// smaller (bound()). The conformance suite (tests/test_conformance.cpp) holds every registered method to it
// on analytic cases, fixed and randomly drawn. `bounds` lists the measurable quantities that delimit the
// regime with this frame's values. Outside it (`inside` false), `reason` names the bound the frame passes,
// with the numbers (e.g. "the floor lies 1.2 m down, past the first focus at 0.64 m"): the method still
// renders, its error is still measured and reported, but nothing is claimed. A case a method cannot render
// at all is refused by capabilities() instead.
struct AccuracyClaim {
    bool inside = true;
    double max_error = kDefaultClaimError;   // absolute nrmse (after the scale fit for relative outputs)
    std::string reason;
    std::vector<RegimeBound> bounds;
    // The error this frame is held to, given the no-caustic baseline's error against the same truth: the
    // stated error or half the baseline's, whichever is smaller, but never below kFlatTolerance (where the
    // truth is nearly flat, an rms ripple of 1 % is allowed, as a flat truth allows std/mean 1 %).
    double bound(double baseline_error) const {
        return std::max(std::min(max_error, 0.5 * baseline_error), std::min(max_error, kFlatTolerance));
    }
    static AccuracyClaim within(double max_error, std::vector<RegimeBound> bounds = {}) {
        return {true, max_error, {}, std::move(bounds)};
    }
    static AccuracyClaim outside(std::string why, std::vector<RegimeBound> bounds = {}) {
        return {false, 0.0, std::move(why), std::move(bounds)};
    }
};

struct RenderRequest {
    const ReceiverChart* receiver = nullptr;     // fill CausticOutput::receiver when non-null
    const CameraGBuffer* camera = nullptr;       // fill CausticOutput::camera when non-null
    // Fill CausticOutput::texture (and texture_rgb with dispersion) when non-null. Only methods whose
    // texture_capability() says yes are asked; the others may ignore it.
    const TextureRequest* texture = nullptr;
    // Fill CausticOutput::camera_volume. Asked only of methods whose volume_capability() says yes, on
    // scenes where some medium scatters (scene_scatters).
    bool camera_volume = false;
};

struct CausticOutput {
    Image receiver;       // chart width x height, 1 channel, E_c [W/m^2] (relative if not radiometric)
    Image receiver_rgb;   // optional colour version (dispersion), 3 channels
    Image camera;         // gbuffer width x height, 1 channel; only covered pixels are read
    Image texture;        // TextureRequest width x height, 1 channel, E_c [W/m^2] (see TextureRequest)
    Image texture_rgb;    // optional colour version of the texture (dispersion), 3 channels
    // Volume caustic radiance L_v [W/(m^2 sr)] (docs/design.md section 3), camera G-buffer width x height, 1
    // channel: per pixel, the radiance scattered once towards the camera, along the primary ray from
    // kVolumeNearDistance (frame/camera.hpp, 5 cm) off the pinhole to its first hit (to infinity on a
    // miss) and inside the camera's own medium
    // (medium_at(scene, gbuffer.medium_object)), by light that had at least one specular event,
    // attenuated by extinction along the whole path. Scattering seen through a refracting surface is not
    // part of it. Every pixel is read.
    Image camera_volume;
    std::map<std::string, Image> debug;                  // optional: caustic map, overlays
    std::map<std::string, Image> views;                  // further views, keyed by their view-table row name
    std::vector<std::pair<std::string, double>> stages_ms;  // optional per-stage timings of render()
    Health health;
};

class Method {
public:
    virtual ~Method() = default;
    virtual Capability capabilities(const Scene& /*scene*/) const { return Capability::yes(); }
    // Whether render() can fill a periodic texture (RenderRequest::texture) for this scene.
    virtual Capability texture_capability(const Scene& /*scene*/) const {
        return Capability::no("does not synthesise periodic textures");
    }
    // Whether render() can fill camera_volume for this scene. A scene with a scattering medium
    // (scene_scatters) is rendered only by methods that say yes: its caustics are attenuated by
    // extinction and include the volume view; the others are skipped with this reason.
    virtual Capability volume_capability(const Scene& /*scene*/) const {
        return Capability::no("does not render volume caustics (camera_volume)");
    }
    virtual void prepare(const Scene& /*scene*/) {}
    virtual void update(const FrameGeometry& /*frame*/) {}
    virtual CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) = 0;
    // The accuracy this method claims on `frame` (asked after update(frame)). The default claims an nrmse of
    // kDefaultClaimError (and half the no-caustic baseline's) everywhere, which a method added later is held
    // to until it states its own regime.
    virtual AccuracyClaim accuracy_claim(const FrameGeometry& /*frame*/) const {
        return AccuracyClaim::within(kDefaultClaimError);
    }
};

struct MethodInfo {
    std::string name;
    std::string doc;
    bool radiometric = true;        // false: output is relative; metrics add a least-squares fit
    // Where a parameter switches the output between radiometric and relative values (an output mode):
    // the answer for a parameter set. Unset: `radiometric` for every parameter set.
    std::function<bool(const ParamSet&)> radiometric_for;
    bool radiometric_at(const ParamSet& p) const { return radiometric_for ? radiometric_for(p) : radiometric; }
    std::vector<ParamSpec> params;  // must contain `grid` and `iterations`
    std::function<std::unique_ptr<Method>(const ParamSet&)> create;
};

}  // namespace caustics
