#pragma once
// A positions texture seen from the light (Shah et al. 2007, Sec. III.B): one face (orthographic or
// perspective) or six cube faces, each a G-buffer of world positions, normals and depths. fetch() is the
// shader's tex2D(posTexture, getTC(mVP, p)): p is projected into the light view and the stored surface
// point is read back, bilinearly between four covered texels (nearest when a neighbour is empty);
// false is the paper's "null value" (no geometry seen in that direction, or outside the frustum).
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>
#include <caustics/blocks/gbuffer/light_projection.hpp>

namespace caustics::caustic_mapping {

struct Texel {
    int face = 0;
    double px = 0, py = 0, depth = 0;
};

// id of texels filled by extend_positions (extrapolated, not a real receiver).
constexpr std::int32_t kExtended = -2;

// Extends the stored surfaces by up to `texels` texels beyond their outermost texels in each row, then
// in each column (linear extrapolation of position and depth from the two outermost covered texels):
// estimates near a receiver's edge then step over the edge instead of hitting the null value. Holes
// between receivers are left empty. The new texels get id kExtended. Not in the paper (where such
// splats are lost, Sec. III.D); extend=0 restores that behaviour.
inline void extend_positions(GBuffer& g, int texels) {
    if (texels <= 0) return;
    const int W = g.width, H = g.height;
    auto fill = [&](std::size_t dst, std::size_t edge, std::size_t inner, float t) {
        g.position[dst] = g.position[edge] + t * (g.position[edge] - g.position[inner]);
        g.depth[dst] = g.depth[edge] + t * (g.depth[edge] - g.depth[inner]);
        if (!g.normal.empty()) g.normal[dst] = g.normal[edge];
        g.id[dst] = kExtended;
    };
    // Extends line l (len texels, index(l, k)) whose outermost covered texels are a <= b.
    auto extend_line = [&](int len, int a, int b, auto index) {
        if (a < 0) return;
        const std::size_t ea = index(a), ia = index(a + 1 <= b ? a + 1 : a);
        for (int k = a - 1; k >= std::max(0, a - texels); --k) fill(index(k), ea, ia, static_cast<float>(a - k));
        const std::size_t eb = index(b), ib = index(b - 1 >= a ? b - 1 : b);
        for (int k = b + 1; k <= std::min(len - 1, b + texels); ++k) fill(index(k), eb, ib, static_cast<float>(k - b));
    };
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 16), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end(); ++y) {
            const std::int32_t* id = &g.id[g.index(0, y)];
            int a = 0, b = W - 1;
            while (a < W && id[a] == -1) ++a;
            if (a == W) continue;
            while (id[b] == -1) --b;
            extend_line(W, a, b, [&](int k) { return g.index(k, y); });
        }
    });
    // Columns: outermost covered rows per column, for blocks of columns, from row-major sweeps down from
    // the top and up from the bottom that stop once every column of the block has found its row.
    constexpr int kBlock = 64;
    tbb::parallel_for(tbb::blocked_range<int>(0, (W + kBlock - 1) / kBlock, 1), [&](const tbb::blocked_range<int>& r) {
        int first[kBlock], last[kBlock];
        for (int blk = r.begin(); blk != r.end(); ++blk) {
            const int x0 = blk * kBlock, x1 = std::min(W, x0 + kBlock);
            std::fill(first, first + kBlock, -1);
            std::fill(last, last + kBlock, -1);
            int missing = x1 - x0;
            for (int y = 0; y < H && missing > 0; ++y) {
                const std::int32_t* id = &g.id[g.index(0, y)];
                for (int x = x0; x < x1; ++x)
                    if (first[x - x0] < 0 && id[x] != -1) first[x - x0] = y, --missing;
            }
            missing = static_cast<int>(std::count_if(first, first + (x1 - x0), [](int f) { return f >= 0; }));
            for (int y = H - 1; y >= 0 && missing > 0; --y) {
                const std::int32_t* id = &g.id[g.index(0, y)];
                for (int x = x0; x < x1; ++x)
                    if (last[x - x0] < 0 && first[x - x0] >= 0 && id[x] != -1) last[x - x0] = y, --missing;
            }
            // The fills row by row across the block (each texel is written once, from its own column's
            // edge, so the order does not change a value): row-major stores instead of a stride of a
            // whole row per texel. Only the rows above the lowest first row [top, top_end] and below the
            // highest last row [bottom_start, bottom] can need a fill: after the rows' pass every row
            // that meets a receiver is usually whole, and walking the rows between them cost as much as
            // the fills (a quarter of the G-buffer stage at map 768).
            int top = H, top_end = -1, bottom_start = H, bottom = -1;
            for (int x = x0; x < x1; ++x) {
                const int a = first[x - x0], b = last[x - x0];
                if (a < 0) continue;
                top = std::min(top, std::max(0, a - texels));
                top_end = std::max(top_end, a - 1);
                bottom_start = std::min(bottom_start, b + 1);
                bottom = std::max(bottom, std::min(H - 1, b + texels));
            }
            auto fill_rows = [&](int ya, int yb) {
                for (int y = ya; y <= yb; ++y)
                    for (int x = x0; x < x1; ++x) {
                        const int a = first[x - x0], b = last[x - x0];
                        if (a < 0) continue;
                        if (y < a && y >= a - texels)
                            fill(g.index(x, y), g.index(x, a), g.index(x, a + 1 <= b ? a + 1 : a), static_cast<float>(a - y));
                        else if (y > b && y <= b + texels)
                            fill(g.index(x, y), g.index(x, b), g.index(x, b - 1 >= a ? b - 1 : b), static_cast<float>(y - b));
                    }
            };
            if (top_end + 1 >= bottom_start) {   // the two ranges meet: one pass over their union
                fill_rows(top, bottom);
            } else {
                fill_rows(top, top_end);
                fill_rows(bottom_start, bottom);
            }
        }
    });
}

struct PositionsTexture {
    std::vector<LightProjection> faces;
    std::vector<GBuffer> maps;
    bool cube = false;
    bool bilinear = true;

    bool locate(const glm::dvec3& p, Texel& t) const {
        t.face = cube ? cube_face_of(p - faces[0].eye) : 0;
        const LightProjection& f = faces[static_cast<std::size_t>(t.face)];
        // LightProjection::project with one reciprocal instead of four divisions on the point's path (the
        // scales do not depend on p): the estimator's lookups are dominated by this chain's latency.
        const glm::dvec3 d = p - f.eye;
        t.depth = glm::dot(d, f.forward);
        double x = glm::dot(d, f.right), y = glm::dot(d, f.up);
        if (f.type == ProjectionType::Perspective) {
            if (!(t.depth > f.near_depth)) return false;
            const double inv_depth = 1.0 / t.depth;
            x *= inv_depth;
            y *= inv_depth;
        }
        t.px = (x - f.x0) * f.pixels_per_x();
        t.py = (f.y1 - y) * f.pixels_per_y();
        if (!(t.px >= 0.0 && t.py >= 0.0 && t.px <= f.width && t.py <= f.height)) return false;
        return true;
    }
    // Stored surface point (and normal) along the light ray through p. false: the null value.
    bool fetch(const glm::dvec3& p, glm::dvec3& q, glm::dvec3* normal = nullptr, Texel* where = nullptr) const {
        Texel t;
        if (!locate(p, t)) return false;
        if (where) *where = t;
        const GBuffer& g = maps[static_cast<std::size_t>(t.face)];
        const double fx = t.px - 0.5, fy = t.py - 0.5;
        if (bilinear) {
            const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
            if (x0 >= 0 && y0 >= 0 && x0 + 1 < g.width && y0 + 1 < g.height) {
                const std::size_t i00 = g.index(x0, y0), i10 = i00 + 1, i01 = i00 + g.width, i11 = i01 + 1;
                if (g.id[i00] != -1 && g.id[i10] != -1 && g.id[i01] != -1 && g.id[i11] != -1) {
                    const double ax = fx - x0, ay = fy - y0;
                    const double w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
                    q = w00 * glm::dvec3(g.position[i00]) + w10 * glm::dvec3(g.position[i10]) +
                        w01 * glm::dvec3(g.position[i01]) + w11 * glm::dvec3(g.position[i11]);
                    if (normal) {
                        const glm::dvec3 n = w00 * glm::dvec3(g.normal[i00]) + w10 * glm::dvec3(g.normal[i10]) +
                                             w01 * glm::dvec3(g.normal[i01]) + w11 * glm::dvec3(g.normal[i11]);
                        const double len = glm::length(n);
                        *normal = len > 0.0 ? n / len : glm::dvec3(g.normal[i00]);
                    }
                    return true;
                }
            }
        }
        const int x = std::clamp(static_cast<int>(std::floor(t.px)), 0, g.width - 1);
        const int y = std::clamp(static_cast<int>(std::floor(t.py)), 0, g.height - 1);
        const std::size_t i = g.index(x, y);
        if (g.id[i] == -1) return false;
        q = glm::dvec3(g.position[i]);
        if (normal) *normal = glm::dvec3(g.normal[i]);
        return true;
    }
    // Light-view depth of p (in the face that holds it): the sign of depth(p) - depth(fetch(p)) says on
    // which side of the stored surface p lies (> 0: behind it, seen from the light).
    // Every face shares the light's eye and a cube map is perspective, so the radial distance needs no face.
    double depth(const glm::dvec3& p) const {
        const LightProjection& f = faces[0];
        return f.type == ProjectionType::Perspective ? glm::length(p - f.eye) : glm::dot(p - f.eye, f.forward);
    }
    // A value with the sign of depth(p) - depth(q), which is all the estimator uses of it: in perspective
    // the difference of squared radial distances (no square roots).
    double side(const glm::dvec3& p, const glm::dvec3& q) const {
        const LightProjection& f = faces[0];
        if (f.type != ProjectionType::Perspective) return depth(p) - depth(q);
        const glm::dvec3 dp = p - f.eye, dq = q - f.eye;
        return glm::dot(dp, dp) - glm::dot(dq, dq);
    }
};

}  // namespace caustics::caustic_mapping
