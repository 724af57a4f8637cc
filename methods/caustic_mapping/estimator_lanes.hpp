#pragma once
// The estimator of estimator.hpp over four rays at once (one per lane of a vector of doubles), for a
// positions texture with one face and bilinear lookups: the common case of the map passes, where every
// lookup of a ray lands between four covered texels and its Newton (or approximate) iteration neither
// oscillates nor meets a bad derivative.
//
// Why: one estimate is a short chain of lookups whose every step branches on the data (in front of or
// behind the surface, converged or not); one ray at a time, the core spends its time on those branches
// and on scalar arithmetic. Four rays in lanes run the same steps with masks instead of branches.
//
// Same bits: each lane performs the scalar estimator's double-precision operations in the same order
// (the method is compiled without contracted multiply-adds), so a result taken from a lane is the
// scalar result bit for bit (tested). A lane that meets anything else (a null value, a texel with an
// empty neighbour, a non-finite estimate, a bad derivative, an oscillation) is left to the scalar
// estimator, which redoes that ray from its start.
#include <cstddef>

#include <glm/glm.hpp>

#include "estimator.hpp"
#include "positions_texture.hpp"

namespace caustics::caustic_mapping {

struct EstimateRay {
    glm::dvec3 v{0.0}, r{0.0, 0.0, 1.0};   // origin and unit direction
    double d_start = 0.0;
};

// Whether `tex` is one the lanes take: one face, bilinear lookups, its map of the face's size.
inline bool lanes_apply(const PositionsTexture& tex) {
    return !tex.cube && tex.bilinear && tex.faces.size() == 1 && tex.maps.size() == 1 &&
           tex.maps[0].width == tex.faces[0].width && tex.maps[0].height == tex.faces[0].height;
}

// out[k] = estimate_intersection(tex, rays[k].v, rays[k].r, s, rays[k].d_start, normals ? &normals[k] : nullptr)
// for k < n, bit for bit: four rays at a time in lanes where lanes_apply(tex), the scalar estimator for
// the rest. Returns how many rays the lanes finished (the others ran through the scalar estimator).
std::size_t estimate_rays(const PositionsTexture& tex, const EstimatorSettings& s, const EstimateRay* rays,
                          std::size_t n, EstimateResult* out, glm::dvec3* normals);

}  // namespace caustics::caustic_mapping
