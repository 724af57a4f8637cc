#pragma once
// Eikonal solution under a height-field water interface (Mercier 2013, Sec. 3): phi = travel time
// (= distance, F = 1 in water) from the interface, by fast marching (Sethian 1996) or by a downward
// layer-by-layer fast-sweeping solver; first- or second-order upwind updates (Rickett & Fomel 2000);
// boundary treatment of Algorithm 2. Exposed for the tests; the plugin is eikonal_fmm.cpp.
#include <cstdint>
#include <vector>

#include "heightfield.hpp"
#include "volume_grid.hpp"

namespace caustics::eikonal {

enum class Solver { Fmm, Sweep };
enum class Init { Vertex, Triangle };
enum class Boundary { None, Paper };  // `embed` is a larger domain, chosen by the caller

struct Options {
    Solver solver = Solver::Fmm;
    int order = 2;
    Init init = Init::Triangle;
    Boundary boundary = Boundary::Paper;
};

struct Stats {
    std::int64_t not_converged = 0;   // sweep layers that hit the pass limit; cells never reached
    std::int64_t nonfinite = 0;
    double init_ms = 0.0, boundary_ms = 0.0, solve_ms = 0.0;
};

// A scalar field being solved: frozen cells keep their values; the others start at +inf.
struct Field {
    VolumeShape shape;
    std::vector<double> phi;
    std::vector<std::uint8_t> frozen;
    const std::vector<float>* cost = nullptr;  // propagation cost F per cell (nullptr: F = 1)
    std::vector<float>* carry = nullptr;       // FMM only: each accepted cell copies its upwind neighbour's
};

// Fast marching from the frozen cells over the whole grid.
void march(Field& f, int order, Stats& stats);
// Downward layer-by-layer fast sweeping: light travels down, so layer k depends only on layers above
// and on itself; each layer is swept in the four horizontal orderings until it stops changing.
void sweep_down(Field& f, int order, Stats& stats);

// Storage kept between solves of the same shape (an animation's frames), so a solve neither allocates
// nor first-touches its grids again.
struct Workspace {
    VolumeD phi;
    std::vector<std::uint8_t> frozen;
};

// Initializes from the interface (band of signed distances, air above frozen), applies the boundary
// treatment and solves. phi > 0 in the water, < 0 in the air above the interface.
VolumeD solve(const HeightField& hf, const VolumeShape& shape, const Options& options, Stats& stats);
// The same into ws.phi (returned), reusing the workspace's storage.
const VolumeD& solve(const HeightField& hf, const VolumeShape& shape, const Options& options, Stats& stats,
                     Workspace& ws);

}  // namespace caustics::eikonal
