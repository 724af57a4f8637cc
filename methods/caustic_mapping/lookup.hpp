#pragma once
// caustic_mapping: the application of the caustic map to receiver points (Shah et al. 2007, Sec. III.B,
// final pass, as a shadow-map lookup): project the point into the light view, test its depth against the
// receivers' positions texture (a point the light cannot see gets no caustic), read the caustic map
// bilinearly and divide by the receiver area one texel covers there (flux per texel -> irradiance).
//
// Every point is looked up on the fly, inside each render: nothing is kept from one render to the next
// (the harness times repeated renders of one frame, and reused per-frame work would be left out of the
// measured frame time). The depth bias and the texel area are needed only where the map holds caustic
// flux, so they are computed there alone; a lookup whose texel's LookupMask bit is clear (no flux and no
// empty texel within one texel) returns 0 before reading the G-buffer or the map.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/camera.hpp>
#include <caustics/util/image.hpp>
#include "lookup_mask.hpp"
#include "positions_texture.hpp"
#include <caustics/frame/receiver_chart.hpp>

namespace caustics::caustic_mapping {

// Lookups that fell outside the light view or on no receiver, and lookups with caustic flux that failed
// the depth test.
struct LookupCounts {
    std::int64_t outside = 0, shadowed = 0;
};

// A receiver bin holds the mean irradiance over its area (docs/design.md): n x n lookups per bin, n the number
// of caustic-map texels a bin side spans (at the chart's corners and centre, the finest wins), so that the
// lookups see every texel of the bin; at most 16.
int auto_bin_samples(const PositionsTexture& receivers, const ReceiverChart& chart);

// Scratch space of the receiver map's pass, refilled on every call (kept so that its large buffers are
// not allocated again in every frame; each task's row buffers of a few KB are).
struct ReceiverScratch {
    std::vector<glm::dvec3> corners;            // the chart's bin corners
    std::vector<double> corner_px, corner_py;   // single face: their texel coordinates
    std::vector<std::uint8_t> corner_usable;    // single face: in front of the eye, finite
};

// The receiver map (`out` is resized to the chart): the mean of n x n stratified lookups per bin (n = 1:
// the bin centre, as the paper's per-pixel lookup). `mask`: built from `receivers` and `caustic`.
void receiver_irradiance(Image& out, ReceiverScratch& scratch, const PositionsTexture& receivers,
                         const std::vector<Image>& caustic, const LookupMask& mask, const ReceiverChart& chart, int n,
                         double depth_bias, LookupCounts& counts);

// The camera view (`out` is resized to the camera): one lookup per pixel whose primary hit is diffuse,
// 0 elsewhere.
void camera_irradiance(Image& out, const PositionsTexture& receivers, const std::vector<Image>& caustic,
                       const LookupMask& mask, const CameraGBuffer& gb, double depth_bias, LookupCounts& counts);

}  // namespace caustics::caustic_mapping
