#pragma once
// Where the first-arrival model of eikonal_fmm stops: the depth of the first focus of the refracted
// plane wave under a height-field interface (where the Snell map onto a horizontal plane first folds),
// and the rays' spread about the mean refracted direction. Used by accuracy_claim and the volume.
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>

namespace caustics::eikonal {

struct FocusAnalysis {
    double first_focus_depth = 1e300;  // below `surface_z` [m]; 1e300: the rays never cross
    double max_curvature = 0.0;        // largest convex curvature of the surface [1/m] (for messages)
    bool shadowed = false;             // some interface point faces away from the light (grazing light)
};

// Over every interface vertex: the ray through (x, h) with refracted direction t reaches depth z at
// X = x + u (h - z), u = t_xy / |t_z|; dX/dx = I + u grad(h)^T + (h - z) grad(u) loses rank at the
// smallest positive root of its determinant (a quadratic in h - z), the local focus. Paraxially, at
// normal incidence this is n / ((n - 1) kappa) for a crest of curvature kappa.
FocusAnalysis analyze_focus(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z);
// The same per interface vertex: the depth below surface_z where the ray entering there focuses
// (1e300: never), hf.nx x hf.ny values, row-major.
std::vector<double> focus_depth_map(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z);

// Largest horizontal run per metre of depth between a ray refracted at the steepest slope and the flat
// interface's ray (the widening of the region the light of a receiver enters through).
double ray_spread(const HeightField& hf, const glm::dvec3& light, double ior);

}  // namespace caustics::eikonal
