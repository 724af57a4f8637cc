#pragma once
// Exact area coverage of polygon edges for TriangleRaster's Area mode (see raster.hpp): an edge deposits
// the x-derivative of its signed coverage into a band accumulator, and a prefix sum along each row
// turns the deposits of a closed polygon's edges into the area of the polygon inside every pixel.
// Band accumulators are column-major (column i of band row r at acc[i * kRows + r]) so that the prefix
// sum over all rows of a band vectorises.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include <glm/glm.hpp>

#include <caustics/blocks/raster/raster.hpp>

namespace caustics::area_coverage {

constexpr int kRows = TriangleRaster::kBandRows;

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
    double* a = acc + (row - row0);   // transposed band: column i of this row at a[i * kRows]
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
            a[i0 * kRows] += d - d * xm;
            a[(i0 + 1) * kRows] += d * xm;
        } else {
            const int i1 = static_cast<int>(xr) - (static_cast<int>(xr) == xr ? 1 : 0);   // ceil(xr) - 1, xr >= 0
            double previous = slope * (0.5 * (i0 + 1.0 - xl) * (i0 + 1.0 - xl));   // phi(c - xr) = 0 here
            a[i0 * kRows] += previous;
            for (int i = i0 + 1; i < i1; ++i) {   // fully crossed columns: phi(c - xl) = c - xl - 1/2
                const double cover = slope * (i + 0.5 - xl);
                a[i * kRows] += cover - previous;
                previous = cover;
            }
            const double c = i1 + 1.0;
            const double cover = slope * (phi(c - xl) - phi(c - xr));
            a[i1 * kRows] += cover - previous;
            a[(i1 + 1) * kRows] += d - cover;
        }
        xa = xb;
        ya = yb;
        ++row;
        ++a;
    }
}

// Splits an edge at x = 0 and x = width and clamps the outside pieces onto those lines: coverage of a
// pixel column depends only on the edge's crossings to its left, so this is exact inside the image.
inline void accumulate_edge(double* acc, std::size_t stride, int row0, int row1, double width, glm::dvec2 a,
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

// Deposits a whole value into the pixel containing (x, y) when that pixel lies in the band [row0, row1)
// (point deposits: triangles inside one pixel and degenerate ones).
inline void accumulate_point(double* acc, int row0, int row1, int width, double x, double y, double value) {
    const double fx = std::floor(x), fy = std::floor(y);
    if (fx < 0.0 || fx >= width || fy < row0 || fy >= row1) return;
    double* a = acc + static_cast<std::size_t>(fy - row0) + static_cast<std::size_t>(fx) * kRows;
    a[0] += value;
    a[kRows] -= value;
}

// Turns a band's deposits into coverage: prefix sums along its rows, all rows at once (column-major:
// vectorises), written to `out` (the band's first row of a row-major image `width` wide, `nrows` rows)
// by adding or overwriting. Columns go through a small row-major tile so that the image is written in
// runs along its rows rather than a pixel per row per column. Clears the accumulator for the next band.
inline void resolve_band(double* acc, int width, int nrows, float* out, bool accumulate) {
    constexpr int kTile = 64;   // columns per tile (a 4 KiB tile of floats stays in L1)
    double run[kRows] = {};
    float tile[kRows][kTile];
    double* a = acc;
    for (int x0 = 0; x0 < width; x0 += kTile) {
        const int n = std::min(kTile, width - x0);
        for (int k = 0; k < n; ++k, a += kRows)
            for (int r = 0; r < kRows; ++r) {
                run[r] += a[r];
                a[r] = 0.0;
                tile[r][k] = static_cast<float>(run[r]);
            }
        for (int r = 0; r < nrows; ++r) {
            float* o = out + static_cast<std::size_t>(r) * width + x0;
            const float* t = tile[r];
            if (accumulate) {
                for (int k = 0; k < n; ++k) o[k] += t[k];
            } else if (n == kTile) {   // fixed length: plain vector moves (a string copy starts slowly)
                for (int k = 0; k < kTile; ++k) o[k] = t[k];
            } else {
                for (int k = 0; k < n; ++k) o[k] = t[k];
            }
        }
    }
    std::fill(a, a + 2 * kRows, 0.0);
}

}  // namespace caustics::area_coverage
