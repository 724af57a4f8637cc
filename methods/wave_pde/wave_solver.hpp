#pragma once
// The wave equation of Mercier 2013, Sec. 4 (Eq. 5), phi_tt = c^2 Laplacian(phi), on a regular grid with
// an explicit leapfrog scheme in grid units (c = 1, h = 1, dt = courant), zero (Dirichlet) values
// outside the grid, and a damping band of `sponge` cells along every face (the x and y faces get
// neither with Sides::Mirror or Sides::Periodic, see there):
//   phi^{n+1} = (2 phi^n - (1 - s/2) phi^{n-1} + courant^2 L(phi^n)) / (1 + s/2),
// s = sigma dt, sigma = strength * (d / sponge)^2 at depth d (cells) into the band: a smooth ramp so the
// band itself does not reflect. Exposed for the tests; the plugin is wave_pde.cpp.
//
// Layout for speed: two float arrays (phi^{n+1} overwrites phi^{n-1}); the three update coefficients
// depend only on the band depth max(d_x, d_yz), so one coefficient row per band depth of the (y, z)
// pair is precomputed and the inner loop over an x row is branch-free; tiles of y rows, each swept
// along z, run in parallel; the narrow band is tracked per x row (a row is updated when it or a y/z
// neighbour row is non-zero), and an inactive row holds exact zeros, so the result does not depend on
// the thread count.
#include <cstdint>
#include <limits>
#include <vector>

#include "volume_grid.hpp"

namespace caustics::wave {

// The x and y faces. Zero: Dirichlet zero outside, and the damping band (the paper). Mirror: zero
// normal derivative at the face (the field continues as its mirror image). Periodic: the field wraps
// (a surface that tiles the box). The z faces always have the zero exterior and the band.
enum class Sides { Zero, Mirror, Periodic };

struct Settings {
    double courant = 0.5;          // c dt / h; stable up to 1 / sqrt(3)
    int sponge = 0;                // damping band width in cells (part of the grid)
    double sponge_strength = 0.5;  // sigma at the outer face, per unit time (c = h = 1)
    bool narrow_band = true;       // update only x rows next to non-zero values (Sec. 4)
    bool clamp_negative = false;   // phi = max(phi, 0) after every step
    Sides sides = Sides::Zero;
};

class Simulation {
public:
    Simulation(const VolumeShape& shape, const Settings& settings);

    // Sets phi^0 = phi^{-1} = initial (zero initial velocity).
    void set_initial(const std::vector<float>& initial);
    // One leapfrog step phi^n -> phi^{n+1}; returns max |phi^{n+1}| (NaN if any is not finite). With
    // `accumulate` (Algorithm 3's sum of phi), the levels are added in pairs on the odd steps, so after
    // the last step call flush() with the same array: it then holds phi^0 + ... + phi^{N-1}.
    // accumulate_top: the window of a front moving down (-z). Layers k > accumulate_top stop
    // accumulating; layers k > accumulate_top + 4 are set to zero and no longer updated. It may only
    // decrease from step to step.
    double step(std::vector<float>* accumulate, int accumulate_top = std::numeric_limits<int>::max());
    void flush(std::vector<float>* accumulate);
    // Discrete energy ||phi^n - phi^{n-1}||^2 / courant^2 + <grad phi^n, grad phi^{n-1}> (edges to the
    // zero exterior included; across mirror faces none; across periodic ones the wrapped edges):
    // exactly conserved by leapfrog without damping.
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
    std::vector<int> depth_x_, depth_y_, depth_z_;  // cells into the damping band (0 outside) per index
    // coef_[(3 * d_yz + q) * nx + i], q = 0, 1, 2: the factors of phi^n, phi^{n-1} and L(phi^n) for a
    // row at (y, z) band depth d_yz.
    std::vector<float> coef_;
    // Per x row (index k * ny + j): non-zero values at time level n (cur) and n - 1 (prev).
    std::vector<std::uint8_t> row_cur_, row_prev_;
    std::vector<float> zero_row_;
    std::int64_t clamped_ = 0, cells_updated_ = 0, steps_ = 0;
    bool pending_ = false;  // the last level phi^n is not yet in the accumulator
    int accumulate_top_ = std::numeric_limits<int>::max(), update_top_ = std::numeric_limits<int>::max();
};

}  // namespace caustics::wave
