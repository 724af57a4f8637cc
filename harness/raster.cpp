#include "raster.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "band_bins.hpp"
#include "raster_area_coverage.hpp"

namespace caustics {
namespace {

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
void shift_range(double lo, double hi, double size, int& k_lo, int& k_hi) {
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
glm::ivec2 band_span(double ymin, double ymax, int height) {
    if (ymax < 0.0 || ymin >= height) return {1, 0};
    return {static_cast<int>(std::max(ymin, 0.0)) / TriangleRaster::kBandRows,
            static_cast<int>(std::min(ymax, height - 1.0)) / TriangleRaster::kBandRows};
}

}  // namespace

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
    // {v00, v11, v01} in row order (the surface grids of caustic_triangles).
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

TriangleRaster::TriangleRaster() : impl_(std::make_unique<Impl>()) {}
TriangleRaster::~TriangleRaster() = default;
TriangleRaster::TriangleRaster(TriangleRaster&&) noexcept = default;
TriangleRaster& TriangleRaster::operator=(TriangleRaster&&) noexcept = default;

// Structured grid, Area coverage, no wrap: every interior edge is shared by two triangles, so it is drawn
// once with the difference of their weights (half the edge work), and the pattern replaces the per-
// triangle bookkeeping of the general path. Edge type 0, 1, 2 of vertex v joins v to v + 1, v + g,
// v + g + 1, drawn in that direction with the weight of the triangle traversing it so, minus the one
// traversing it backwards. Lists are filled per fixed chunk of vertex rows and each band reads them in
// input order, so the result is the same for any thread count.
RasterStats TriangleRaster::Impl::draw_grid(const RasterTriangles& batch, bool accumulate, Image& target, int g) {
    const glm::vec2* const P = batch.positions.data();
    const float* const values = batch.triangle_values.data();
    const std::size_t ntri = batch.triangles.size(), nb = static_cast<std::size_t>(bands);
    const std::size_t cells = static_cast<std::size_t>(g - 1);
    const int W = width, H = height;
    kinds.resize(ntri);
    tri_weight.resize(ntri);

    // Edge lists per [vertex-row chunk][part][band]: part 0 holds the chunk's first vertex row, whose edges
    // need the previous chunk's triangles, part 1 its other rows; a band reads them in that order.
    const int chunks = (g + kGridChunkRows - 1) / kGridChunkRows;
    grid_lists.resize(static_cast<std::size_t>(chunks) * 2 * nb);
    auto lists_of = [&](int c, int part) { return grid_lists.data() + (static_cast<std::size_t>(c) * 2 + part) * nb; };
    const double* const tw = tri_weight.data();
    const float fw = static_cast<float>(W), fh = static_cast<float>(H);
    const int last_row = H - 1;
    // Lists every edge of vertex row j with a non-zero weight, and every point-deposit triangle of cell row
    // j, in the bands they touch.
    auto bin_row = [&](int j, std::vector<GridEdge>* lists) {
        const bool in_j = j + 1 < g;
        for (int i = 0; i < g; ++i) {
            const std::size_t v = static_cast<std::size_t>(j) * g + i;
            const std::size_t tA = 2 * (static_cast<std::size_t>(j) * cells + i), tB = tA + 1;
            const std::size_t left = tA - 2, below = tA - 2 * cells + 1;
            const bool in_i = i + 1 < g;
            double w[3];
            w[0] = in_i ? (in_j ? tw[tA] : 0.0) - (j > 0 ? tw[below] : 0.0) : 0.0;
            w[1] = in_j ? (i > 0 ? tw[left] : 0.0) - (in_i ? tw[tB] : 0.0) : 0.0;
            w[2] = in_i && in_j ? tw[tB] - tw[tA] : 0.0;
            const std::size_t other[3] = {v + 1, v + g, v + g + 1};
            for (int type = 0; type < 3; ++type) {
                if (w[type] == 0.0) continue;
                const glm::vec2 a = P[v], b = P[other[type]];
                if (std::min(a.x, b.x) >= fw) continue;   // deposits right of the image only
                const float lo = std::min(a.y, b.y), hi = std::max(a.y, b.y);
                if (!(hi > 0.0f && lo < fh && lo != hi)) continue;
                const int band_lo = static_cast<int>(std::max(lo, 0.0f)) / kBandRows;
                const int band_hi = std::min(static_cast<int>(hi), last_row) / kBandRows;
                const std::uint32_t code = static_cast<std::uint32_t>(v << 2) | static_cast<std::uint32_t>(type);
                for (int band = band_lo; band <= band_hi; ++band) lists[band].push_back({w[type], code});
            }
            if (!(in_i && in_j)) continue;
            for (std::size_t t : {tA, tB}) {
                if (kinds[t] != kOnePixel && kinds[t] != kDegenerate) continue;
                const glm::uvec3 tri = batch.triangles[t];
                const Box box = bounding_box(P[tri.x], P[tri.y], P[tri.z]);
                const glm::ivec2 span = band_span(box.ymin, box.ymax, H);
                for (int band = span.x; band <= span.y; ++band)
                    lists[band].push_back({0.0, static_cast<std::uint32_t>(t << 2) | 3u});
            }
        }
    };

    // Pass 1, chunks of rows: classify the two triangles of every cell, then list the edges of the rows
    // whose triangles are all the chunk's own (the cache still holds their weights).
    chunk_stats.assign(static_cast<std::size_t>(chunks), RasterStats{});
    tbb::parallel_for(0, chunks, [&](int c) {
        const int j0 = c * kGridChunkRows, j1 = std::min(g, j0 + kGridChunkRows);
        TriangleKind* const kind = kinds.data();
        double* const weight = tri_weight.data();
        RasterStats st;
        // Both triangles of a cell share the diagonal p00-p11: its box and finiteness are found once.
        auto classify = [&](std::size_t t, const Box& diagonal, bool diagonal_finite, glm::vec2 p0, glm::vec2 p1,
                            glm::vec2 p2, glm::vec2 apex) {
            const float value = values[t];
            TriangleKind k = kSkip;
            double w = 0.0;
            if (value != 0.0f) {
                const Box b{std::min(diagonal.xmin, apex.x), std::min(diagonal.ymin, apex.y),
                            std::max(diagonal.xmax, apex.x), std::max(diagonal.ymax, apex.y)};
                if (!(diagonal_finite && std::isfinite(apex.x) && std::isfinite(apex.y) && std::isfinite(value))) {
                    ++st.nonfinite;
                } else if (b.xmax >= 0.0f && b.xmin < fw && b.ymax >= 0.0f && b.ymin < fh) {
                    const double cross = cross2(p0, p1, p2);
                    k = area_kind(b, cross);
                    ++st.drawn;
                    if (k == kNormal) w = area_weight(cross, value);
                    else ++st.point_deposits;
                }
            }
            kind[t] = k;
            weight[t] = w;
        };
        const std::size_t cell_end = std::min(cells, static_cast<std::size_t>(j1));
        for (std::size_t j = static_cast<std::size_t>(j0); j < cell_end; ++j) {
            const glm::vec2* row = P + j * g;
            for (std::size_t i = 0; i < cells; ++i) {
                const glm::vec2 p00 = row[i], p10 = row[i + 1], p01 = row[i + g], p11 = row[i + g + 1];
                const Box diagonal{std::min(p00.x, p11.x), std::min(p00.y, p11.y), std::max(p00.x, p11.x),
                                   std::max(p00.y, p11.y)};
                const bool diagonal_finite =
                    std::isfinite(p00.x) && std::isfinite(p00.y) && std::isfinite(p11.x) && std::isfinite(p11.y);
                const std::size_t t = 2 * (j * cells + i);
                classify(t, diagonal, diagonal_finite, p00, p10, p11, p10);
                classify(t + 1, diagonal, diagonal_finite, p00, p11, p01, p01);
            }
        }
        chunk_stats[static_cast<std::size_t>(c)] = st;
        std::vector<GridEdge>* const lists = lists_of(c, 1);
        for (std::size_t b = 0; b < nb; ++b) lists[b].clear();
        for (int j = j0 + 1; j < j1; ++j) bin_row(j, lists);
    });
    // Pass 2: the first row of every chunk.
    tbb::parallel_for(0, chunks, [&](int c) {
        std::vector<GridEdge>* const lists = lists_of(c, 0);
        for (std::size_t b = 0; b < nb; ++b) lists[b].clear();
        bin_row(c * kGridChunkRows, lists);
    });

    // Pass 3: draw band by band (each band owns its rows of the target).
    const std::size_t stride = static_cast<std::size_t>(W) + 2;
    const std::uint32_t step[3] = {1u, static_cast<std::uint32_t>(g), static_cast<std::uint32_t>(g) + 1u};
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& range) {
        double* const acc = band_accumulator(stride);
        for (int band = range.begin(); band != range.end(); ++band) {
            const int row0 = band * kBandRows, row1 = std::min(H, row0 + kBandRows);
            for (std::size_t list = 0; list < 2 * static_cast<std::size_t>(chunks); ++list) {
                for (const GridEdge& e : grid_lists[list * nb + band]) {
                    const std::uint32_t type = e.code & 3u, id = e.code >> 2;
                    if (type != 3u) {
                        area_coverage::accumulate_edge(acc, stride, row0, row1, W, glm::dvec2(P[id]),
                                                       glm::dvec2(P[id + step[type]]), e.weight);
                        continue;
                    }
                    const glm::uvec3 tri = batch.triangles[id];
                    const double value = values[id];
                    if (kinds[id] == kOnePixel) {
                        const Box b = bounding_box(P[tri.x], P[tri.y], P[tri.z]);
                        area_coverage::accumulate_point(acc, row0, row1, W, b.xmin, b.ymin, value);
                    } else {
                        for (unsigned vi : {tri.x, tri.y, tri.z})
                            area_coverage::accumulate_point(acc, row0, row1, W, P[vi].x, P[vi].y, value / 3.0);
                    }
                }
            }
            area_coverage::resolve_band(acc, W, row1 - row0, target.pixels.data() + static_cast<std::size_t>(row0) * W,
                                        accumulate);
        }
    });

    RasterStats total;
    for (const RasterStats& s : chunk_stats) {
        total.drawn += s.drawn;
        total.nonfinite += s.nonfinite;
        total.point_deposits += s.point_deposits;
    }
    return total;
}

RasterStats TriangleRaster::draw(const RasterTriangles& batch, const RasterOptions& options, Image& target) {
    Impl& m = *impl_;
    if (target.channels != 1 || target.width <= 0 || target.height <= 0 ||
        target.pixels.size() != static_cast<std::size_t>(target.width) * target.height)
        throw std::invalid_argument("TriangleRaster::draw: target must be a non-empty 1-channel image");
    if (batch.triangle_values.size() != batch.triangles.size())
        throw std::invalid_argument("TriangleRaster::draw: one triangle value per triangle required");
    const bool interpolate = !batch.vertex_values.empty();
    if (interpolate && batch.vertex_values.size() != batch.positions.size())
        throw std::invalid_argument("TriangleRaster::draw: one vertex value per position required");
    if (interpolate && options.coverage == RasterCoverage::Area)
        throw std::invalid_argument("TriangleRaster::draw: Area coverage takes per-triangle values only");

    const bool area = options.coverage == RasterCoverage::Area;
    m.width = target.width;
    m.height = target.height;
    m.wrap = options.wrap;
    m.bands = (m.height + kBandRows - 1) / kBandRows;
    const std::size_t ntri = batch.triangles.size();
    const std::size_t chunks = (ntri + kChunk - 1) / kChunk;
    const std::size_t bands = static_cast<std::size_t>(m.bands);
    const auto& pos = batch.positions;
    const auto& tris = batch.triangles;
    const std::size_t npos = pos.size();

    // A structured grid (g x g vertices, as the surface grids of caustic_triangles) in Area mode without
    // wrap takes the shared-edge path (draw_grid).
    if (area && !m.wrap && ntri > 0) {
        const auto g = static_cast<std::size_t>(std::llround(std::sqrt(static_cast<double>(npos))));
        if (g >= 2 && g * g == npos && ntri == 2 * (g - 1) * (g - 1) && g < (std::size_t{1} << 14) &&
            m.is_grid(tris, static_cast<unsigned>(g)))
            return m.draw_grid(batch, options.accumulate, target, static_cast<int>(g));
    }

    m.boxes.resize(ntri);
    m.kinds.resize(ntri);
    if (!m.wrap) m.band_range.resize(ntri);
    m.counts.assign(chunks * bands, 0u);
    m.cursors.resize(chunks * bands);
    m.band_start.resize(bands + 1);
    m.chunk_stats.assign(chunks, RasterStats{});
    m.tri_weight.resize(area ? ntri : 0);

    // Pass 1: classify, bound and count the band entries of every triangle copy (per chunk).
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        RasterStats& st = m.chunk_stats[c];
        std::uint32_t* count = m.counts.data() + c * bands;
        const std::size_t end = std::min(ntri, (c + 1) * kChunk);
        // Local pointers: stores through the vectors would otherwise make every one reload its data.
        TriangleKind* const kinds = m.kinds.data();
        double* const tri_weight = m.tri_weight.data();
        Box* const boxes = m.boxes.data();
        glm::ivec2* const band_range = m.band_range.data();
        const glm::vec2* const P = pos.data();
        const float* const values = batch.triangle_values.data();
        RasterStats local;
        for (std::size_t t = c * kChunk; t < end; ++t) {
            kinds[t] = kSkip;
            if (area) tri_weight[t] = 0.0;
            const glm::uvec3 tri = tris[t];
            const float value = values[t];
            if (!interpolate && value == 0.0f) continue;
            if (tri.x >= npos || tri.y >= npos || tri.z >= npos)
                throw std::invalid_argument("TriangleRaster::draw: triangle index out of range");
            const glm::vec2 p0 = P[tri.x], p1 = P[tri.y], p2 = P[tri.z];
            bool finite = finite_triangle(p0, p1, p2, value);
            if (finite && interpolate)
                finite = std::isfinite(batch.vertex_values[tri.x]) && std::isfinite(batch.vertex_values[tri.y]) &&
                         std::isfinite(batch.vertex_values[tri.z]);
            if (!finite) {
                ++local.nonfinite;
                continue;
            }
            const Box b = bounding_box(p0, p1, p2);
            TriangleKind kind = kNormal;
            if (area) {
                kind = area_kind(b, cross2(p0, p1, p2));
            } else if (std::max({std::abs(b.xmin), std::abs(b.xmax), std::abs(b.ymin), std::abs(b.ymax)}) >
                       kMaxFixedCoordinate) {
                ++local.too_large;
                continue;
            }
            const int copies = m.for_each_copy(b, [&](int, int, int lo, int hi) {
                for (int band = lo; band <= hi; ++band) ++count[band];
                if (!m.wrap) band_range[t] = {lo, hi};
            });
            if (copies < 0) {
                ++local.too_large;
                continue;
            }
            if (copies == 0) continue;
            boxes[t] = b;
            kinds[t] = kind;
            if (area && kind == kNormal) tri_weight[t] = area_weight(cross2(p0, p1, p2), value);
            local.drawn += copies;
            if (kind == kOnePixel || kind == kDegenerate) ++local.point_deposits;
        }
        st = local;
    });

    // Entry offsets (band_bins.hpp): each band lists its triangles in input order.
    m.entries.resize(band_offsets(m.counts, chunks, bands, m.cursors, m.band_start));

    // Pass 2: fill the band lists.
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        std::uint32_t* cursor = m.cursors.data() + c * bands;
        const std::size_t end = std::min(ntri, (c + 1) * kChunk);
        for (std::size_t t = c * kChunk; t < end; ++t) {
            if (m.kinds[t] == kSkip) continue;
            if (!m.wrap) {
                for (int band = m.band_range[t].x; band <= m.band_range[t].y; ++band)
                    m.entries[cursor[band]++] = {static_cast<std::uint32_t>(t), 0, 0};
                continue;
            }
            m.for_each_copy(m.boxes[t], [&](int sx, int sy, int lo, int hi) {
                for (int band = lo; band <= hi; ++band)
                    m.entries[cursor[band]++] = {static_cast<std::uint32_t>(t), static_cast<std::int16_t>(sx),
                                                 static_cast<std::int16_t>(sy)};
            });
        }
    });

    // Pass 3: draw band by band (each band owns its rows of the target).
    const int W = m.width, H = m.height;
    const std::size_t stride = static_cast<std::size_t>(W) + 2;
    tbb::parallel_for(tbb::blocked_range<int>(0, m.bands, 1), [&](const tbb::blocked_range<int>& range) {
        for (int band = range.begin(); band != range.end(); ++band) {
            const int row0 = band * kBandRows, row1 = std::min(H, row0 + kBandRows);
            const BinEntry* first = m.entries.data() + m.band_start[band];
            const BinEntry* last = m.entries.data() + m.band_start[band + 1];
            if (area) {
                double* const acc = m.band_accumulator(stride);
                for (const BinEntry* e = first; e != last; ++e) {
                    const glm::uvec3 tri = tris[e->triangle];
                    const glm::dvec2 shift(static_cast<double>(e->sx) * W, static_cast<double>(e->sy) * H);
                    const glm::dvec2 p0 = glm::dvec2(pos[tri.x]) + shift, p1 = glm::dvec2(pos[tri.y]) + shift,
                                     p2 = glm::dvec2(pos[tri.z]) + shift;
                    const double value = batch.triangle_values[e->triangle];
                    const std::uint8_t kind = m.kinds[e->triangle];
                    if (kind == kOnePixel) {
                        const Box& b = m.boxes[e->triangle];
                        area_coverage::accumulate_point(acc, row0, row1, W, b.xmin + shift.x, b.ymin + shift.y, value);
                    } else if (kind == kDegenerate) {
                        for (const glm::dvec2& p : {p0, p1, p2})
                            area_coverage::accumulate_point(acc, row0, row1, W, p.x, p.y, value / 3.0);
                    } else {
                        const double weight = m.tri_weight[e->triangle];
                        accumulate_edge(acc, stride, row0, row1, W, p0, p1, weight);
                        accumulate_edge(acc, stride, row0, row1, W, p1, p2, weight);
                        accumulate_edge(acc, stride, row0, row1, W, p2, p0, weight);
                    }
                }
                area_coverage::resolve_band(acc, W, row1 - row0, target.pixels.data() + static_cast<std::size_t>(row0) * W,
                                            options.accumulate);
                continue;
            }

            // PixelCenter: integer edge functions on vertices snapped to 1/256 pixel.
            if (!options.accumulate)
                std::fill(target.pixels.begin() + static_cast<std::ptrdiff_t>(row0) * W,
                          target.pixels.begin() + static_cast<std::ptrdiff_t>(row1) * W, 0.0f);
            const std::int64_t one = std::int64_t{1} << kSubpixelBits, half = one / 2;
            for (const BinEntry* e = first; e != last; ++e) {
                const glm::uvec3 tri = tris[e->triangle];
                unsigned idx[3] = {tri.x, tri.y, tri.z};
                std::int64_t X[3], Y[3];
                for (int k = 0; k < 3; ++k) {
                    X[k] = std::llround(static_cast<double>(pos[idx[k]].x) * kSubpixel) + e->sx * W * one;
                    Y[k] = std::llround(static_cast<double>(pos[idx[k]].y) * kSubpixel) + e->sy * H * one;
                }
                std::int64_t area2 = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
                if (area2 == 0) continue;   // no interior: covers no centre
                if (area2 < 0) {
                    std::swap(X[1], X[2]);
                    std::swap(Y[1], Y[2]);
                    std::swap(idx[1], idx[2]);
                    area2 = -area2;
                }
                // Edge k runs from vertex k+1 to k+2 (opposite vertex k); E_k > 0 inside.
                std::int64_t ex[3], ey[3], bias[3];
                for (int k = 0; k < 3; ++k) {
                    const int a = (k + 1) % 3, b = (k + 2) % 3;
                    ex[k] = X[b] - X[a];
                    ey[k] = Y[b] - Y[a];
                    // Tie rule = an infinitesimal shift of the sample point by (eta, eps), eta << eps:
                    // a centre on the edge is inside iff dx > 0, or dx == 0 and dy < 0.
                    bias[k] = (ex[k] > 0 || (ex[k] == 0 && ey[k] < 0)) ? 0 : -1;
                }
                const std::int64_t xmin = std::min({X[0], X[1], X[2]}), xmax = std::max({X[0], X[1], X[2]});
                const std::int64_t ymin = std::min({Y[0], Y[1], Y[2]}), ymax = std::max({Y[0], Y[1], Y[2]});
                const std::int64_t i0 = std::max<std::int64_t>(0, floor_div(xmin - half + one - 1, one));
                const std::int64_t i1 = std::min<std::int64_t>(W - 1, floor_div(xmax - half, one));
                const std::int64_t j0 = std::max<std::int64_t>(row0, floor_div(ymin - half + one - 1, one));
                const std::int64_t j1 = std::min<std::int64_t>(row1 - 1, floor_div(ymax - half, one));
                if (i0 > i1 || j0 > j1) continue;
                const float constant = batch.triangle_values[e->triangle];
                float vv[3] = {0.0f, 0.0f, 0.0f};
                if (interpolate)
                    for (int k = 0; k < 3; ++k) vv[k] = batch.vertex_values[idx[k]];
                const double inv_area2 = 1.0 / static_cast<double>(area2);
                const std::int64_t px0 = i0 * one + half;
                for (std::int64_t j = j0; j <= j1; ++j) {
                    const std::int64_t py = j * one + half;
                    std::int64_t w[3];
                    for (int k = 0; k < 3; ++k) {
                        const int a = (k + 1) % 3;
                        w[k] = ex[k] * (py - Y[a]) - ey[k] * (px0 - X[a]) + bias[k];
                    }
                    float* out = target.pixels.data() + static_cast<std::size_t>(j) * W;
                    for (std::int64_t i = i0; i <= i1; ++i) {
                        if ((w[0] | w[1] | w[2]) >= 0) {
                            float v = constant;
                            if (interpolate)
                                v = static_cast<float>(((w[0] - bias[0]) * double(vv[0]) + (w[1] - bias[1]) * double(vv[1]) +
                                                        (w[2] - bias[2]) * double(vv[2])) * inv_area2);
                            out[i] += v;
                        }
                        for (int k = 0; k < 3; ++k) w[k] -= ey[k] * one;
                    }
                }
            }
        }
    });

    RasterStats total;
    for (const RasterStats& s : m.chunk_stats) {
        total.drawn += s.drawn;
        total.nonfinite += s.nonfinite;
        total.point_deposits += s.point_deposits;
        total.too_large += s.too_large;
    }
    return total;
}

}  // namespace caustics
