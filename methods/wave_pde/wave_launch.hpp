#pragma once
// The physical launch of wave_pde (departure from Mercier 2013, Sec. 4, where phi = 1 on every
// interface cell at t = 0, i.e. every interface point emits at once: the limit of an infinite index,
// whose output ignores n and is not flat at n = 1).
//
// Here the launch is the refracted wave itself: the incident plane wave reaches the interface point p at
// T0(p) = (d . p) / n in water path length (the wave equation's unit: the grid's wave speed is that of
// light in water, c = h = 1), for the light's direction d and the index n. Geometric optics carries it
// from p along the Snell direction t_p to a horizontal source plane z0 one cell below the lowest point
// of the surface (a thin slab: the caustic forms far below it), where it arrives at
// T(x) = T0(p) + |x - p| with the horizontal irradiance |d . N(p)| T_F / J (N = (-grad eta, 1), the
// incident flux per unit footprint, J the Jacobian of the map p -> x, T_F Fresnel's transmittance when
// the scene asks for it). Each cell of a Gaussian sheet (width 1 cell) about the plane emits a pulse
// at the local plane wave's time T(x) + t_z dz, with the weight sqrt(E |t_z|) (a horizontal profile
// integrates along t to sqrt(2 pi) / |t_z|, so the emitted amplitude squared is E / |t_z|, the
// intensity of a wave that lays E on a horizontal plane). Times and positions are continuous: the
// surface's height enters the phase exactly, so waves far below one cell in amplitude still bend the
// front; the sheet's cells emit in phase along t, so it radiates the refracted wave downwards (the
// upward wave is spread over the sheet's thickness and leaves through the top band).
//
// Why a flat plane and not a sheet along the surface: a corrugated sheet of in-phase monopoles is
// transparent only in the short-wave limit; at the grid's wavelengths (about 2 pi pulse widths) it
// scatters, about 5 % of modulation at n = 1 on the sine at grid 64. On the plane, n = 1 gives T = d . x
// and a uniform E exactly: the emitted wave is the undisturbed plane wave and the texture is flat.
// Rays that cross between the surface and the plane (a focus within the slab, i.e. amplitudes of the
// order of the focal length) are counted (folded_columns) and emit nothing.
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>
#include "wave_solver.hpp"

namespace caustics::wave {

struct Launch {
    Source source;
    // The time after which a cell no longer accumulates: the latest first arrival of the refracted
    // front there (bounded by Fermat's principle along the mean refracted direction) plus the pulse's
    // extent and `margin`; stop[k]: the largest over layer k (non-increasing in k).
    CellWindow window;
    std::vector<double> stop;
    double plane_z = 0.0;               // the source plane's height
    std::int64_t shadowed_columns = 0;  // columns the light meets from below (grazing slopes): no source
    std::int64_t folded_columns = 0;    // columns whose rays cross above the plane: no source
};

// The sheet's lateral aperture along x (axis 0) and y (axis 1): the weights are 0 before index
// begin[a] and from end[a] on, and rise as sin^2 over ramp_begin[a] (ramp_end[a]) cells after begin
// (before end). A soft edge: a hard one diffracts fringes of several percent a Fresnel width
// sqrt(lambda depth) into the light it bounds, a sin^2 ramp of about that width next to none.
struct Aperture {
    int begin[2] = {-1 << 30, -1 << 30}, end[2] = {1 << 30, 1 << 30};
    int ramp_begin[2] = {0, 0}, ramp_end[2] = {0, 0};
    double weight(int i, int j) const;
};

// `light`: unit direction the light travels in; `mean_refracted`: the flat interface's refracted
// direction (unit, downward); times in c = h = 1 units, shifted so the earliest pulse starts after t = 0.
Launch phase_delay_launch(const HeightField& hf, const VolumeShape& grid, const glm::dvec3& light, double ior,
                          bool fresnel, const glm::dvec3& mean_refracted, double pulse_width, double margin,
                          const Aperture& aperture);

// The cells of the lateral padding on the low and high face of an axis along which the refracted light
// travels sideways, for a volume whose faces have the damping band: on both faces the band, the
// sheet's soft edge (`ramp` cells) and `gap` cells of full weight; on the face the light comes from
// (upstream) also the horizontal distance the light travels over the volume's depth, so that every ray
// reaching the volume starts `gap` cells inside the full-weight sheet (the edge's diffraction reaches
// about a Fresnel width past its geometric shadow). An axis without sideways travel: the band only.
struct AxisPadding {
    int low = 0, high = 0, ramp_low = 0, ramp_high = 0;
};
AxisPadding upstream_padding(double refracted_component, double refracted_z, int depth_cells, int sponge, int ramp, int gap);

}  // namespace caustics::wave
