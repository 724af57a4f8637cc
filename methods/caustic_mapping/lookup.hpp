#pragma once
// caustic_mapping: the application of the caustic map to receiver points (Shah et al. 2007, Sec. III.B,
// final pass, as a shadow-map lookup): project the point into the light view, test its depth against the
// receivers' positions texture (a point the light cannot see gets no caustic), read the caustic map
// bilinearly and divide by the receiver area one texel covers there (flux per texel -> irradiance).
//
// Each render first prepares every point (projection, texel indices, bilinear weights, depth bias, texel
// area), then reads the caustic map. The preparation is redone on every render, inside the timed region,
// although a static receiver, camera and light would allow reusing it: the harness times repeated renders
// of one frame, and a reused preparation would leave per-frame work out of the measured frame time.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "camera.hpp"
#include "frame.hpp"
#include "image.hpp"
#include "positions_texture.hpp"
#include "receiver_chart.hpp"

namespace caustics::caustic_mapping {

struct PreparedLookup {
    static constexpr std::uint32_t kOutside = 0xffffffffu;
    std::uint32_t texel = kOutside;   // depth-test texel in the face's G-buffer; kOutside: outside the view
    std::uint32_t corner = 0;         // bilinear: texel (x0, y0); the others are +1, +W, +W+1
    std::uint32_t face = 0;
    float ax = 0.0f, ay = 0.0f;       // bilinear weights of x0 + 1 and y0 + 1
    float depth = 0.0f;               // the point's light-view depth minus the slope-scaled bias
    float inv_area = 0.0f;            // 1 / receiver area of one caustic-map texel at the point [1/m^2]
};

// Prepares the lookup of point p (unit normal n) on `receivers`; depth_bias scales the shadow-map bias of
// about two texels (slope-scaled).
PreparedLookup prepare_lookup(const PositionsTexture& receivers, const glm::dvec3& p, const glm::dvec3& n,
                              double depth_bias);

// Irradiance at a prepared point from the caustic maps (flux per texel, one per face). Counts points
// outside the light view or on no receiver (`outside`) and points with caustic flux that fail the depth
// test (`shadowed`).
inline double lookup_irradiance(const PreparedLookup& l, const PositionsTexture& receivers,
                                const std::vector<Image>& caustic, std::int64_t& outside, std::int64_t& shadowed) {
    if (l.texel == PreparedLookup::kOutside) {
        ++outside;
        return 0.0;
    }
    const GBuffer& g = receivers.maps[l.face];
    if (g.id[l.texel] == -1) {
        ++outside;
        return 0.0;
    }
    const float* map = caustic[l.face].pixels.data();
    const std::size_t w = static_cast<std::size_t>(g.width);
    const float top = map[l.corner] + l.ax * (map[l.corner + 1] - map[l.corner]);
    const float bottom = map[l.corner + w] + l.ax * (map[l.corner + w + 1] - map[l.corner + w]);
    const float flux = top + l.ay * (bottom - top);
    if (flux == 0.0f) return 0.0;   // no caustic here: the depth test cannot change that
    if (l.depth > g.depth[l.texel]) {
        ++shadowed;
        return 0.0;
    }
    return static_cast<double>(flux) * l.inv_area;
}

// The prepared lookups of one set of points (the receiver map's samples or the camera's pixels); the
// buffer is kept between renders so that nothing allocates after the first frame.
struct LookupSet {
    std::vector<PreparedLookup> lookups;
};

// A receiver bin holds the mean irradiance over its area (DESIGN.md): n x n lookups per bin, n the number
// of caustic-map texels a bin side spans (at the chart's corners and centre, the finest wins), so that the
// lookups see every texel of the bin; at most 16.
int auto_bin_samples(const PositionsTexture& receivers, const ReceiverChart& chart);
// The receiver map's lookups: n x n stratified points per bin (n = 1: the bin centre, as the paper's
// per-pixel lookup), bin-major.
void prepare_receiver_lookups(LookupSet& set, const PositionsTexture& receivers,
                              const ReceiverChart& chart, int n, double depth_bias);
// The camera view's lookups, one per pixel whose primary hit is diffuse.
void prepare_camera_lookups(LookupSet& set, const PositionsTexture& receivers,
                            const CameraGBuffer& gb, double depth_bias);

}  // namespace caustics::caustic_mapping
