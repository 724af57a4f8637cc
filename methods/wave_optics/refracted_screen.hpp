#pragma once
// The refracted wave on the reference plane (the water's mean level), built from the exact refraction at
// every surface point: the default input field of the wave_optics propagator.
//
// Stam's algorithm (1996, "The Algorithm") multiplies a plane wave at normal incidence by a thin phase
// screen phi = k0 (n - 1) h, unit amplitude, taken at the same lateral point. That is the first-order
// model of the interface: at oblique light it misses first-order terms (the flux the tilted surface
// intercepts, cos_i + d_xy . grad h per unit area, and the lateral offset h tan(theta_t) between the
// surface point and where its refracted light crosses the reference plane), and near a focus, where the
// intensity depends on the focal length to the order of (1 - z / f)^-1, even second-order terms of the
// slope move the caustic. The field here is the geometric-optics (WKB) field of the refracted wave
// continued, inside the water, to the plane z = level: each surface sample x_s refracts the light exactly
// (Snell with the local normal, optional local Fresnel transmittance) into the unit direction t; its ray
// crosses the plane at X = x_s + h t_xy / |t_z| with
//   optical path (relative to the carrier d_xy . X)   P = h [(n - d_xy . t_xy) / |t_z| - cos_i]
//   flux density (relative to flat water)             a^2 = (cos_i + d_xy . grad h) T(local) e^(-Ka h / |t_z|)
//                                                            / (cos_i T(flat) det dX/dx_s)
// and u(X) = a exp(2 pi i P / lambda0) (lambda0: vacuum wavelength). The phase gradient is then the exact
// refracted transverse wave vector (the eikonal property), and |u|^2 the exact flux, so that free
// propagation from this plane (angular spectrum: exact in the homogeneous water) tends to the exact
// Snell mapping as lambda -> 0 wherever the rays have not crossed. At ior = 1 it is exactly flat.
// For a flat surface it reduces to P = h (n cos_t - cos_i), a = 1: Stam's screen.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/blocks/fft/fft.hpp>

namespace caustics::wave_optics {

struct RefractionSetup {
    int nx = 0, ny = 0;
    double lx = 1.0, ly = 1.0;             // period [m]
    glm::dvec3 light{0.0, 0.0, -1.0};      // unit direction of the incident light (z < 0)
    double ior = 1.33;
    bool fresnel = false;                  // local Fresnel transmittance T(local) / T(flat)
    double absorption = 0.0;               // Ka [1/m]: the path between the surface and the plane
};

struct RefractedScreen {
    std::vector<float> path;        // P(X) [m], nx * ny, row-major
    std::vector<float> amplitude;   // a(X)
    std::int64_t folded_cells = 0;  // surface samples whose map to the plane folds (det dX/dx_s <= 0): no flux there
    std::int64_t unlit_cells = 0;   // surface samples facing away from the light (no transmitted flux)
    // Scratch, per surface sample: offset to the crossing [cells], P, flux density (kept between calls).
    struct Sample {
        float dx, dy, path, density;
    };
    std::vector<Sample> samples;
};

// Builds the screen from heights above the reference plane on the nx x ny periodic grid (sample (i, j) at
// (i lx / nx, j ly / ny)).
void build_refracted_screen(const float* height, const RefractionSetup& setup, RefractedScreen& out);

// Unpolarised Fresnel transmittance from air into a medium of index n at incidence cosine ci.
double fresnel_transmittance(double ci, double n);

// u = a exp(i k0 P) of a refracted screen into `field` (n x n); returns the cells whose phase step to the
// next cell in x or y exceeds pi (the screen is under-resolved there), as set_phase_screen() does.
std::int64_t screen_field(const RefractedScreen& screen, int n, double k0, std::vector<ComplexF>& field);

}  // namespace caustics::wave_optics
