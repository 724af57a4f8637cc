#pragma once
// caustic_mapping: Shah, Konttinen, Pattanaik, "Caustics Mapping: An Image-space Technique for Real-time
// Caustics" (2007; docs/papers.md). Internal interface shared by the plugin's translation units.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "estimator.hpp"
#include "geometry.hpp"
#include <caustics/api/method.hpp>
#include "positions_texture.hpp"
#include <caustics/blocks/regime/first_focus.hpp>
#include <caustics/blocks/splat/splat.hpp>

namespace caustics::caustic_mapping {

enum class FluxWeight { Radiometric, Paper };
enum class CubeMode { Auto, Off, On };

constexpr int kMapPerGrid = 6;      // map = 0 (auto): caustic-map texels per grid vertex
constexpr int kMinAutoMap = 768, kMaxAutoMap = 4096;
constexpr int kMaxMap = 8192;       // the largest map the `map` parameter accepts

struct Settings {
    int grid = 128;
    int map = 768;
    EstimatorSettings estimator;
    FluxWeight flux = FluxWeight::Radiometric;
    SplatKernel splat = SplatKernel::Gaussian;
    bool adaptive = true;          // per-splat radius from the neighbours' landing spacing (splats.hpp)
    bool elliptic = true;          // per-splat covariance from the landing map's Jacobian (elliptic_splats.hpp)
    double splat_radius = 0.0;   // texels; 0: auto (gaussian: 2.5 grid spacings; adaptive: minimum 1)
    double lowpass = 0.0;        // texels; 0: off
    CubeMode cube = CubeMode::Auto;
    bool bilinear = true;
    int bin_samples = 0;           // receiver map: n x n lookups per bin; 0: auto (texels per bin side)
    int extend = -1;               // texels the receivers' positions are extrapolated past their edges; -1: all
    bool absorption = true;
    double depth_bias = 1.0;
    bool debug_maps = false;
    bool map_auto = true;          // `map` was 0: the map follows the grid (and the fold refinement's grid)
    bool refine_past_focus = true;       // past the first focus, the frame is drawn at the fold regime's settings
};

// Per-render health, summed over threads.
struct Counters {
    std::int64_t covered = 0, grazing = 0, null_value = 0, null_exit = 0, not_converged = 0, oscillating = 0,
                 bisection = 0, bad_derivative = 0, tir = 0, nonfinite = 0, lookups = 0, lost_outside = 0,
                 missed = 0;
    void add(const Counters& o);
};

Settings settings_from(const ParamSet& p);

// The claimed regime (Method::accuracy_claim), measured on the fixed and drawn sine cases at the default map
// (README.md): water (a dielectric height field) under one light at most kMaxTiltDeg from the vertical,
// grid >= kMinGrid, the receiver at most kMaxFocusFraction of the way to the refracted wave's first focus
// (blocks/regime): nrmse <= kClaimError (at the defaults, over 1,200 drawn cases of six seeds: 0.040 up to 0.8
// of the way, 0.049 between 0.8 and 0.9, hence the 0.8; the fixed sine_oblique, 0.91 of the way, was outside before too).
constexpr double kMaxTiltDeg = 45.0, kMaxFocusFraction = 0.8, kClaimError = 0.05;
constexpr int kMinGrid = 64;
// The fold regime: past the first focus the error is the grid's sampling of the surface and the map's
// texels across the folds (README.md "Past the first focus"). With grid >= kFoldMinGrid, a map of exactly
// kFoldMapPerGrid texels per grid spacing (the setting measured: grid 512, map 6144), the elliptic splats,
// bilinear lookups and Newton's estimator with at least kFoldMinIterations, under directional light, nrmse
// <= kFoldClaimError from
// kFoldMinFocusFraction to kFoldMaxFocusFraction x the first focus under light at most kFoldMaxTiltDeg from
// the vertical (the drawn cases' range). Just past the focus the cusp where the two folds meet lies near
// the receiver and its peak bins are not held (up to 0.14 measured between 1.0 and 1.1 x).
constexpr double kFoldClaimError = 0.10, kFoldMinFocusFraction = 1.1, kFoldMaxFocusFraction = 6.0,
                 kFoldMaxTiltDeg = 40.0;
constexpr int kFoldMinGrid = 512;
constexpr double kFoldMapPerGrid = 12.0;
// Caustic-map texels per grid spacing where the claims were measured: at 3 (grid 256, map 768) the map's
// texels limit sharp lines (sine_oblique 0.060), at 48 (grid 128, map 6144) the error before the focus was
// 0.26 on drawn cases; 6 (the auto map up to grid 682; it stops at kMaxAutoMap) and 12 were measured within
// the claims, 24 reached 0.040 against the claimed 0.05, so the bound stays at 16.
constexpr double kMinMapPerGrid = 6.0, kMaxMapPerGrid = 16.0;
constexpr int kMinApproxIterations = 3;   // the approximate estimator's claim under tilted light
constexpr int kFoldMinIterations = 3;    // Newton's iterations the fold regime was measured with (the default)
// The settings a frame is drawn with. `s` itself, except where refine_past_focus is on, the map automatic, the
// light directional and the frame in the fold regime's reach but not in the settings' own (the receiver
// kFoldMinFocusFraction to kFoldMaxFocusFraction x the first focus, light within kFoldMaxTiltDeg, the
// elliptic splats, bilinear lookups and Newton's estimator with at least kFoldMinIterations): there the grid
// is raised to kFoldMinGrid and the map to kFoldMapPerGrid x the grid, the settings the fold regime was
// measured at. Nowhere else: refining elsewhere would cost 25-38 x the frame (pool, sine_deep) and widen no
// claim. render() decides it from the first focus alone (regime::RegimeParts::FocusOnly), claim_for() from
// the full regime: the same depth ratio and tilt.
Settings frame_settings(const FrameGeometry& frame, const Settings& s);
// Whether `s` has the grid and map the fold regime was measured at (grid >= kFoldMinGrid, a map of exactly
// kFoldMapPerGrid texels per grid spacing): its claim, and the splats' width (elliptic_splats.hpp).
bool fold_resolution(const Settings& s);
// The claim of the settings `s` on the frame, at the settings frame_settings() draws it with.
AccuracyClaim claim_for(const FrameGeometry& frame, const Settings& s);
MethodInfo caustic_mapping_info();
std::unique_ptr<Method> make_caustic_mapping(const ParamSet& p);

}  // namespace caustics::caustic_mapping
