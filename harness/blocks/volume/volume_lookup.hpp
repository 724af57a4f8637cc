#pragma once
// Reading a volume caustic texture at receiver points (the render() of the volume methods) and the flux
// normalization of the relative ones (Mercier 2013).
#include <glm/glm.hpp>

#include <caustics/api/method.hpp>
#include <caustics/scene/scene.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>

namespace caustics {

// Mean transmitted irradiance [W/m^2] that a flat interface would deliver onto a receiver with unit
// normal `receiver_normal` (directional light `scene.lights[0]`, Fresnel transmittance when
// scene.fresnel). The flux normalization of the relative volume methods targets it.
double flat_transmitted_irradiance(const Scene& scene, double ior, const glm::dvec3& receiver_normal);
// Refracted direction of the directional light through a horizontal interface (unit, downward).
glm::dvec3 mean_refracted_direction(const Scene& scene, double ior);

// ---- Receiver lookups into a caustic texture (the render() of the volume methods) ----

struct VolumeLookup {
    const VolumeF* texture = nullptr;   // caustic values; the box is texture->shape
    bool normalize_flux = true;          // scale so the receiver's mean equals the transmitted irradiance
    double ior = 1.33;                   // the interface's index (flux target, scaled mapping)
    // Mercier's Fig. 2b: the texture was computed with an infinite refractive index (fronts move along
    // the interface normals); a finite index is approximated by reading the texture at the point whose
    // depth below `surface_z` along the mean refracted direction is scaled by (n - 1) / n, which maps
    // the paraxial focus R of the infinite model to n R / (n - 1).
    bool scaled_ior = false;
    double surface_z = 0.0;
    // Light enters through the water's rectangle only (when given, hi > lo): a point whose ray along
    // the mean refracted direction (the flat interface's) comes from outside it is unlit and reads 0,
    // and the flux normalization leaves it out. Only oblique light makes such points inside the box:
    // the strip below the water's edge that the refracted sunlight moves away from.
    glm::dvec2 water_lo{0.0}, water_hi{0.0};
};

// Fills the receiver map (trilinear lookup at every bin's centre point) and the camera view (at the
// G-buffer positions of covered pixels) that `request` asks for. Points outside the box give 0 and
// are counted in health "outside_volume". With normalize_flux the scale is fitted on the receiver map
// (built from the scene's receiver resolution when the request has none).
CausticOutput render_volume_texture(const FrameGeometry& frame, const RenderRequest& request,
                                    const VolumeLookup& lookup);

}  // namespace caustics
