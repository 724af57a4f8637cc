// Scan conversion of beam hulls into the camera (Sec. 4.3, 5.1). See hull_raster.hpp.
#include "hull_raster.hpp"

#include <algorithm>
#include <cmath>

namespace caustics::adaptive_beams {
namespace {

double cross2d(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain: the convex hull of `pts`, counter-clockwise.
std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> pts) {
    std::sort(pts.begin(), pts.end(), [](const glm::dvec2& a, const glm::dvec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    if (pts.size() < 3) return pts;
    std::vector<glm::dvec2> h(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross2d(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
        h[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && cross2d(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
        h[k++] = pts[i - 1];
    }
    h.resize(k - 1);
    return h;
}

// A pixel index from a bound that may be far outside the image (or +-1e300 for an empty polygon): clamped
// to [-1, n] before the cast, which is undefined for values an int cannot hold.
int to_index(double v, int n) {
    if (!(v > -1.0)) return -1;
    return v > n ? n : static_cast<int>(v);
}

// Projects the hull's corners, first clipping their convex hull by the near plane: the part in front is
// the hull of the corners in front and of the crossings of every pair of corners with the plane.
Footprint footprint(const std::array<glm::dvec3, 6>& corners, const CameraModel& cam, int height, bool& clipped) {
    constexpr double kNear = 1e-4;
    double z[6];
    std::vector<glm::dvec3> front;
    for (int i = 0; i < 6; ++i) {
        z[i] = glm::dot(corners[i] - cam.position, cam.forward);
        if (z[i] > kNear) front.push_back(corners[i]);
    }
    clipped = front.size() < 6;
    Footprint f;
    if (front.empty()) return f;
    if (clipped)
        for (int i = 0; i < 6; ++i)
            for (int j = i + 1; j < 6; ++j)
                if ((z[i] > kNear) != (z[j] > kNear)) {
                    const double t = (kNear - z[i]) / (z[j] - z[i]);
                    front.push_back(corners[i] + t * (corners[j] - corners[i]));
                }
    std::vector<glm::dvec2> pts;
    for (const glm::dvec3& p : front) {
        double px = 0.0, py = 0.0;
        if (cam.project(p, px, py)) pts.push_back({px, py});
    }
    f.poly = convex_hull(pts);
    double lo = 1e300, hi = -1e300;
    for (const glm::dvec2& p : f.poly) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    f.y_lo = to_index(std::max(0.0, std::ceil(lo - 0.5)), height);
    f.y_hi = to_index(std::min(height - 1.0, std::floor(hi - 0.5)), height);
    f.box_lo = to_index(std::max(0.0, std::floor(lo)), height);
    f.box_hi = to_index(std::min(height - 1.0, std::ceil(hi) - 1.0), height);
    return f;
}

// The polygon's x extent on the line y = yc: [lo, hi], empty when lo > hi.
void extent_at(const Footprint& f, double yc, double& lo, double& hi) {
    const std::size_t n = f.poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = f.poly[i], b = f.poly[(i + 1) % n];
        if ((a.y <= yc && b.y >= yc) || (b.y <= yc && a.y >= yc)) {
            if (a.y == b.y) {
                lo = std::min({lo, a.x, b.x});
                hi = std::max({hi, a.x, b.x});
            } else {
                const double x = a.x + (yc - a.y) / (b.y - a.y) * (b.x - a.x);
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
        }
    }
}

// Pixel columns of row y: whose centres lie in the polygon, or (box) whose squares it overlaps; [x0, x1].
void row_span(const Footprint& f, int y, int width, bool box, int& x0, int& x1) {
    double lo = 1e300, hi = -1e300;
    if (!box) {
        extent_at(f, y + 0.5, lo, hi);
        x0 = to_index(std::max(0.0, std::ceil(lo - 0.5)), width);
        x1 = to_index(std::min(width - 1.0, std::floor(hi - 0.5)), width);
        return;
    }
    // The convex polygon's part in the strip [y, y + 1]: its corners there and its crossings of both lines.
    extent_at(f, y, lo, hi);
    extent_at(f, y + 1.0, lo, hi);
    for (const glm::dvec2& p : f.poly)
        if (p.y >= y && p.y <= y + 1.0) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
    x0 = to_index(std::max(0.0, std::floor(lo)), width);
    x1 = to_index(std::min(width - 1.0, std::ceil(hi) - 1.0), width);
}

// The six corners of the beam's slab y in [ya, yb]: its edges' points at both ends.
std::array<glm::dvec3, 6> slab_corners(const Beam& b, double ya, double yb) {
    std::array<glm::dvec3, 6> piece;
    for (int i = 0; i < 3; ++i) piece[i] = b.point(i, ya), piece[3 + i] = b.point(i, yb);
    return piece;
}

void add_part(Coverage& cov, Footprint&& f) {
    if (f.box_lo > f.box_hi) return;
    if (f.y_lo <= f.y_hi) {
        const bool first = cov.y_lo > cov.y_hi;
        cov.y_lo = first ? f.y_lo : std::min(cov.y_lo, f.y_lo);
        cov.y_hi = first ? f.y_hi : std::max(cov.y_hi, f.y_hi);
    }
    const bool first = cov.parts == 0;
    cov.box_lo = first ? f.box_lo : std::min(cov.box_lo, f.box_lo);
    cov.box_hi = first ? f.box_hi : std::max(cov.box_hi, f.box_hi);
    cov.part[static_cast<std::size_t>(cov.parts++)] = std::move(f);
}

}  // namespace

Coverage coverage(const Beam& b, HullType hull, const std::array<glm::dvec3, 6>& corners, const CameraModel& cam,
                  int height, bool& clipped) {
    Coverage cov;
    double cut[4] = {b.y0};
    int nc = 1;
    if (hull == HullType::Tight && b.flipped) {
        double r[2];
        int nr = 0;
        real_roots(b.a0, b.a1, b.a2, r, nr);
        std::sort(r, r + nr);
        for (int k = 0; k < nr; ++k)
            if (r[k] > b.y0 && r[k] < b.y1) cut[nc++] = r[k];
    }
    cut[nc++] = b.y1;
    clipped = false;
    for (int k = 0; k + 1 < nc; ++k) {
        const std::array<glm::dvec3, 6> piece = nc > 2 ? slab_corners(b, cut[k], cut[k + 1]) : corners;
        bool c = false;
        Footprint f = footprint(piece, cam, height, c);
        clipped = clipped || c;
        add_part(cov, std::move(f));
    }
    return cov;
}

Coverage slab_coverage(const Beam& b, double ya, double yb, const CameraModel& cam, int height, bool& clipped) {
    Coverage cov;
    add_part(cov, footprint(slab_corners(b, ya, yb), cam, height, clipped));
    return cov;
}

int row_spans(const Coverage& cov, int y, int width, bool box, int (&spans)[3][2]) {
    int n = 0;
    for (int k = 0; k < cov.parts; ++k) {
        const Footprint& f = cov.part[static_cast<std::size_t>(k)];
        if (box ? (y < f.box_lo || y > f.box_hi) : (y < f.y_lo || y > f.y_hi)) continue;
        int x0, x1;
        row_span(f, y, width, box, x0, x1);
        if (x0 > x1) continue;
        int m = n++;
        while (m > 0 && spans[m - 1][0] > x0) spans[m][0] = spans[m - 1][0], spans[m][1] = spans[m - 1][1], --m;
        spans[m][0] = x0, spans[m][1] = x1;
    }
    int kept = 0;
    for (int k = 0; k < n; ++k)
        if (kept > 0 && spans[k][0] <= spans[kept - 1][1] + 1)
            spans[kept - 1][1] = std::max(spans[kept - 1][1], spans[k][1]);
        else
            spans[kept][0] = spans[k][0], spans[kept][1] = spans[k][1], ++kept;
    return kept;
}

}  // namespace caustics::adaptive_beams
