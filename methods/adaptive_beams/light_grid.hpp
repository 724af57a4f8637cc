#pragma once
// The hierarchical projected grid (Sec. 4.1, 4.2) and the beams it generates (Sec. 4.3, 6).
//
// The grid lives in the light's image space (an orthographic view for a directional light, a perspective
// one for a point light, harness/blocks/gbuffer/light_projection.hpp). Each grid vertex is the light ray
// through it, followed through the specular objects: its first hit (the light G-buffer's position, normal,
// depth and object, Sec. 4.1), the refraction or reflection there and, inside a closed dielectric, the
// second refraction on the way out (two-sided refraction, Sec. 6), up to the first diffuse surface or the
// extrusion limit. A cell is split (Sec. 4.2) where its corners disagree (silhouette, another object,
// total internal reflection), where depth or normal jump, where the light's hits at its edge midpoints
// leave the bilinear beam (Sec. 6), where its beam converges strongly for its share of the light,
// where the beam is wide as seen from the camera, and where a beam passes a focus before it ends.
#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/blocks/gbuffer/light_projection.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>

#include "beam.hpp"

namespace caustics::adaptive_beams {

constexpr int kMaxSegments = 3;
constexpr std::uint8_t kEndsOnDiffuse = 1, kEndsOnReceiver = 2, kAllOnReceiver = 4, kReceiverOrNothing = 8;

// One light ray followed through the specular objects (a vertex of the projected grid).
struct LightPath {
    enum Status : std::uint8_t { Missed, Ok, TotalInternalReflection, Lost };
    Status status = Missed;   // Missed: the first hit is not specular (or nothing); Lost: met a second specular object
    int object = -1;          // first specular object hit
    double depth = 0.0;       // distance from the light (orthographic: from its image plane)
    glm::dvec3 normal{0.0};   // shading normal at the first hit
    int segments = 0;
    std::array<EdgeRay, kMaxSegments> seg{};
    std::array<int, kMaxSegments> medium{};   // object whose inside holds the segment, -1 outside
    std::array<int, kMaxSegments> end_object{};   // what the segment ends on (-1: the extrusion limit)
};

struct GridSettings {
    int grid = 32;                   // initial cells per side
    int iterations = 2;              // refinement levels
    bool adaptive = true;            // false: the uniform grid x grid (no refinement)
    double depth_threshold = 2.0;    // split: depth jump across a cell > this x its width
    double normal_threshold_deg = 15.0;   // split: corner normals further apart than this
    double focus_ratio = 1.0;        // split: the beam's end section is below 1 / (this 4^level) of its start
    double deviation = 0.01;         // split: a midpoint's hit is off the beam's by more than this x the cell's end size
    double camera_angle = 0.05;      // split: the beam's width seen from the camera [rad] above this
    bool fold_split = true;          // split: one of the cell's beams passes a focus before it ends
    double clamp_ratio = 1e-3;       // |A| >= this x the start area
    double energy_cutoff = 1e-3;     // extrusion ends (and faint beams are discarded) below this
};

struct GridStats {
    std::int64_t beams_generated = 0, beams_split = 0, discarded_tir = 0, discarded_energy = 0, flipped = 0,
                 degenerate = 0, lost = 0, cells = 0;
};

// The beams of one frame, ready to be accumulated.
struct BeamSet {
    std::vector<Beam> beams;
    std::vector<std::uint8_t> ends;   // per beam: kEndsOnDiffuse | kEndsOnReceiver where an edge ends there, kAllOnReceiver where all three do,
                                      // kReceiverOrNothing where each ends there or at the extrusion limit
    std::vector<int> end_object;      // per beam: the diffuse object all three edges end on, else -1
    GridStats stats;
};

// The lattice points generate() traced, each once: a dense table of indices where the finest lattice is
// small enough ((res + 1)^2 <= kDenseLatticeLimit), a hash map beyond.
struct LatticePoints {
    static constexpr std::size_t kDenseLatticeLimit = std::size_t{1} << 24;
    int side = 0;                                  // res + 1 where dense, 0 where hashed
    std::vector<int> dense;                        // side x side: index into paths, -1 not traced
    std::unordered_map<std::uint64_t, int> hashed;
    std::vector<LightPath> paths;
    // Empty, for a lattice of res x res cells (dense where (res + 1)^2 <= dense_limit); the storage of the
    // last frame is kept.
    void reset(int res, std::size_t dense_limit = kDenseLatticeLimit);
    int find(int i, int j) const {
        if (side > 0) {
            assert(i >= 0 && j >= 0 && i < side && j < side);
            return dense[static_cast<std::size_t>(j) * side + static_cast<std::size_t>(i)];
        }
        const auto it = hashed.find((static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j));
        return it == hashed.end() ? -1 : it->second;
    }
    const LightPath& at(int i, int j) const {
        const int k = find(i, j);
        assert(k >= 0 && "a lattice point read before it was traced");
        return paths[static_cast<std::size_t>(k)];
    }
    void insert(int i, int j, int index);
};

// The beams of one triangle (or one leaf) of lattice points (one beam per segment of their common path),
// what was dropped, and what the oracle weighs.
struct TriangleBeams {
    std::vector<Beam> beams;
    std::vector<std::uint8_t> ends;
    std::vector<int> end_object;
    std::int64_t tir = 0, energy = 0, degenerate = 0, lost = 0, flipped = 0;
    double min_ratio = 1e300, max_view_angle = 0.0;
    bool folded = false;   // a beam passes a focus before it ends
    // Empty, keeping the vectors' capacity.
    void clear();
};

// generate()'s working storage, kept between frames by its owner so that the lattice (hundreds of megabytes
// at 5 levels) and the leaves' beams are neither allocated nor mapped afresh each frame.
struct GridScratch {
    std::size_t dense_limit = LatticePoints::kDenseLatticeLimit;   // tests lower it to check the hashed lattice
    LatticePoints lattice;
    std::vector<TriangleBeams> leaves;        // per leaf, in leaf order
    std::vector<std::uint8_t> corner_marks;   // the leaves' corners on a dense lattice
};

class LightGrid {
public:
    // Beams are extruded at most to the box of the scene's bounds and the camera (grown by 5 %).
    LightGrid(const FrameGeometry& frame, const RayTracer& tracer, const GridSettings& settings);

    // The beams into `out`, replacing what it held (its vectors keep their capacity: a set reused over frames
    // does not map its hundreds of megabytes afresh each frame), with `scratch` as the working storage.
    void generate(BeamSet& out, GridScratch& scratch) const;

    const LightProjection& projection() const { return proj_; }
    int resolution() const { return res_; }

    // Follows the light ray through point (i, j) of the finest grid's lattice (exposed for tests).
    LightPath trace(double i, double j) const;

private:
    struct Cell { int level, i, j; };
    using Lattice = LatticePoints;
    using TriBeams = TriangleBeams;
    void trace_points(Lattice& lattice, const std::vector<Cell>& cells, int size, int step) const;
    std::uint8_t oracle(const Lattice& lattice, const Cell& c, int size, int level, bool can_split) const;
    void leaf_beams(const Lattice& lattice, const std::vector<Cell>& leaves, int s0, std::vector<TriBeams>& per,
                    std::vector<std::uint8_t>& corner_marks, BeamSet& out) const;
    void make_triangle(const Lattice& lattice, const glm::ivec2 (&ci)[3], TriBeams& tb, bool clip) const;
    void emit(const glm::dvec2 (&c)[3], const LightPath* const (&p)[3], TriBeams& tb) const;
    double triangle_flux(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) const;
    void ray_at(double i, double j, glm::dvec3& origin, glm::dvec3& dir) const;

    const FrameGeometry& frame_;
    const RayTracer& tracer_;
    GridSettings s_;
    LightProjection proj_;
    int res_ = 0;          // finest lattice cells per side (grid x 2^iterations)
    Bounds3 extent_;
    double offset_ = 1e-5;
};

}  // namespace caustics::adaptive_beams
