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
#include <optional>
#include <vector>

#include <caustics/blocks/volume/volume_grid.hpp>

namespace caustics::wave {

// The x and y faces. Zero: Dirichlet zero outside, and the damping band (the paper). Mirror: zero
// normal derivative at the face (the field continues as its mirror image). Periodic: the field wraps
// (a surface that tiles the box). The z faces always have the zero exterior and the band.
enum class Sides { Zero, Mirror, Periodic };

// What step() adds to the accumulator. Sum: phi (Algorithm 3's CausticValue; the levels in pairs, see
// step()). Flux: the downward energy flux through a horizontal plane, phi_t * dphi/dz (z up), in the
// centred differences (phi^{n+1} - phi^{n-1}) (phi^n_{k+1} - phi^n_{k-1}) / 4 (c = h = 1, times dt for
// the time integral, i.e. / (4 courant) * courant): the wave equation's energy current is -phi_t grad phi,
// and for a pulse A g(t - s . x) its time integral through a plane of normal z is A^2 (s . -z) int g'^2,
// i.e. proportional to the irradiance the pulse's rays deliver onto a horizontal receiver.
enum class Accumulate { Sum, Flux };

// A source sheet injected as displacement (phi^n and phi^{n-1} both raised by the same increment, so
// the velocity is unchanged; in the continuum phi_tt = Laplacian(phi) + D_tt for the injected
// displacement D): cell c receives weight * G((t - time) / width) by time t, G the normal CDF, so
// its emitted pulse is weight * the Gaussian g of width `width` (c = h = 1 units) centred at `time`.
// Times are continuous: a cell whose time falls between two steps gets the exact fraction of its
// displacement at each (the sub-step interpolation of the launch).
struct SourceCell {
    std::uint32_t cell;
    float weight, time;
    double injected = 0.0;  // the displacement injected so far (the solver's bookkeeping)
};
struct Source {
    std::vector<SourceCell> cells;  // any order; the solver sorts them by time
    double width = 1.5;             // Gaussian time width of each cell's pulse
};

// Accumulate::Flux: cell (i, j, k) accumulates while the time of level n, n * courant, is at most
// s0 + sx i + sy j + sz k (each cell stops when the front has passed it: cells the oblique front
// passes early would otherwise add the scheme's dispersive tail for longer than the others).
struct CellWindow {
    double s0 = std::numeric_limits<double>::infinity(), sx = 0.0, sy = 0.0, sz = 0.0;
};

struct Settings {
    double courant = 0.5;          // c dt / h; stable up to 1 / sqrt(3)
    int sponge = 0;                // damping band width in cells (part of the grid)
    double sponge_strength = 0.5;  // sigma at the outer face, per unit time (c = h = 1)
    bool narrow_band = true;       // update only x rows next to non-zero values (Sec. 4)
    bool clamp_negative = false;   // phi = max(phi, 0) after every step
    Sides sides = Sides::Zero;     // the x faces (and the y faces unless sides_y is set)
    std::optional<Sides> sides_y;  // the y faces where they differ (e.g. mirror across y, a band across x)
    Accumulate accumulate = Accumulate::Sum;
    CellWindow window;
    Sides side_x() const { return sides; }
    Sides side_y() const { return sides_y.value_or(sides); }
};

class Simulation {
public:
    Simulation(const VolumeShape& shape, const Settings& settings);

    // Sets phi^0 = phi^{-1} = initial (zero initial velocity).
    void set_initial(const std::vector<float>& initial);
    // A source injected while stepping (time 0 is phi^0; step n brings its displacement up to time
    // n * courant before the update). Replaces any earlier one.
    void set_source(Source source);
    void set_window(const CellWindow& window) { settings_.window = window; }
    // The largest source time plus 4 widths: after it the source injects nothing (within 1e-4).
    double source_end() const;
    // One leapfrog step phi^n -> phi^{n+1}; returns max |phi^{n+1}| (NaN if any is not finite). With
    // `accumulate` and Accumulate::Sum (Algorithm 3's sum of phi), the levels are added in pairs on the
    // odd steps, so after the last step call flush() with the same array: it then holds
    // phi^0 + ... + phi^{N-1}. With Accumulate::Flux every step adds the flux term at level n.
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
    std::int64_t steps() const { return steps_; }
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
    Source source_;              // cells sorted by time
    std::size_t source_done_ = 0;  // source_.cells before this index have injected all they carry
    void inject(int update_top);
    std::int64_t clamped_ = 0, cells_updated_ = 0, steps_ = 0;
    bool pending_ = false;  // the last level phi^n is not yet in the accumulator
    int accumulate_top_ = std::numeric_limits<int>::max(), update_top_ = std::numeric_limits<int>::max();
};

}  // namespace caustics::wave
