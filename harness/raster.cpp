#include "raster.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

namespace caustics {
namespace {

constexpr std::size_t kChunk = 4096;    // triangles per binning work item (fixed: keeps output order)
constexpr int kMaxCopies = 9;           // wrap: a triangle may touch at most 3 x 3 image tiles
constexpr int kSubpixelBits = 8;        // PixelCenter: fixed-point vertex snapping (1/256 pixel)
constexpr double kSubpixel = 1 << kSubpixelBits;
constexpr double kMaxFixedCoordinate = 1 << 22;  // pixels; keeps edge functions well inside int64

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

// Phi(u) = integral_0^u clamp(t, 0, 1) dt: the area right of a sloped edge inside one pixel column.
inline double phi(double u) {
    if (u <= 0.0) return 0.0;
    if (u >= 1.0) return u - 0.5;
    return 0.5 * u * u;
}

// Accumulates into one band the x-derivative of the signed coverage of the segment (x0, y0) -> (x1, y1)
// with x already inside [0, width]. `acc` holds band rows [row0, row1) with `stride` doubles each; a
// prefix sum along a row turns it into coverage (edges going down the rows add, going up subtract).
// In a row slice of height dy where the edge spans columns i0..i1, column i gets
// d * (Phi(i+1-xl) - Phi(i+1-xr)) / (xr - xl), d = dy * weight; d / (xr - xl) = weight / |dx/dy| is the
// same for every row, so the only division is per edge. The last column takes the remainder, so each
// row slice deposits exactly d whatever the rounding (flux conservation).
inline void accumulate_line(double* acc, std::size_t stride, int row0, int row1, double width, double x0,
                            double y0, double x1, double y1, double weight) {
    if (y0 == y1) return;
    double sign = weight;
    if (y0 > y1) {
        std::swap(x0, x1);
        std::swap(y0, y1);
        sign = -weight;
    }
    const double ytop = std::max(y0, static_cast<double>(row0));
    const double ybot = std::min(y1, static_cast<double>(row1));
    if (ytop >= ybot) return;
    const double dxdy = (x1 - x0) / (y1 - y0);
    const double slope = dxdy != 0.0 ? sign / std::abs(dxdy) : 0.0;
    int row = static_cast<int>(ytop);   // ytop >= row0 >= 0: truncation is floor
    double* a = acc + static_cast<std::size_t>(row - row0) * stride;
    double ya = ytop;
    double xa = x0 + (ya - y0) * dxdy;
    while (ya < ybot) {
        const double yb = std::min(row + 1.0, ybot);
        const double xb = x0 + (yb - y0) * dxdy;
        const double d = sign * (yb - ya);
        const double xl = std::clamp(std::min(xa, xb), 0.0, width);
        const double xr = std::clamp(std::max(xa, xb), 0.0, width);
        const int i0 = static_cast<int>(xl);
        if (xr <= i0 + 1.0) {
            // Within one pixel column: the part right of the mean x stays in column i0.
            const double xm = 0.5 * (xl + xr) - i0;
            a[i0] += d - d * xm;
            a[i0 + 1] += d * xm;
        } else {
            const int i1 = static_cast<int>(std::ceil(xr)) - 1;
            double previous = slope * (0.5 * (i0 + 1.0 - xl) * (i0 + 1.0 - xl));   // phi(c - xr) = 0 here
            a[i0] += previous;
            for (int i = i0 + 1; i < i1; ++i) {   // fully crossed columns: phi(c - xl) = c - xl - 1/2
                const double cover = slope * (i + 0.5 - xl);
                a[i] += cover - previous;
                previous = cover;
            }
            const double c = i1 + 1.0;
            const double cover = slope * (phi(c - xl) - phi(c - xr));
            a[i1] += cover - previous;
            a[i1 + 1] += d - cover;
        }
        xa = xb;
        ya = yb;
        ++row;
        a += stride;
    }
}

// Splits an edge at x = 0 and x = width and clamps the outside pieces onto those lines: coverage of a
// pixel column depends only on the edge's crossings to its left, so this is exact inside the image.
void accumulate_edge(double* acc, std::size_t stride, int row0, int row1, double width, glm::dvec2 a,
                     glm::dvec2 b, double weight) {
    if (a.y == b.y) return;
    if (std::max(a.y, b.y) <= row0 || std::min(a.y, b.y) >= row1) return;
    if (a.x >= 0.0 && a.x <= width && b.x >= 0.0 && b.x <= width) {
        accumulate_line(acc, stride, row0, row1, width, a.x, a.y, b.x, b.y, weight);
        return;
    }
    double ts[4] = {0.0, 1.0, 1.0, 1.0};
    int n = 1;
    const double dx = b.x - a.x;
    if (dx != 0.0) {
        for (double line : {0.0, width}) {
            const double t = (line - a.x) / dx;
            if (t > 0.0 && t < 1.0) ts[n++] = t;
        }
    }
    if (n == 3 && ts[2] < ts[1]) std::swap(ts[1], ts[2]);
    ts[n++] = 1.0;
    for (int k = 0; k + 1 < n; ++k) {
        const glm::dvec2 p = a + ts[k] * (b - a);
        const glm::dvec2 q = a + ts[k + 1] * (b - a);
        const double xc = std::clamp(0.5 * (p.x + q.x), 0.0, width);
        const bool outside = 0.5 * (p.x + q.x) != xc;
        accumulate_line(acc, stride, row0, row1, width, outside ? xc : std::clamp(p.x, 0.0, width), p.y,
                        outside ? xc : std::clamp(q.x, 0.0, width), q.y, weight);
    }
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

    int width = 0, height = 0, bands = 0;
    bool wrap = false;

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

    // Pass 1: classify, bound and count the band entries of every triangle copy (per chunk).
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        RasterStats& st = m.chunk_stats[c];
        std::uint32_t* count = m.counts.data() + c * bands;
        const std::size_t end = std::min(ntri, (c + 1) * kChunk);
        for (std::size_t t = c * kChunk; t < end; ++t) {
            m.kinds[t] = kSkip;
            const glm::uvec3 tri = tris[t];
            const float value = batch.triangle_values[t];
            if (!interpolate && value == 0.0f) continue;
            if (tri.x >= npos || tri.y >= npos || tri.z >= npos)
                throw std::invalid_argument("TriangleRaster::draw: triangle index out of range");
            const glm::vec2 p0 = pos[tri.x], p1 = pos[tri.y], p2 = pos[tri.z];
            bool finite = std::isfinite(value) && std::isfinite(p0.x) && std::isfinite(p0.y) &&
                          std::isfinite(p1.x) && std::isfinite(p1.y) && std::isfinite(p2.x) && std::isfinite(p2.y);
            if (finite && interpolate)
                finite = std::isfinite(batch.vertex_values[tri.x]) && std::isfinite(batch.vertex_values[tri.y]) &&
                         std::isfinite(batch.vertex_values[tri.z]);
            if (!finite) {
                ++st.nonfinite;
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
                ++st.too_large;
                continue;
            }
            const int copies = m.for_each_copy(b, [&](int, int, int lo, int hi) {
                for (int band = lo; band <= hi; ++band) ++count[band];
                if (!m.wrap) m.band_range[t] = {lo, hi};
            });
            if (copies < 0) {
                ++st.too_large;
                continue;
            }
            if (copies == 0) continue;
            m.boxes[t] = b;
            m.kinds[t] = kind;
            st.drawn += copies;
            if (kind == kOnePixel || kind == kDegenerate) ++st.point_deposits;
        }
    });

    // Entry offsets: band-major, chunk-minor, so each band lists its triangles in input order.
    std::uint32_t running = 0;
    for (std::size_t b = 0; b < bands; ++b) {
        m.band_start[b] = running;
        for (std::size_t c = 0; c < chunks; ++c) {
            m.cursors[c * bands + b] = running;
            running += m.counts[c * bands + b];
        }
    }
    m.band_start[bands] = running;
    m.entries.resize(running);

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
                std::vector<double>& acc = m.band_acc.local();
                if (acc.size() < stride * kBandRows) acc.assign(stride * kBandRows, 0.0);
                auto deposit = [&](double x, double y, double value) {
                    const double fx = std::floor(x), fy = std::floor(y);
                    if (fx < 0.0 || fx >= W || fy < row0 || fy >= row1) return;
                    double* a = acc.data() + static_cast<std::size_t>(fy - row0) * stride + static_cast<std::size_t>(fx);
                    a[0] += value;
                    a[1] -= value;
                };
                for (const BinEntry* e = first; e != last; ++e) {
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
                        // Coverage accumulates with the sign of -(signed area): weight = value / coverage.
                        const double signed_area = 0.5 * ((p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x));
                        const double weight = -value / signed_area;
                        accumulate_edge(acc.data(), stride, row0, row1, W, p0, p1, weight);
                        accumulate_edge(acc.data(), stride, row0, row1, W, p1, p2, weight);
                        accumulate_edge(acc.data(), stride, row0, row1, W, p2, p0, weight);
                    }
                }
                for (int row = row0; row < row1; ++row) {
                    double* a = acc.data() + static_cast<std::size_t>(row - row0) * stride;
                    float* out = target.pixels.data() + static_cast<std::size_t>(row) * W;
                    double run = 0.0;
                    if (options.accumulate) {
                        for (int x = 0; x < W; ++x) {
                            run += a[x];
                            a[x] = 0.0;
                            out[x] += static_cast<float>(run);
                        }
                    } else {
                        for (int x = 0; x < W; ++x) {
                            run += a[x];
                            a[x] = 0.0;
                            out[x] = static_cast<float>(run);
                        }
                    }
                    a[W] = a[W + 1] = 0.0;
                }
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
