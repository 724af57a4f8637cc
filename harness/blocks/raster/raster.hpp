#pragma once
// A software rasterizer of 2-D triangles into a float image, shared by methods (docs/design.md section 2).
//
// Coordinates are in pixels: x along a row (column index), y down the rows (row 0 first); pixel (i, j)
// covers [i, i+1) x [j, j+1) and its centre is (i + 1/2, j + 1/2). Drawing is additive (or overwrites,
// see RasterOptions::accumulate). Two coverage models:
//
//   PixelCenter  point sampling at pixel centres with the top-left fill rule on 8-bit sub-pixel
//                fixed-point vertices: two triangles sharing an edge (or a vertex fan) count every
//                centre exactly once. A pixel gets the triangle's value (or the per-vertex values
//                interpolated with barycentric weights). Tiny triangles alias: a triangle smaller than
//                a pixel covers zero or one centre.
//   Area         exact area coverage: the triangle's value is a total (e.g. a flux) split among the
//                pixels in proportion to the area of the triangle inside each pixel, so the sum over the
//                image equals the sum of the values of the triangles inside it (flux conservation) and
//                nothing aliases. Signed-area accumulation per scanline (edges deposit the derivative of
//                the coverage along x, a prefix sum integrates it; as in font-rs / stb_truetype), so the
//                cost is per edge crossing, independent of the triangle's interior area. Folded triangles
//                (either orientation) deposit their value positively. Triangles whose bounding box lies
//                inside one pixel, and degenerate ones (zero area), deposit their whole value without
//                dividing by their area (one pixel, or a third at each vertex's pixel).
//
// Toroidal wrap (periodic textures): a triangle crossing the image border re-enters on the other side.
// Without wrap, whatever lies outside the image is dropped (clipped exactly in Area mode).
//
// Parallel (TBB) over horizontal bands of rows: triangles are binned to the bands they touch, and each
// band draws its triangles in input order, so the result is bit-identical for any thread count.
// Buffers are kept in the TriangleRaster object: after the first call of a given size nothing allocates.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/util/image.hpp>

namespace caustics {

enum class RasterCoverage { PixelCenter, Area };

struct RasterOptions {
    RasterCoverage coverage = RasterCoverage::PixelCenter;
    bool wrap = false;        // toroidal: x modulo width, y modulo height
    bool accumulate = true;   // false: every pixel of the target is overwritten (no clear needed)
};

// A batch of triangles indexing `positions` (pixel coordinates). A triangle is skipped when its value
// is exactly 0 (and no vertex values are given) or a vertex is not finite.
struct RasterTriangles {
    std::span<const glm::vec2> positions;
    std::span<const glm::uvec3> triangles;
    // One per triangle. PixelCenter: the value written at each covered centre. Area: the total that is
    // split among the covered pixels by area.
    std::span<const float> triangle_values;
    // Optional, one per position, PixelCenter only: interpolated across the triangle instead of
    // triangle_values.
    std::span<const float> vertex_values;
};

struct RasterStats {
    std::int64_t drawn = 0;            // triangle copies drawn (wrap can draw one triangle several times)
    std::int64_t nonfinite = 0;        // triangles skipped for a non-finite vertex or value
    std::int64_t point_deposits = 0;   // Area: triangles deposited without area division
    std::int64_t too_large = 0;        // wrap: triangles spanning more than 8 image tiles (skipped)
};

class TriangleRaster {
public:
    TriangleRaster();
    ~TriangleRaster();
    TriangleRaster(TriangleRaster&&) noexcept;
    TriangleRaster& operator=(TriangleRaster&&) noexcept;

    // Draws into `target` (one channel; its size is the raster size). Throws std::invalid_argument on
    // mismatched spans or unsupported combinations (vertex values with Area coverage).
    RasterStats draw(const RasterTriangles& batch, const RasterOptions& options, Image& target);

    // Rows per band (parallel work item); a power of two. Exposed for tests.
    static constexpr int kBandRows = 16;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace caustics
