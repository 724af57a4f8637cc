#include <caustics/blocks/raster/raster.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/band_bins.hpp>
#include "detail/raster_area_coverage.hpp"
#include "detail/raster_impl.hpp"

namespace caustics {

TriangleRaster::TriangleRaster() : impl_(std::make_unique<Impl>()) {}
TriangleRaster::~TriangleRaster() = default;
TriangleRaster::TriangleRaster(TriangleRaster&&) noexcept = default;
TriangleRaster& TriangleRaster::operator=(TriangleRaster&&) noexcept = default;

// Area coverage of one band (pass 3): every listed triangle's edges (or point deposits) into the band's
// accumulator, then resolved into its rows of the target.
void TriangleRaster::Impl::draw_area_band(const RasterTriangles& batch, int band, bool accumulate, Image& target) {
    const auto& pos = batch.positions;
    const auto& tris = batch.triangles;
    const int W = width, H = height;
    const int row0 = band * kBandRows, row1 = std::min(H, row0 + kBandRows);
    const BinEntry* first = entries.data() + band_start[band];
    const BinEntry* last = entries.data() + band_start[band + 1];
    const std::size_t stride = static_cast<std::size_t>(W) + 2;
    double* const acc = band_accumulator(stride);
    for (const BinEntry* e = first; e != last; ++e) {
        const glm::uvec3 tri = tris[e->triangle];
        const glm::dvec2 shift(static_cast<double>(e->sx) * W, static_cast<double>(e->sy) * H);
        const glm::dvec2 p0 = glm::dvec2(pos[tri.x]) + shift, p1 = glm::dvec2(pos[tri.y]) + shift,
                         p2 = glm::dvec2(pos[tri.z]) + shift;
        const double value = batch.triangle_values[e->triangle];
        const std::uint8_t kind = kinds[e->triangle];
        if (kind == kOnePixel) {
            const Box& b = boxes[e->triangle];
            area_coverage::accumulate_point(acc, row0, row1, W, b.xmin + shift.x, b.ymin + shift.y, value);
        } else if (kind == kDegenerate) {
            for (const glm::dvec2& p : {p0, p1, p2})
                area_coverage::accumulate_point(acc, row0, row1, W, p.x, p.y, value / 3.0);
        } else {
            const double weight = tri_weight[e->triangle];
            accumulate_edge(acc, stride, row0, row1, W, p0, p1, weight);
            accumulate_edge(acc, stride, row0, row1, W, p1, p2, weight);
            accumulate_edge(acc, stride, row0, row1, W, p2, p0, weight);
        }
    }
    area_coverage::resolve_band(acc, W, row1 - row0, target.pixels.data() + static_cast<std::size_t>(row0) * W,
                                accumulate);
}

// Pixel-centre coverage of one band (pass 3): each listed triangle adds its value (or its interpolated
// vertex values) to the pixels whose centres it covers.
void TriangleRaster::Impl::draw_center_band(const RasterTriangles& batch, int band, bool accumulate, Image& target) {
    const auto& pos = batch.positions;
    const auto& tris = batch.triangles;
    const int W = width, H = height;
    const int row0 = band * kBandRows, row1 = std::min(H, row0 + kBandRows);
    const BinEntry* first = entries.data() + band_start[band];
    const BinEntry* last = entries.data() + band_start[band + 1];
    const bool interpolate = !batch.vertex_values.empty();
    // PixelCenter: integer edge functions on vertices snapped to 1/256 pixel.
    if (!accumulate)
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

    // A structured grid (g x g vertices, as a height-field method's surface grid) in Area mode without
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
    tbb::parallel_for(tbb::blocked_range<int>(0, m.bands, 1), [&](const tbb::blocked_range<int>& range) {
        for (int band = range.begin(); band != range.end(); ++band) {
            if (area)
                m.draw_area_band(batch, band, options.accumulate, target);
            else
                m.draw_center_band(batch, band, options.accumulate, target);
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
