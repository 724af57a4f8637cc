#pragma once
// caustic_mapping: from the landing points of the grid texels to the splats of the caustic map
// (Shah et al. 2007, Sec. III.B, last pass: one point primitive per grid vertex, additive blending).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/blocks/splat/splat.hpp>

namespace caustics::caustic_mapping {

// Where the light of one grid texel lands: a cube face and a splat (value 0: it lands nowhere).
struct FaceSplat {
    int face;
    Splat splat;
};

// Footprint radius of each splat in caustic-map texels.
//   Fixed     every splat gets `radius` (the paper's point primitive when below one texel).
//   Adaptive  the footprint follows the local ray density: the landing points of a regular grid form a
//             deformed lattice whose spacing along the grid's x and y is J * (1, 0) and J * (0, 1), J the
//             Jacobian of the landing map (central differences of the neighbours' landing points). A
//             Gaussian of sigma >= spacing / 2 reconstructs a lattice without ripple, so the support is
//             radius = 3.5 * sigma = kAdaptiveScale * the larger spacing, at least `radius` (1 texel: the
//             focus stays as sharp as the map allows) and at most kMaxAdaptiveRadius. Where the light
//             spreads the splats grow and close the gaps (no ring pattern of isolated splats); where it
//             focuses they shrink (no blur of the focus by a size fixed at the grid spacing). Not in the
//             paper (its footprint is a fixed point size); splat=gaussian / point restore that.
//             Where a texel's grid neighbours do not land (silhouette texels, texels next to rays lost to
//             TIR or a null value: the grazing rays that spread the most) the spacing comes from the
//             neighbours that do: the diagonals, else the nearest ring of landed texels within
//             kNeighbourSearch; a splat with none keeps the minimum (its flux is kept, and counted).
enum class FootprintMode { Fixed, Adaptive };
constexpr float kAdaptiveScale = 1.75f;
constexpr float kMaxAdaptiveRadius = 64.0f;
constexpr int kNeighbourSearch = 4;

// The step of the landing lattice at landed texel (x, y) along grid offset (dx, dy): the central
// difference of the neighbours' landing points, one-sided at an edge of the lit region (neighbours that
// land on another face do not count); false when neither neighbour lands.
bool lattice_step(const std::vector<FaceSplat>& landing, int grid, int x, int y, int dx, int dy, glm::vec2& step);

// The Adaptive footprint radius of landed texel (x, y) (landing[y * grid + x] has a value > 0), at least
// min_radius; false when no landed neighbour lies within kNeighbourSearch texels (then min_radius).
bool adaptive_radius(const std::vector<FaceSplat>& landing, int grid, int x, int y, float min_radius, float& radius);

// Appends the splats of the grid x grid landing points to per_face[face] (cleared first; one vector per
// face, reused between frames so that no frame allocates once they have grown). Returns the number of
// adaptive splats with no landed neighbour within kNeighbourSearch texels (kept at the minimum radius).
int build_splats(const std::vector<FaceSplat>& landing, int grid, FootprintMode mode, float radius,
                 std::vector<std::vector<Splat>>& per_face);

}  // namespace caustics::caustic_mapping
