#pragma once
// The no-caustic baseline (docs/design.md section 6): what a flat interface would transmit, and the pieces of
// flat-interface optics that the volume methods' flux normalization (volume_lookup.cpp) shares with it.
#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/util/image.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

// Unpolarised Fresnel transmittance 1 - (rs^2 + rp^2) / 2 of a dielectric interface (the reflectance the
// reference's Russian roulette uses, reference.cpp).
double fresnel_transmittance(double cos_i, double cos_t, double n_i, double n_t);

// A directional light refracted by a horizontal interface from index n_outside into index ior.
struct FlatTransmission {
    glm::dvec3 direction{0.0, 0.0, -1.0};  // refracted direction (unit, downward)
    double horizontal_irradiance = 0.0;     // flux per horizontal area below the interface: E0 cos_i T
};
FlatTransmission flat_interface_transmission(const Light& light, double n_outside, double ior, bool fresnel);

// Length of the straight path along `direction` from the plane z = surface_z down to p.
double refracted_path_length(const glm::dvec3& p, const glm::dvec3& direction, double surface_z);

// Whether the ray along `direction` that reaches p crossed the plane z = surface_z inside the rectangle
// [lo, hi] (the water's): the strip below the water's edge that oblique light moves away from is unlit.
bool enters_through_rectangle(const glm::dvec3& p, const glm::dvec3& direction, double surface_z,
                              const glm::dvec2& lo, const glm::dvec2& hi);

// What the flat interface would transmit, for scenes whose specular object is one height-field dielectric
// interface lit by directional lights: per bin, the mean over 4 x 4 sub-points (weighted by true area) of
// sum over lights E0 cos_i T_fresnel (if scene.fresnel) exp(-Ka L) |t . n_r| / |t_z|, zero where the flat
// interface's refracted ray through the point enters outside the water rectangle or the point is above
// the interface. The flat interface is at the height field's base height; occlusion by other objects is
// not modelled (a baseline, not a reference). Empty Image when the scene is not of that kind.
Image flat_interface_baseline(const FrameGeometry& frame, const ReceiverChart& chart);

}  // namespace caustics
