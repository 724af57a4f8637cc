#pragma once
// The volume caustic radiance L_v of the camera (Sec. 5.1, 5.2), with its cost set by the image, not only
// by the beams. The view is each pixel's mean radiance over the pixel (docs/design.md section 3); the
// paper evaluates one ray per fragment. Here:
//
//  - nodes: the pixels on a lattice of spacing `step` (and the last row and column) are evaluated at
//    their centres, every beam whose hull holds the centre adding its ray-beam integral;
//  - blocks: between four nodes, a block is smooth when the nodes' radiances differ by at most `refine`
//    of their mean and every pixel of it sees the same object at a depth within 5 % of the bilinear
//    depth (kDepthTolerance); the pixels of a smooth block are interpolated bilinearly (the game engines' reduced-resolution
//    volumetrics with a depth-aware upsampling);
//  - refined pixels (those of the other blocks: the light cone's edges, silhouettes, caustic structure
//    narrower than a block) are evaluated in full, as the mean of `subpixels` x `subpixels` stratified
//    rays through the pixel's square, each to its own first hit (the box filter at the cone's edges);
//  - edge pixels (refined pixels whose sub-rays' radiances spread by more than `refine` of their mean:
//    a hull's edge crosses them, where a ray's chord through the light grows as the square root of its
//    distance from the cone's surface) are evaluated again with `edge_subpixels` x `edge_subpixels` rays.
//
// step = 1, subpixels = 1 is the paper's one ray per pixel centre. The defaults (step 2, refine 1, 2 x 2
// sub-rays) were chosen on a sweep of sphere_fog (README): faster than the paper's and with a third less
// error, most of it removed at the cone's edges. Features narrower than a block that
// leave all four nodes dark are missed; the error is measured against the reference (README).
#include <cstdint>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/util/image.hpp>

#include "hull_raster.hpp"
#include "ray_beam.hpp"

namespace caustics::adaptive_beams {

struct VolumeSettings {
    int samples = 1;       // Gauss-Legendre points per ray-beam interval (1: the paper's midpoint)
    int step = 2;          // node spacing [pixels]
    double refine = 1.0;   // a block whose nodes differ by more than this fraction of their mean is refined
    int subpixels = 2;     // rays per side of a refined pixel
    int edge_subpixels = 1;   // rays per side of a refined pixel whose sub-rays disagree (a hull's edge in it)
    bool lanes = true;     // the ray-beam integrals four rays at a time in AVX2 lanes where the CPU has them
    bool single = false;   // each fragment's integral in single precision, one ray at a time (volume_precision)
    double cull = 0.0;     // beams whose mean radiance over their hull is below this fraction of the beams' 99th
                           // percentile are left out (accumulate.cpp, cull_faint_beams); 0: none
};

struct VolumeStats {
    std::int64_t fill = 0;      // (beam, pixel) pairs scan-converted
    std::int64_t rays = 0;      // (beam, ray) integrals evaluated
    std::int64_t clamped = 0;   // integrand evaluations at a focus where |A| was clamped
    std::int64_t refined = 0;   // pixels evaluated in full (not interpolated)
    std::int64_t edge_pixels = 0;   // refined pixels evaluated again with edge_subpixels^2 rays
};

// One beam as the volume view sees it: its integral from the camera and its pixels (hull_raster.hpp).
struct VolumeBeam {
    const RayBeam* beam = nullptr;
    const Coverage* pixels = nullptr;
};

// Fills `volume` (g.width x g.height) with L_v from `beams`, walked in their order. The tracer (may be
// null: sub-rays then take their pixel's depth) finds the sub-rays' first hits.
void render_volume(const std::vector<VolumeBeam>& beams, const CameraModel& cam, const CameraGBuffer& g,
                   const RayTracer* tracer, const VolumeSettings& s, Image& volume, VolumeStats& stats);

}  // namespace caustics::adaptive_beams
