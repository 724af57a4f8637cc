#pragma once
// The wave equation of Mercier 2013, Sec. 4 (Eq. 5), phi_tt = c^2 Laplacian(phi), on a regular grid with
// an explicit leapfrog scheme in grid units (c = 1, h = 1, dt = courant), zero (Dirichlet) values
// outside the grid, and a damping band of `sponge` cells along every face:
//   phi^{n+1} = (2 phi^n - (1 - s/2) phi^{n-1} + courant^2 L(phi^n)) / (1 + s/2),
// s = sigma dt, sigma = strength * (d / sponge)^2 at depth d (cells) into the band: a smooth ramp so the
// band itself does not reflect. Exposed for the tests; the plugin is wave_pde.cpp.
#include <cstdint>
#include <vector>

#include "volume_grid.hpp"

namespace caustics::wave {

struct Settings {
    double courant = 0.5;          // c dt / h; stable up to 1 / sqrt(3)
    int sponge = 0;                // damping band width in cells (part of the grid)
    double sponge_strength = 0.5;  // sigma at the outer face, per unit time (c = h = 1)
    bool narrow_band = true;       // update only z-layers next to non-zero values (Sec. 4)
    bool clamp_negative = false;   // phi = max(phi, 0) after every step
};

class Simulation {
public:
    Simulation(const VolumeShape& shape, const Settings& settings);

    // Sets phi^0 = phi^{-1} = initial (zero initial velocity).
    void set_initial(const std::vector<float>& initial);
    // One leapfrog step; adds phi^n to `accumulate` (Algorithm 3) when non-null. Returns max |phi^{n+1}|.
    double step(std::vector<float>* accumulate);
    // Discrete energy ||phi^n - phi^{n-1}||^2 / courant^2 + <grad phi^n, grad phi^{n-1}> (edges to the
    // zero exterior included): exactly conserved by leapfrog without damping.
    double energy() const;
    // The same energy restricted to cells (and edges between cells) inside [lo, hi) index box, of the
    // difference of this simulation's field and `other`'s over that box (offset maps our box to theirs).
    double difference_energy(const Simulation& other, glm::ivec3 lo, glm::ivec3 hi, glm::ivec3 offset) const;

    const std::vector<float>& current() const { return cur_; }
    const VolumeShape& shape() const { return shape_; }
    std::int64_t clamped() const { return clamped_; }
    std::int64_t cells_updated() const { return cells_updated_; }

private:
    VolumeShape shape_;
    Settings settings_;
    std::vector<float> cur_, prev_;
    std::vector<float> ramp_x_, ramp_y_, ramp_z_;  // d / sponge per index along each axis
    std::vector<std::uint8_t> active_;             // per z-layer: any |phi| above the band threshold
    std::vector<float> zero_row_;
    std::int64_t clamped_ = 0, cells_updated_ = 0;
};

}  // namespace caustics::wave
