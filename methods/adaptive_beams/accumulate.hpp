#pragma once
// Accumulating the beams (Sec. 5): each beam's bounding hull is scan-converted into the camera (pixel
// centres inside the projection of the hull, near-clipped), and every pixel it touches gets the beam's
// in-scattered radiance along its primary ray (Sec. 5.1, 5.2) and, where the pixel sees a diffuse surface,
// the beam's irradiance there by point-in-beam (Sec. 5.3), low-pass filtered afterwards (Sec. 7); beams
// that end on one plane are instead split among the pixels by exact coverage (surface_coverage.hpp). The
// receiver map takes the same point-in-beam test at stratified points of each bin.
//
// Parallel over bands of rows; each band walks the beams in their order, so the sums are the same for
// any thread count.
#include <cstdint>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/util/image.hpp>

#include "light_grid.hpp"
#include "volume_view.hpp"

namespace caustics::adaptive_beams {

struct AccumulateSettings {
    HullType hull = HullType::Tight;
    VolumeSettings volume;      // the volume view: Gauss points, node spacing, refinement, sub-rays
    int receiver_samples = 3;   // stratified point-in-beam samples per bin side on the receiver map
    bool surface_coverage = true;   // camera surface caustics of beams ending on a plane by exact pixel coverage
                                    // (surface_coverage.hpp); false: point-in-beam for all (the paper)
    int filter = 1;             // camera surface caustics by point-in-beam: tent filter radius [pixels], 0 = none
    double end_tol = 0.05;      // a surface point may lie this fraction of a beam's length past its end
};

struct AccumulateStats {
    std::int64_t fill = 0;            // camera pixels touched by hulls (fragments)
    std::int64_t clamped = 0;         // evaluations at a focus where |A| was clamped
    std::int64_t near_clipped = 0;    // hulls cut by the camera's near plane (beams that leave the frustum behind it)
    std::int64_t offscreen = 0;       // hulls wholly outside the image (beams that leave the frustum)
    std::int64_t prism_fallback = 0;  // prism hull not formed: the tight corners were used
    std::int64_t volume_rays = 0;     // (beam, ray) integrals of the volume view
    std::int64_t volume_refined = 0;  // volume view pixels evaluated in full (the others interpolated)
    std::int64_t volume_edge_pixels = 0;  // refined pixels evaluated again with edge_subpixels^2 rays
    std::int64_t volume_culled = 0;   // volume beams left out as faint (VolumeSettings::cull)
    std::int64_t coverage_beams = 0;  // beams whose surface caustic was deposited by pixel coverage
    double hulls_ms = 0.0;            // the camera's stages: the beams' pixels (hull scan conversion),
    double surface_ms = 0.0;          // the surface caustics of the camera view,
    double volume_ms = 0.0;           // the volume view
};

// Fills `surface` (E_c at covered pixels, when non-null) and `volume` (L_v, when non-null, volume_view.hpp),
// both sized to the G-buffer. The tracer (may be null) finds the first hits of the volume view's sub-rays.
void accumulate_camera(const BeamSet& set, const Scene& scene, const CameraGBuffer& gbuffer, const RayTracer* tracer,
                       const AccumulateSettings& s, Image* surface, Image* volume, AccumulateStats& stats);

// Fills the receiver map (chart width x height, mean E_c per bin).
void accumulate_receiver(const BeamSet& set, const Scene& scene, const ReceiverChart& chart, const AccumulateSettings& s,
                         Image& receiver, AccumulateStats& stats);

}  // namespace caustics::adaptive_beams
