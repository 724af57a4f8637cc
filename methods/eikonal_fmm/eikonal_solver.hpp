#pragma once
// Eikonal solution under a height-field water interface (Mercier 2013, Sec. 3): phi = travel time
// (= distance, F = 1 in water) from the interface, by fast marching (Sethian 1996) or by a downward
// layer-by-layer fast-sweeping solver; first- or second-order upwind updates (Rickett & Fomel 2000);
// boundary treatment of Algorithm 2. Exposed for the tests; the plugin is eikonal_fmm.cpp.
#include <cstdint>
#include <vector>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>

namespace caustics::eikonal {

enum class Solver { Fmm, Sweep };
enum class Init { Vertex, Triangle };
enum class Boundary { None, Paper };  // `embed` is a larger domain, chosen by the caller
// The time the front leaves each interface point. Paper: 0 everywhere (Sec. 3: the limit of an
// infinite refractive index, fronts move along the interface normals). PlaneWave: the arrival time of
// the incident plane wave, (d . q) / n in water path length, so that below the interface grad T is
// the refracted direction of Snell's law (its tangential part is that of d / n).
enum class InitTime { Paper, PlaneWave };

struct Options {
    Solver solver = Solver::Fmm;
    int order = 2;
    Init init = Init::Triangle;
    Boundary boundary = Boundary::Paper;
    InitTime init_time = InitTime::PlaneWave;
    glm::dvec3 light{0.0, 0.0, -1.0};  // PlaneWave: the direction the incident light travels (unit)
    double ior = 1.33;                 // PlaneWave: the water's index (the outside is air, n = 1)
};

// The incident plane wave refracted at the (extended) interface point over (x, y).
struct Refraction {
    glm::dvec3 point{0.0};             // q on the interface
    glm::dvec3 normal{0.0, 0.0, 1.0};  // unit, upward
    glm::dvec3 direction{0.0, 0.0, -1.0};  // refracted ray t (unit, downward)
    double cos_i = 1.0, cos_t = 1.0;   // -d . N and -t . N
    bool lit = true;                   // false where the light meets the interface from below (shadowed)
};
Refraction refract_at(const HeightField& hf, double x, double y, const glm::dvec3& light, double ior);
// Snell's law for a unit upward normal (cos_i clamped at 0 for grazing / back-facing light).
glm::dvec3 refract_direction(const glm::dvec3& light, const glm::dvec3& normal, double ior);
// The refracted ray of the plane wave through p: the interface point q with p = q + s t(q) (a
// fixed-point iteration on the entry point; exact for any surface before the rays cross). Returns s,
// > 0 below the interface, < 0 above; r receives q's refraction.
double refracted_foot(const HeightField& hf, const glm::dvec3& p, const glm::dvec3& light, double ior, Refraction& r);
// The plane wave's arrival time at interface point q in water path length: (d . q) / n.
inline double plane_wave_time(const glm::dvec3& q, const glm::dvec3& light, double ior) {
    return (light.x * q.x + light.y * q.y + light.z * q.z) / ior;
}

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
