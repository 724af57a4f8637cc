// TriangleRaster's structured-grid path (area coverage of a surface grid's triangles, no wrap).
#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/band_bins.hpp>
#include "detail/raster_impl.hpp"

namespace caustics {

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

}  // namespace caustics
