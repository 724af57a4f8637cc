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

namespace extension_detail {

// Whether any of id[0 .. n) is not -1 (n a multiple of kScan: whole vectors, no early exit inside).
constexpr int kScan = 16;
inline bool any_drawn(const std::int32_t* id, int n) {
    int any = 0;
#pragma omp simd reduction(| : any)
    for (int k = 0; k < n; ++k) any |= id[k] != -1;
    return any != 0;
}

// The first and last texels of a row of W that are not -1 (a = W: none), scanning kScan texels at a
// time: the rows' ends are mostly empty (on the bunny scene 419k of the 590k texels are extended), and,
// one texel at a time, the scans took a third of the extension's time.
inline void drawn_range(const std::int32_t* id, int W, int& a, int& b) {
    a = 0;
    while (a + kScan <= W && !any_drawn(id + a, kScan)) a += kScan;
    while (a < W && id[a] == -1) ++a;
    if (a == W) return;
    b = W - 1;
    while (b + 1 - kScan > a && !any_drawn(id + b + 1 - kScan, kScan)) b -= kScan;
    while (id[b] == -1) --b;
}

// Texels k = lo .. hi of a line (index(k)) extrapolated from the edge texel at k = e, t = |k - e| texels
// out, away from the texel `inner` next to it: position and depth edge + t (edge - inner), id kExtended.
// The differences are taken once per line (the same values as per texel).
template <class Index>
inline void fill_line(GBuffer& g, int lo, int hi, int e, std::size_t edge, std::size_t inner, Index index) {
    const glm::vec3 pe = g.position[edge], pd = g.position[edge] - g.position[inner];
    const float de = g.depth[edge], dd = g.depth[edge] - g.depth[inner];
    const bool normals = !g.normal.empty();
    const glm::vec3 ne = normals ? g.normal[edge] : glm::vec3(0.0f);
    for (int k = lo; k <= hi; ++k) {
        const std::size_t dst = index(k);
        const float t = static_cast<float>(k < e ? e - k : k - e);
        g.position[dst] = pe + t * pd;
        g.depth[dst] = de + t * dd;
        if (normals) g.normal[dst] = ne;
        g.id[dst] = kExtended;
    }
}

}  // namespace extension_detail

// Extends the stored surfaces by up to `texels` texels beyond their outermost texels in each row, then
// in each column (linear extrapolation of position and depth from the two outermost covered texels):
// estimates near a receiver's edge then step over the edge instead of hitting the null value. Holes
// between receivers are left empty. The new texels get id kExtended. Not in the paper (where such
// splats are lost, Sec. III.D); extend=0 restores that behaviour.
inline void extend_positions(GBuffer& g, int texels) {
    if (texels <= 0) return;
    using namespace extension_detail;
    const int W = g.width, H = g.height;
    // Extends line l (len texels, index(l, k)) whose outermost covered texels are a <= b.
    auto extend_line = [&](int len, int a, int b, auto index) {
        if (a < 0) return;
        if (a > 0) fill_line(g, std::max(0, a - texels), a - 1, a, index(a), index(a + 1 <= b ? a + 1 : a), index);
        if (b < len - 1) fill_line(g, b + 1, std::min(len - 1, b + texels), b, index(b), index(b - 1 >= a ? b - 1 : b), index);
    };
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 16), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end(); ++y) {
            int a = 0, b = 0;
            drawn_range(&g.id[g.index(0, y)], W, a, b);
            if (a == W) continue;
            const std::size_t row = g.index(0, y);
            extend_line(W, a, b, [row](int k) { return row + static_cast<std::size_t>(k); });
        }
    });
    // Columns: outermost covered rows per column, for blocks of columns, from row-major sweeps down from
    // the top and up from the bottom that stop once every column of the block has found its row. A row
    // none of whose texels in the block is drawn is passed over in whole vectors.
    constexpr int kBlock = 64;
    tbb::parallel_for(tbb::blocked_range<int>(0, (W + kBlock - 1) / kBlock, 1), [&](const tbb::blocked_range<int>& r) {
        int first[kBlock], last[kBlock];
        for (int blk = r.begin(); blk != r.end(); ++blk) {
            const int x0 = blk * kBlock, x1 = std::min(W, x0 + kBlock);
            const bool whole = x1 - x0 == kBlock;
            std::fill(first, first + kBlock, -1);
            std::fill(last, last + kBlock, -1);
            int missing = x1 - x0;
            for (int y = 0; y < H && missing > 0; ++y) {
                const std::int32_t* id = &g.id[g.index(0, y)];
                if (whole && !any_drawn(id + x0, kBlock)) continue;
                for (int x = x0; x < x1; ++x)
                    if (first[x - x0] < 0 && id[x] != -1) first[x - x0] = y, --missing;
            }
            missing = static_cast<int>(std::count_if(first, first + (x1 - x0), [](int f) { return f >= 0; }));
            for (int y = H - 1; y >= 0 && missing > 0; --y) {
                const std::int32_t* id = &g.id[g.index(0, y)];
                if (whole && !any_drawn(id + x0, kBlock)) continue;
                for (int x = x0; x < x1; ++x)
                    if (last[x - x0] < 0 && first[x - x0] >= 0 && id[x] != -1) last[x - x0] = y, --missing;
            }
            // Each column's fills: the column's texels are a stride of a whole row apart, but each texel is
            // written once, from its own column's edge, so the order does not change a value.
            for (int x = x0; x < x1; ++x) {
                const int a = first[x - x0], b = last[x - x0];
                if (a < 0) continue;
                extend_line(H, a, b, [&g, x](int k) { return g.index(x, k); });
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
