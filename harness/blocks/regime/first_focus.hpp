#pragma once
// The measurable quantities accuracy claims state their regimes in (Method::accuracy_claim, RegimeBound):
// the depth of the first focus of the plane wave refracted by a height-field interface (where the Snell
// map onto a horizontal plane first folds), the light's tilt, the receiver's depth, and the rays' spread
// about the mean refracted direction. One definition for every method, so that "past the first focus"
// means the same in every claim; the conformance suite recomputes them from closed forms
// (tests/conformance_regime.hpp).
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/api/method.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>

namespace caustics::regime {

struct FocusAnalysis {
    double first_focus_depth = 1e300;  // below `surface_z` [m]; 1e300: the rays never cross
    double max_curvature = 0.0;        // largest convex curvature of the surface [1/m] (for messages)
    bool shadowed = false;             // some interface point faces away from the light (grazing light)
};

// The direction refracted from air into index `ior` (Snell, vector form) for a unit light direction and a
// unit normal facing the light's side; air to a denser medium never totally reflects.
glm::dvec3 refract_direction(const glm::dvec3& light, const glm::dvec3& normal, double ior);

// Over every interface vertex: the ray through (x, h) with refracted direction t reaches depth z at
// X = x + u (h - z), u = t_xy / |t_z|; dX/dx = I + u grad(h)^T + (h - z) grad(u) loses rank at the
// smallest positive root of its determinant (a quadratic in h - z), the local focus. Paraxially, at
// normal incidence this is n / ((n - 1) kappa) for a crest of curvature kappa.
FocusAnalysis analyze_focus(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z);
// Its first_focus_depth alone: the smallest of focus_depth_map's values.
double first_focus_depth(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z);
// The same per interface vertex: the depth below surface_z where the ray entering there focuses
// (1e300: never), hf.nx x hf.ny values, row-major.
std::vector<double> focus_depth_map(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z);

// Largest horizontal run per metre of depth between a ray refracted at the steepest slope and the flat
// interface's ray (the widening of the region the light of a receiver enters through).
double ray_spread(const HeightField& hf, const glm::dvec3& light, double ior);

// The surface's feature scale and its sharpest focusing curvature, over its vertices.
struct SurfaceScales {
    double feature = 0.0;             // 2 pi rms slope / rms curvature [m] (the period of a sine; 0: flat)
    double focusing_curvature = 0.0;  // the largest -(smallest Hessian eigenvalue) [1/m]: crests focus
};
SurfaceScales surface_scales(const HeightField& hf);

// A frame's water regime: one dielectric height field lit by the scene's first light (directional, or a
// point light taken along its direction to the water's centre), over the diffuse receivers below it.
struct WaterRegime {
    bool valid = false;               // false: no dielectric height field or no light
    const ObjectInstance* water = nullptr;
    double tilt_deg = 0.0;            // the light's angle from the vertical
    double surface_z = 0.0;           // the water's mean level
    double depth = 0.0;               // the deepest diffuse receiver point below surface_z [m] (0: none)
    FocusAnalysis focus;              // of the refracted plane wave, below surface_z
    double ior = 1.0;
    double feature_length = 0.0;      // surface_scales(...).feature [m]
    // depth / first focus depth: < 1 before the first focus, > 1 past it (0 where the rays never cross).
    double depth_over_first_focus() const {
        return focus.first_focus_depth < 1e299 ? depth / focus.first_focus_depth : 0.0;
    }
};
// What water_regime computes: everything, or (for a decision taken every frame) the first focus alone, with
// focus.max_curvature, focus.shadowed and feature_length left at their defaults.
enum class RegimeParts { All, FocusOnly };
WaterRegime water_regime(const FrameGeometry& frame, RegimeParts parts = RegimeParts::All);

// The claim of a regime delimited by `bounds`: within max_error where every bound holds, else outside with
// the reason `explain` gives for the first bound that fails (the bounds are kept either way).
AccuracyClaim claim_within_bounds(std::vector<RegimeBound> bounds, double max_error,
                                  const std::function<std::string(const RegimeBound&)>& explain);

// "name 1.36 > 1" (or "< limit" for a lower bound), three significant digits.
std::string describe(const RegimeBound& b);

}  // namespace caustics::regime
