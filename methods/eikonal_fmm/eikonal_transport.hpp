#pragma once
// Radiometric output of the eikonal method: the transport equation of geometric optics along the rays
// of the eikonal solution T (|grad T| = 1 in water), d ln I / ds = -Laplacian T - Ka (s the path length
// along grad T, I the irradiance across the ray, Ka the absorption), integrated layer by layer downward.
// Not in Mercier 2013, whose texture is the curvature itself (Sec. 3.1); this is the physics it
// approximates (the intensity law of the eikonal equation: div(I grad T) = -Ka I). Exposed for the
// tests; the plugin is eikonal_fmm.cpp.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>

namespace caustics::eikonal {

struct TransportInput {
    const HeightField* interface = nullptr;
    glm::dvec3 light{0.0, 0.0, -1.0};  // direction the incident light travels (unit)
    double irradiance = 1.0;            // E0 on a plane perpendicular to the light [W/m^2]
    double ior = 1.33;
    bool fresnel = false;               // Fresnel transmittance at the interface
    double absorption = 0.0;            // Ka [1/m] in the water
    // Depth below the interface's mean height of the first focus (blocks/regime/first_focus.hpp); 1e300: none.
    double first_focus_depth = 1e300;
    // Optional, finer: each interface vertex's focus depth (focus_depth_map, hf.nx x hf.ny) and the rays'
    // spread about the mean refracted direction (ray_spread). A cell at depth D is then past the first
    // focus only if a ray that can reach it (entering within spread D of the mean ray through it) has
    // focused above it, so a steep ripple does not end the model under the whole surface.
    const std::vector<double>* focus_map = nullptr;
    double spread = 0.0;
};

struct TransportStats {
    std::int64_t past_first_focus = 0;  // water cells deeper than the first focus
    std::int64_t clamped = 0;           // cells whose ray direction was nearly horizontal (clamped)
    std::int64_t nonfinite = 0;
};

// Fills `out` (T's shape) with the irradiance on a horizontal receiver, E = I |grad T . z|, in the
// water below the interface and 0 in the air. `lap` is the 7-point Laplacian of T (1/length).
// Near the interface (within two cells) I is set from flux conservation across it, along the exact
// refracted ray: E0 cos_i T_fresnel dA = I cos_t dA. Below, each cell traces its (straight) ray back
// up to 8 layers (semi-Lagrangian), interpolates ln I there and integrates -Laplacian T - Ka over the
// step. Cells deeper than the first focus (of the rays that can reach them, with focus_map) are past it: first-arrival times no longer describe the
// light there (rays have crossed; the first-arrival front has kinks that swallow them). They are
// counted and hold the flat interface's transmitted irradiance (with absorption along the mean
// refracted ray), what the light averages to, so the values stay bounded and the flux close.
void transport(const VolumeD& T, const VolumeF& lap, const TransportInput& in, VolumeF& out, TransportStats& stats);

}  // namespace caustics::eikonal
