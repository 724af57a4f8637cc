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

}  // namespace

struct TriangleRaster::Impl {
    std::vector<Box> boxes;
    std::vector<std::uint8_t> kinds;
    std::vector<glm::ivec2> band_range;   // without wrap: the bands of the single copy (pass 1 -> 2)
    std::vector<std::uint32_t> counts;    // [chunk][band]
    std::vector<std::uint32_t> cursors;   // [chunk][band] write positions
    std::vector<std::uint32_t> band_start;
    std::vector<BinEntry> entries;
    std::vector<RasterStats> chunk_stats;
    tbb::enumerable_thread_specific<std::vector<double>> band_acc;
    // Structured-grid path (Area coverage, no wrap): see draw_grid_bins.
    std::vector<double> tri_weight;          // per triangle: -value / signed area (0: draws no edges)
    std::vector<std::uint8_t> chunk_grid;    // per chunk: its triangles follow the grid pattern
    std::vector<double> edge_weight;         // per edge slot 3 v + type
    std::vector<glm::ivec2> edge_band;       // per edge slot: band range (x > y: none)
    std::vector<std::uint32_t> grid_entries; // (id << 2) | type; type 3: point-deposit triangle id

    int width = 0, height = 0, bands = 0;
    bool wrap = false;

    // Grid path: edge slot 3 v + type joins vertex v to v + 1 (type 0), v + g (1), v + g + 1 (2), drawn
    // in that direction with the weight of the triangle traversing it so minus the one traversing it
    // backwards; point-deposit triangles are listed with type 3. Fills band_start and grid_entries in a
    // fixed order (vertex rows in chunks of kGridChunkRows), whatever the thread count.
    void bin_grid(std::span<const glm::vec2> pos, int g) {
        const std::size_t nb = static_cast<std::size_t>(bands);
        const int chunks = (g + kGridChunkRows - 1) / kGridChunkRows;
        edge_weight.resize(3 * pos.size());
        edge_band.resize(3 * pos.size());
        counts.assign(static_cast<std::size_t>(chunks) * nb, 0u);
        cursors.resize(counts.size());
        const float fw = static_cast<float>(width), fh = static_cast<float>(height);
        const int last_row = height - 1;
        auto band_of = [&](float ya, float yb, glm::ivec2& r) {
            const float lo = std::min(ya, yb), hi = std::max(ya, yb);
            if (!(hi > 0.0f && lo < fh && lo != hi)) {
                r = {1, 0};
                return;
            }
            r.x = static_cast<int>(std::max(lo, 0.0f)) / kBandRows;
            r.y = std::min(static_cast<int>(hi), last_row) / kBandRows;
        };
        tbb::parallel_for(0, chunks, [&](int c) {
            std::uint32_t* count = counts.data() + static_cast<std::size_t>(c) * nb;
            const int j1 = std::min(g, (c + 1) * kGridChunkRows);
            for (int j = c * kGridChunkRows; j < j1; ++j) {
                for (int i = 0; i < g; ++i) {
                    const std::size_t v = static_cast<std::size_t>(j) * g + i;
                    const std::size_t tA = 2 * (static_cast<std::size_t>(j) * (g - 1) + i), tB = tA + 1;
                    const std::size_t left = tA - 2, below = tA - 2 * static_cast<std::size_t>(g - 1) + 1;
                    const bool in_i = i + 1 < g, in_j = j + 1 < g;
                    double w[3];
                    w[0] = in_i ? (in_j ? tri_weight[tA] : 0.0) - (j > 0 ? tri_weight[below] : 0.0) : 0.0;
                    w[1] = in_j ? (i > 0 ? tri_weight[left] : 0.0) - (in_i ? tri_weight[tB] : 0.0) : 0.0;
                    w[2] = in_i && in_j ? tri_weight[tB] - tri_weight[tA] : 0.0;
                    const std::size_t other[3] = {v + 1, v + g, v + g + 1};
                    for (int type = 0; type < 3; ++type) {
                        glm::ivec2& r = edge_band[3 * v + type];
                        edge_weight[3 * v + type] = w[type];
                        r = {1, 0};
                        if (w[type] == 0.0) continue;
                        const glm::vec2 a = pos[v], b = pos[other[type]];
                        if (std::min(a.x, b.x) >= fw) continue;   // deposits right of the image only
                        band_of(a.y, b.y, r);
                        for (int band = r.x; band <= r.y; ++band) ++count[band];
                    }
                    if (in_i && in_j)
                        for (std::size_t t : {tA, tB})
                            if (kinds[t] == kOnePixel || kinds[t] == kDegenerate)
                                for (int band = band_range[t].x; band <= band_range[t].y; ++band) ++count[band];
                }
            }
        });
        grid_entries.resize(band_offsets(counts, static_cast<std::size_t>(chunks), nb, cursors, band_start));
        tbb::parallel_for(0, chunks, [&](int c) {
            std::uint32_t* cursor = cursors.data() + static_cast<std::size_t>(c) * nb;
            const int j1 = std::min(g, (c + 1) * kGridChunkRows);
            for (int j = c * kGridChunkRows; j < j1; ++j) {
                for (int i = 0; i < g; ++i) {
                    const std::size_t v = static_cast<std::size_t>(j) * g + i;
                    for (int type = 0; type < 3; ++type) {
                        const glm::ivec2 r = edge_band[3 * v + type];
                        const std::uint32_t code = static_cast<std::uint32_t>(v << 2) | static_cast<std::uint32_t>(type);
                        for (int band = r.x; band <= r.y; ++band) grid_entries[cursor[band]++] = code;
                    }
                    if (i + 1 < g && j + 1 < g) {
                        const std::size_t tA = 2 * (static_cast<std::size_t>(j) * (g - 1) + i);
                        for (std::size_t t : {tA, tA + 1})
                            if (kinds[t] == kOnePixel || kinds[t] == kDegenerate)
                                for (int band = band_range[t].x; band <= band_range[t].y; ++band)
                                    grid_entries[cursor[band]++] = static_cast<std::uint32_t>(t << 2) | 3u;
                    }
                }
            }
        });
    }

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
    m.boxes.resize(ntri);
    m.kinds.resize(ntri);
    if (!m.wrap) m.band_range.resize(ntri);
    m.counts.assign(chunks * bands, 0u);
    m.cursors.resize(chunks * bands);
    m.band_start.resize(bands + 1);
    m.chunk_stats.assign(chunks, RasterStats{});

    const auto& pos = batch.positions;
    const auto& tris = batch.triangles;
    const std::size_t npos = pos.size();

    // A structured grid (g x g vertices, cells (i, j) split into {v00, v10, v11}, {v00, v11, v01}, as the
    // surface grids of caustic_triangles): in Area mode without wrap every interior edge is shared by two
    // triangles, so it is drawn once with the difference of their weights (half the edge work).
    int grid_g = 0;
    if (area && !m.wrap && ntri > 0) {
        const auto g = static_cast<std::size_t>(std::llround(std::sqrt(static_cast<double>(npos))));
        if (g >= 2 && g * g == npos && ntri == 2 * (g - 1) * (g - 1) && g < (std::size_t{1} << 14))
            grid_g = static_cast<int>(g);
    }
    m.tri_weight.resize(area ? ntri : 0);
    m.chunk_grid.assign(chunks, grid_g > 0 ? 1 : 0);

    // Pass 1: classify, bound and count the band entries of every triangle copy (per chunk).
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        RasterStats& st = m.chunk_stats[c];
        std::uint32_t* count = m.counts.data() + c * bands;
        const std::size_t end = std::min(ntri, (c + 1) * kChunk);
        if (grid_g > 0) {   // the chunk starts on an even triangle: cell c * kChunk / 2
            const unsigned g = static_cast<unsigned>(grid_g);
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
            m.chunk_grid[c] = ok ? 1 : 0;
        }
        // Local pointers: the byte stores to kinds would otherwise make every vector reload its data.
        std::uint8_t* const kinds = m.kinds.data();
        double* const tri_weight = m.tri_weight.data();
        Box* const boxes = m.boxes.data();
        glm::ivec2* const band_range = m.band_range.data();
        const glm::vec2* const P = pos.data();
        const float* const values = batch.triangle_values.data();
        const bool count_bands = grid_g == 0;   // grid: the edges are binned instead (bin_grid)
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
            bool finite = std::isfinite(value) && std::isfinite(p0.x) && std::isfinite(p0.y) &&
                          std::isfinite(p1.x) && std::isfinite(p1.y) && std::isfinite(p2.x) && std::isfinite(p2.y);
            if (finite && interpolate)
                finite = std::isfinite(batch.vertex_values[tri.x]) && std::isfinite(batch.vertex_values[tri.y]) &&
                         std::isfinite(batch.vertex_values[tri.z]);
            if (!finite) {
                ++local.nonfinite;
                continue;
            }
            const Box b{std::min({p0.x, p1.x, p2.x}), std::min({p0.y, p1.y, p2.y}),
                        std::max({p0.x, p1.x, p2.x}), std::max({p0.y, p1.y, p2.y})};
            TriangleKind kind = kNormal;
            if (area) {
                const double fx = std::floor(static_cast<double>(b.xmin));
                const double fy = std::floor(static_cast<double>(b.ymin));
                if (b.xmax <= fx + 1.0 && b.ymax <= fy + 1.0) {
                    kind = kOnePixel;
                } else {
                    const glm::dvec2 e1 = glm::dvec2(p1) - glm::dvec2(p0), e2 = glm::dvec2(p2) - glm::dvec2(p0);
                    const double area2 = std::abs(e1.x * e2.y - e1.y * e2.x);
                    const double diag2 = double(b.xmax - b.xmin) * (b.xmax - b.xmin) + double(b.ymax - b.ymin) * (b.ymax - b.ymin);
                    if (area2 <= 2e-8 + 2e-10 * diag2) kind = kDegenerate;   // would divide by ~0
                }
            } else if (std::max({std::abs(b.xmin), std::abs(b.xmax), std::abs(b.ymin), std::abs(b.ymax)}) >
                       kMaxFixedCoordinate) {
                ++local.too_large;
                continue;
            }
            const int copies = m.for_each_copy(b, [&](int, int, int lo, int hi) {
                if (count_bands)
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
            if (area && kind == kNormal) {
                // Coverage accumulates with the sign of -(signed area): weight = value / coverage. Wrap
                // copies are shifted by whole tiles, which leaves the (exact) differences unchanged.
                const glm::dvec2 q0(p0), q1(p1), q2(p2);
                const double signed_area = 0.5 * ((q1.x - q0.x) * (q2.y - q0.y) - (q1.y - q0.y) * (q2.x - q0.x));
                tri_weight[t] = -static_cast<double>(value) / signed_area;
            }
            local.drawn += copies;
            if (kind == kOnePixel || kind == kDegenerate) ++local.point_deposits;
        }
        st = local;
    });

    const bool grid = grid_g > 0 && std::all_of(m.chunk_grid.begin(), m.chunk_grid.end(), [](std::uint8_t f) { return f != 0; });
    if (grid) {
        m.bin_grid(pos, grid_g);
    } else if (grid_g > 0) {   // not a grid after all: count the band entries pass 1 skipped
        tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
            std::uint32_t* count = m.counts.data() + c * bands;
            const std::size_t end = std::min(ntri, (c + 1) * kChunk);
            for (std::size_t t = c * kChunk; t < end; ++t)
                if (m.kinds[t] != kSkip)
                    for (int band = m.band_range[t].x; band <= m.band_range[t].y; ++band) ++count[band];
        });
    }

    // Entry offsets (band_bins.hpp): each band lists its triangles in input order.
    if (!grid) {
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
    }

    // Pass 3: draw band by band (each band owns its rows of the target).
    const int W = m.width, H = m.height;
    const std::size_t stride = static_cast<std::size_t>(W) + 2;
    tbb::parallel_for(tbb::blocked_range<int>(0, m.bands, 1), [&](const tbb::blocked_range<int>& range) {
        for (int band = range.begin(); band != range.end(); ++band) {
            const int row0 = band * kBandRows, row1 = std::min(H, row0 + kBandRows);
            const BinEntry* first = grid ? nullptr : m.entries.data() + m.band_start[band];
            const BinEntry* last = grid ? nullptr : m.entries.data() + m.band_start[band + 1];
            if (area) {
                std::vector<double>& acc = m.band_acc.local();
                if (acc.size() < stride * kBandRows) acc.assign(stride * kBandRows, 0.0);
                auto deposit = [&](double x, double y, double value) {
                    const double fx = std::floor(x), fy = std::floor(y);
                    if (fx < 0.0 || fx >= W || fy < row0 || fy >= row1) return;
                    double* a = acc.data() + static_cast<std::size_t>(fy - row0) + static_cast<std::size_t>(fx) * kRows;
                    a[0] += value;
                    a[kRows] -= value;
                };
                if (grid) {
                    const std::uint32_t g = static_cast<std::uint32_t>(grid_g);
                    const std::uint32_t step[3] = {1u, g, g + 1u};
                    const std::uint32_t* ge = m.grid_entries.data();
                    for (std::uint32_t k = m.band_start[band], kend = m.band_start[band + 1]; k != kend; ++k) {
                        const std::uint32_t code = ge[k], type = code & 3u, id = code >> 2;
                        if (type != 3u) {
                            accumulate_edge(acc.data(), stride, row0, row1, W, glm::dvec2(pos[id]),
                                            glm::dvec2(pos[id + step[type]]), m.edge_weight[3 * std::size_t{id} + type]);
                            continue;
                        }
                        const glm::uvec3 tri = tris[id];
                        const double value = batch.triangle_values[id];
                        if (m.kinds[id] == kOnePixel) {
                            const Box& b = m.boxes[id];
                            deposit(b.xmin, b.ymin, value);
                        } else {
                            for (unsigned vi : {tri.x, tri.y, tri.z}) deposit(pos[vi].x, pos[vi].y, value / 3.0);
                        }
                    }
                }
                for (const BinEntry* e = first; e != last && !grid; ++e) {
                    const glm::uvec3 tri = tris[e->triangle];
                    const glm::dvec2 shift(static_cast<double>(e->sx) * W, static_cast<double>(e->sy) * H);
                    const glm::dvec2 p0 = glm::dvec2(pos[tri.x]) + shift, p1 = glm::dvec2(pos[tri.y]) + shift,
                                     p2 = glm::dvec2(pos[tri.z]) + shift;
                    const double value = batch.triangle_values[e->triangle];
                    const std::uint8_t kind = m.kinds[e->triangle];
                    if (kind == kOnePixel) {
                        const Box& b = m.boxes[e->triangle];
                        deposit(b.xmin + shift.x, b.ymin + shift.y, value);
                    } else if (kind == kDegenerate) {
                        for (const glm::dvec2& p : {p0, p1, p2}) deposit(p.x, p.y, value / 3.0);
                    } else {
                        const double weight = m.tri_weight[e->triangle];
                        accumulate_edge(acc.data(), stride, row0, row1, W, p0, p1, weight);
                        accumulate_edge(acc.data(), stride, row0, row1, W, p1, p2, weight);
                        accumulate_edge(acc.data(), stride, row0, row1, W, p2, p0, weight);
                    }
                }
                // Prefix sums along the rows, all rows of the band at once (column-major: vectorises).
                const int nrows = row1 - row0;
                float* out = target.pixels.data() + static_cast<std::size_t>(row0) * W;
                double run[kRows] = {};
                double* a = acc.data();
                for (int x = 0; x < W; ++x, a += kRows) {
                    float col[kRows];
                    for (int r = 0; r < kRows; ++r) {
                        run[r] += a[r];
                        a[r] = 0.0;
                        col[r] = static_cast<float>(run[r]);
                    }
                    if (options.accumulate) {
                        for (int r = 0; r < nrows; ++r) out[static_cast<std::size_t>(r) * W + x] += col[r];
                    } else {
                        for (int r = 0; r < nrows; ++r) out[static_cast<std::size_t>(r) * W + x] = col[r];
                    }
                }
                std::fill(a, a + 2 * kRows, 0.0);
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
