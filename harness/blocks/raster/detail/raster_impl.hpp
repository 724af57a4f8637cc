#pragma once
// Internals of TriangleRaster shared by its two translation units: raster.cpp (the general path) and
// raster_grid.cpp (the structured-grid path). Not part of the harness's interface.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/raster.hpp>
#include "raster_area_coverage.hpp"

namespace caustics {
namespace raster_detail {

constexpr std::size_t kChunk = 4096;    // triangles per binning work item (fixed: keeps output order)
constexpr int kGridChunkRows = 8;       // grid path: vertex rows per binning work item (fixed)
constexpr int kMaxCopies = 9;           // wrap: a triangle may touch at most 3 x 3 image tiles
constexpr int kSubpixelBits = 8;        // PixelCenter: fixed-point vertex snapping (1/256 pixel)
constexpr double kSubpixel = 1 << kSubpixelBits;
constexpr double kMaxFixedCoordinate = 1 << 22;  // pixels; keeps edge functions well inside int64

using area_coverage::accumulate_edge;
using area_coverage::kRows;   // Area: band accumulators are column-major

enum TriangleKind : std::uint8_t { kSkip = 0, kNormal = 1, kOnePixel = 2, kDegenerate = 3 };

// One drawn instance of a triangle: shifted by (sx * width, sy * height) pixels (wrap copies).
struct BinEntry {
    std::uint32_t triangle;
    std::int16_t sx, sy;
};

struct Box {
    float xmin, ymin, xmax, ymax;
};

// Tile shifts k such that [lo, hi] + k * size overlaps (0, size).
inline void shift_range(double lo, double hi, double size, int& k_lo, int& k_hi) {
    k_lo = static_cast<int>(std::floor(-hi / size)) + 1;
    k_hi = static_cast<int>(std::ceil((size - lo) / size)) - 1;
}

inline std::int64_t floor_div(std::int64_t a, std::int64_t b) {
    std::int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

inline Box bounding_box(glm::vec2 p0, glm::vec2 p1, glm::vec2 p2) {
    return {std::min(std::min(p0.x, p1.x), p2.x), std::min(std::min(p0.y, p1.y), p2.y),
            std::max(std::max(p0.x, p1.x), p2.x), std::max(std::max(p0.y, p1.y), p2.y)};
}

// Twice the signed area of a triangle (counter-clockwise positive), in double from its float vertices.
inline double cross2(glm::vec2 p0, glm::vec2 p1, glm::vec2 p2) {
    const glm::dvec2 e1 = glm::dvec2(p1) - glm::dvec2(p0), e2 = glm::dvec2(p2) - glm::dvec2(p0);
    return e1.x * e2.y - e1.y * e2.x;
}

// Area coverage: a triangle whose box lies inside one pixel, or whose area is ~0 next to its size (it
// would divide by ~0), is deposited as points; any other is drawn by its edges. `cross` = cross2(...).
inline TriangleKind area_kind(const Box& b, double cross) {
    // A box inside one pixel is at most 1 wide and high (in float too: rounding is monotonic), which
    // spares the floors for nearly every triangle.
    if (b.xmax - b.xmin <= 1.0f && b.ymax - b.ymin <= 1.0f) {
        const double fx = std::floor(static_cast<double>(b.xmin));
        const double fy = std::floor(static_cast<double>(b.ymin));
        if (b.xmax <= fx + 1.0 && b.ymax <= fy + 1.0) return kOnePixel;
    }
    const double diag2 = double(b.xmax - b.xmin) * (b.xmax - b.xmin) + double(b.ymax - b.ymin) * (b.ymax - b.ymin);
    return std::abs(cross) <= 2e-8 + 2e-10 * diag2 ? kDegenerate : kNormal;
}

// Coverage accumulates with the sign of -(signed area): the edge weight value / coverage. Wrap copies
// are shifted by whole tiles, which leaves the (exact) differences unchanged.
inline double area_weight(double cross, float value) { return -static_cast<double>(value) / (0.5 * cross); }

inline bool finite_triangle(glm::vec2 p0, glm::vec2 p1, glm::vec2 p2, float value) {
    return std::isfinite(value) && std::isfinite(p0.x) && std::isfinite(p0.y) && std::isfinite(p1.x) &&
           std::isfinite(p1.y) && std::isfinite(p2.x) && std::isfinite(p2.y);
}

// Bands [lo, hi] that rows [ymin, ymax] of an image `height` rows high touch (hi < lo: none).
inline glm::ivec2 band_span(double ymin, double ymax, int height) {
    if (ymax < 0.0 || ymin >= height) return {1, 0};
    return {static_cast<int>(std::max(ymin, 0.0)) / TriangleRaster::kBandRows,
            static_cast<int>(std::min(ymax, height - 1.0)) / TriangleRaster::kBandRows};
}

}  // namespace raster_detail

using namespace raster_detail;   // in namespace caustics: the .cpp files of TriangleRaster only

struct TriangleRaster::Impl {
    std::vector<Box> boxes;
    std::vector<TriangleKind> kinds;   // not a char type: its stores alias nothing else
    std::vector<glm::ivec2> band_range;   // without wrap: the bands of the single copy (pass 1 -> 2)
    std::vector<std::uint32_t> counts;    // [chunk][band]
    std::vector<std::uint32_t> cursors;   // [chunk][band] write positions
    std::vector<std::uint32_t> band_start;
    std::vector<BinEntry> entries;
    std::vector<RasterStats> chunk_stats;
    tbb::enumerable_thread_specific<std::vector<double>> band_acc;
    std::vector<double> tri_weight;       // Area, per triangle: -value / signed area (0: draws no edges)
    // Structured-grid path (draw_grid): per [vertex-row chunk][band], the edges and point deposits in
    // input order; the lists keep their capacity between calls.
    struct GridEdge {
        double weight;
        std::uint32_t code;   // (vertex << 2) | edge type 0..2, or (triangle << 2) | 3: point deposit
    };
    std::vector<std::vector<GridEdge>> grid_lists;
    std::vector<std::uint8_t> chunk_grid;   // per triangle chunk: its triangles follow the grid pattern

    int width = 0, height = 0, bands = 0;
    bool wrap = false;

    double* band_accumulator(std::size_t stride) {
        std::vector<double>& acc = band_acc.local();
        if (acc.size() < stride * kBandRows) acc.assign(stride * kBandRows, 0.0);
        return acc.data();
    }

    // Whether the triangles are those of a g x g vertex grid, cells (i, j) split into {v00, v10, v11},
    // {v00, v11, v01} in row order (a height-field method's surface grid).
    bool is_grid(std::span<const glm::uvec3> tris, unsigned g) {
        const std::size_t chunks = (tris.size() + kChunk - 1) / kChunk;
        chunk_grid.assign(chunks, 0);
        tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {   // chunks start on even triangles
            const std::size_t end = std::min(tris.size(), (c + 1) * kChunk);
            const std::size_t cell0 = c * kChunk / 2;
            unsigned i = static_cast<unsigned>(cell0 % (g - 1)), j = static_cast<unsigned>(cell0 / (g - 1));
            bool ok = true;
            for (std::size_t t = c * kChunk; t < end && ok; t += 2) {
                const unsigned v00 = j * g + i, v10 = v00 + 1, v01 = v00 + g, v11 = v01 + 1;
                ok = tris[t] == glm::uvec3(v00, v10, v11) && tris[t + 1] == glm::uvec3(v00, v11, v01);
                if (++i == g - 1) {
                    i = 0;
                    ++j;
                }
            }
            chunk_grid[c] = ok ? 1 : 0;
        });
        return std::all_of(chunk_grid.begin(), chunk_grid.end(), [](std::uint8_t f) { return f != 0; });
    }

    RasterStats draw_grid(const RasterTriangles& batch, bool accumulate, Image& target, int g);
    // Pass 3 of draw(), one band of rows (raster.cpp).
    void draw_area_band(const RasterTriangles& batch, int band, bool accumulate, Image& target);
    void draw_center_band(const RasterTriangles& batch, int band, bool accumulate, Image& target);

    // Calls fn(sx, sy, band_lo, band_hi) for every copy of a triangle with bounding box b.
    template <class Fn>
    int for_each_copy(const Box& b, Fn&& fn) const {
        int sx0 = 0, sx1 = 0, sy0 = 0, sy1 = 0;
        if (wrap) {
            shift_range(b.xmin, b.xmax, width, sx0, sx1);
            shift_range(b.ymin, b.ymax, height, sy0, sy1);
            if ((sx1 - sx0 + 1) * (sy1 - sy0 + 1) > kMaxCopies) return -1;
        } else if (!(b.xmax >= 0.0f && b.xmin < width && b.ymax >= 0.0f && b.ymin < height)) {
            return 0;
        }
        int copies = 0;
        for (int sy = sy0; sy <= sy1; ++sy) {
            const double y0 = static_cast<double>(b.ymin) + static_cast<double>(sy) * height;
            const double y1 = static_cast<double>(b.ymax) + static_cast<double>(sy) * height;
            if (y1 < 0.0 || y0 >= height) continue;
            const int band_lo = static_cast<int>(std::max(y0, 0.0)) / kBandRows;
            const int band_hi = static_cast<int>(std::min(y1, height - 1.0)) / kBandRows;
            for (int sx = sx0; sx <= sx1; ++sx) {
                fn(sx, sy, band_lo, band_hi);
                ++copies;
            }
        }
        return copies;
    }
};

}  // namespace caustics
