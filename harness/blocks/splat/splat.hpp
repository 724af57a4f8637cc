#pragma once
// Point splats with additive accumulation into a float image (the caustic map of Shah et al. 2007 and
// other splatting methods), plus a flux-conserving low-pass filter.
//
//   Point      the whole value goes to the pixel holding the point (a GPU point primitive of one pixel).
//   Gaussian   a separable Gaussian footprint over the pixels whose centres lie within `radius` pixels of
//              the point in x and y (a square support, sigma = radius / 3.5: the cut-off is at 0.2 % of
//              the peak, so overlapping splats of a regular lattice add up smoothly). The weights are normalised
//              over the whole footprint, inside the image or not, so one splat's weights sum to 1: the
//              part falling outside the image is not renormalised but reported (SplatStats::outside),
//              which keeps the accumulated map flux conserving also near borders. A radius below one
//              pixel falls back to the point splat.
//
// Pixel coordinates as in raster.hpp (pixel (i, j) covers [i, i+1) x [j, j+1)). Parallel (TBB) over
// bands of rows: splats are binned in fixed-size chunks and each band adds its splats in input order,
// so the result is identical for any thread count. Buffers are reused between calls.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/util/image.hpp>

namespace caustics {

enum class SplatKernel { Point, Gaussian };

struct Splat {
    glm::vec2 pixel;      // continuous pixel coordinates
    float value;          // the total deposited (e.g. a flux)
    float radius = 0.0f;  // Gaussian support of this splat in pixels; 0: the radius passed to draw()
};

struct SplatStats {
    std::int64_t splatted = 0;     // splats with some weight inside the image
    std::int64_t outside = 0;      // splats entirely outside the image
    std::int64_t nonfinite = 0;    // skipped: non-finite position or value
    double value_inside = 0.0;     // sum of value * weight that landed in the image
    double value_outside = 0.0;    // sum of value * weight that fell outside (partly or entirely)
};

class SplatRaster {
public:
    SplatRaster();
    ~SplatRaster();
    SplatRaster(SplatRaster&&) noexcept;
    SplatRaster& operator=(SplatRaster&&) noexcept;

    // Adds the splats to `target` (one channel). radius: Gaussian support in pixels for splats without
    // their own (ignored for Point).
    SplatStats draw(std::span<const Splat> splats, SplatKernel kernel, double radius, Image& target);

    static constexpr int kBandRows = 16;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Separable Gaussian low-pass (sigma = radius / 3, support +-radius pixels) of a one-channel image, in
// place; the kernel is renormalised at the borders so the image's total is kept. radius < 1: no-op.
void gaussian_lowpass(Image& image, double radius);

}  // namespace caustics
