// caustic_mapping: the parameter table (every option with its one-line doc) and the registration.
#include <algorithm>
#include <memory>
#include <string>

#include "caustic_mapping.hpp"
#include <caustics/api/registry.hpp>

namespace caustics::caustic_mapping {

Settings settings_from(const ParamSet& p) {
    Settings s;
    s.grid = static_cast<int>(p.get_int("grid"));
    // Auto: at least kMapPerGrid texels per grid vertex (and never below the former fixed 768), so the
    // footprints of the landing lattice (elliptic_splats.hpp) keep their size in texels as the grid is
    // refined: a map fixed while the grid grows makes its texels, not the grid, the limit on sharp caustics
    // (sine_oblique at grid 256 and map 768: nrmse 0.060, above grid 128's 0.044; with map 1536: 0.011).
    s.map = p.get_int("map") > 0 ? static_cast<int>(p.get_int("map"))
                                 : std::clamp(kMapPerGrid * s.grid, kMinAutoMap, kMaxAutoMap);
    s.estimator.kind = p.get_enum("estimator") == "newton" ? EstimatorKind::Newton : EstimatorKind::Approx;
    s.estimator.iterations = static_cast<int>(p.get_int("iterations"));
    s.estimator.d0 = p.get_float("d0");
    s.estimator.eps = p.get_float("eps");
    s.estimator.safeguard = p.get_enum("safeguard") == "bisection" ? Safeguard::Bisection : Safeguard::None;
    s.estimator.tolerance = p.get_float("tolerance");
    s.estimator.bisection_steps = static_cast<int>(p.get_int("bisection_steps"));
    s.flux = p.get_enum("flux_weight") == "paper" ? FluxWeight::Paper : FluxWeight::Radiometric;
    s.splat = p.get_enum("splat") == "point" ? SplatKernel::Point : SplatKernel::Gaussian;
    s.elliptic = p.get_enum("splat") == "elliptic";
    s.adaptive = s.elliptic || p.get_enum("splat") == "adaptive";
    s.splat_radius = p.get_float("splat_radius");
    s.lowpass = p.get_float("lowpass");
    const std::string& cube = p.get_enum("cube_map");
    s.cube = cube == "on" ? CubeMode::On : cube == "off" ? CubeMode::Off : CubeMode::Auto;
    s.bilinear = p.get_enum("filter") == "bilinear";
    s.extend = static_cast<int>(p.get_int("extend"));
    s.bin_samples = static_cast<int>(p.get_int("bin_samples"));
    s.absorption = p.get_bool("absorption");
    s.depth_bias = p.get_float("depth_bias");
    s.debug_maps = p.get_bool("debug_maps");
    s.map_auto = p.get_int("map") == 0;
    s.refine_past_focus = p.get_bool("refine_past_focus");
    return s;
}

MethodInfo caustic_mapping_info() {
    MethodInfo info;
    info.name = "caustic_mapping";
    info.doc =
        "Caustics mapping (Shah, Konttinen, Pattanaik 2007): light-space positions textures of the receivers and "
        "of the specular objects (one grid vertex per texel), per-vertex refraction (double surface for closed "
        "dielectrics via a back-face texture, single surface for water, one reflection for mirrors), image-space "
        "intersection estimation (the paper's approximate iteration or Newton-Raphson, optional bisection "
        "safeguard), splats into a caustic map, shadow-map style lookup. Directional and point lights (cube map "
        "when the receivers leave one frustum), spheres, meshes, boxes, height fields, mirrors; Fresnel on the "
        "transmitted path. Not supported: several lights, dispersion, participating media, light through more "
        "than one specular object, internal reflections (total internal reflection loses the ray), reflected "
        "parts of dielectrics.";
    info.radiometric = true;
    info.params = {
        {"grid", ParamType::Int, "128", 2, 4096, {}, "refractive vertex grid: specular positions/normals texture resolution (grid x grid)",
         {"64", "128"}},
        {"iterations", ParamType::Int, "3", 1, 1000, {}, "estimator iterations (updates of the distance d) per ray", {"1", "3"}},
        {"map", ParamType::Int, "0", 0, kMaxMap, {},
         "caustic-map and receiver positions texture resolution (map x map per face); 0: auto, 6 x grid, at least "
         "768 (the paper-era default, used up to grid 128) and at most 4096"},
        {"estimator", ParamType::Enum, "newton", 0, 0, {"approx", "newton"},
         "approx: d <- |lookup(v + d r) - v| (Sec. III.C-D); newton: Newton-Raphson with a forward difference "
         "(appendix; converges for oblique rays where approx at 3 iterations does not)",
         {"approx", "newton"}},
        {"d0", ParamType::Float, "0", 0.0, 1e6, {},
         "initial distance along the ray [m]; 0: start at the vertex (first lookup on its own light ray); paper: 1"},
        {"eps", ParamType::Float, "0.01", 1e-9, 10.0, {}, "Newton forward-difference step [m] (paper: 0.1)"},
        {"safeguard", ParamType::Enum, "bisection", 0, 0, {"none", "bisection"},
         "bisection: when the last two estimates oscillate around the surface, bisect that bracket (Sec. III.D)"},
        {"tolerance", ParamType::Float, "1e-4", 0.0, 1.0, {}, "convergence: |d_{k+1} - d_k| below this [m] stops early"},
        {"bisection_steps", ParamType::Int, "8", 1, 64, {}, "minimum bisection steps once the safeguard engages"},
        {"flux_weight", ParamType::Enum, "radiometric", 0, 0, {"radiometric", "paper"},
         "radiometric: E0 x texel area (I x solid angle) per vertex; paper: Eq. 6 (N.L)/V times the total flux"},
        {"splat", ParamType::Enum, "elliptic", 0, 0, {"point", "gaussian", "adaptive", "elliptic"},
         "point: one texel per vertex (the paper); gaussian: normalised (flux-conserving) Gaussian footprint of a "
         "fixed radius; adaptive: isotropic Gaussian of 1.75 x the larger local spacing of neighbouring vertices' "
         "landing points; elliptic: Gaussian whose covariance is the landing map's Jacobian times 0.55 grid "
         "spacings, 0.5 at the fold settings (follows the ray density in each direction: focused lines stay sharp across, no gaps along; "
         "adaptive and elliptic are not in the paper)"},
        {"splat_radius", ParamType::Float, "0", 0.0, 100.0, {},
         "Gaussian support in caustic-map texels (sigma = radius/3.5); 0: auto (gaussian: 2.5 grid spacings; "
         "adaptive, elliptic: the smallest footprint, 1 texel)"},
        {"lowpass", ParamType::Float, "0", 0.0, 64.0, {}, "flux-conserving Gaussian low-pass radius of the caustic map in texels; 0: off"},
        {"cube_map", ParamType::Enum, "auto", 0, 0, {"auto", "off", "on"},
         "point lights: six-face cube map for receivers (auto: when one frustum would exceed 60 degrees off-axis; off: one frustum clamped at 80)"},
        {"extend", ParamType::Int, "-1", -1, 1024, {},
         "extrapolate the receivers' positions texture this many texels (at most map/8) past their edges; -1: to "
         "the texture's edges, which also cover the specular objects (estimates started beside a receiver under "
         "tilted light step onto it); 0: the paper's null value at edges"},
        {"bin_samples", ParamType::Int, "0", 0, 16, {},
         "receiver map: n x n caustic-map lookups averaged per bin (a bin holds the mean over its area); 1: the "
         "bin centre (the paper's per-pixel lookup); 0: auto, n = caustic-map texels per bin side (at most 16)"},
        {"filter", ParamType::Enum, "bilinear", 0, 0, {"bilinear", "nearest"}, "positions texture lookups: bilinear or nearest texel"},
        {"absorption", ParamType::Bool, "true", 0, 0, {}, "Beer-Lambert absorption (Eq. 7) inside dielectrics / in the water"},
        {"depth_bias", ParamType::Float, "1.0", 0.0, 100.0, {}, "scale of the receiver lookup's slope-scaled depth bias (about two texels)"},
        {"refine_past_focus", ParamType::Bool, "true", 0, 0, {},
         "where the receiver lies 1.1 to 6 x the first focus depth under directional light within 40 deg of the "
         "vertical (water; map 0, elliptic splats, bilinear lookups, Newton's estimator with >= 3 iterations), draw "
         "the frame at grid max(grid, 512) with a map of 12 x that grid, the settings the claim past the focus was "
         "measured at (25-38 x the frame's time: pool 17 -> 437 ms, sine_deep 17 -> 625 ms); false: every frame at "
         "grid and map (the paper)",
         {"false", "true"}},
        {"debug_maps", ParamType::Bool, "false", 0, 0, {}, "also output the caustic map (face 0, flux per texel) as a debug image"},
    };
    info.create = make_caustic_mapping;
    return info;
}

CAUSTICS_REGISTER_METHOD(caustic_mapping_info);

}  // namespace caustics::caustic_mapping
