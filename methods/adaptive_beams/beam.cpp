// Beam space, the area function, point-in-beam and the ray-beam integral (Sec. 4.3, 5.1-5.3).
#include "beam.hpp"

#include "gauss_legendre.hpp"
#include "ray_beam.hpp"

#include <algorithm>
#include <cmath>

namespace caustics::adaptive_beams {
namespace {


// Barycentric coordinates of in-plane point q in the cross-section at y; false when A is exactly zero.
bool barycentric(const Beam& b, const glm::dvec2& q, double y, std::array<double, 3>& bary, double& area) {
    const glm::dvec2 P0 = b.p[0] + y * b.g[0], P1 = b.p[1] + y * b.g[1], P2 = b.p[2] + y * b.g[2];
    area = 0.5 * cross2(P1 - P0, P2 - P0);
    if (area == 0.0) return false;
    bary[0] = 0.5 * cross2(P1 - q, P2 - q) / area;
    bary[1] = 0.5 * cross2(P2 - q, P0 - q) / area;
    bary[2] = 1.0 - bary[0] - bary[1];
    return true;
}

// Perpendicular irradiance at (bary, y) before the surface or phase terms, and the local unit direction;
// 0 outside [ys, ye] (+ tol past the end).
double local_density(const Beam& b, const std::array<double, 3>& bary, double y, double area, double sigma_t,
                     double end_tol, glm::dvec3& dir, BeamCounters& counters) {
    const double ys = bary[0] * b.ys[0] + bary[1] * b.ys[1] + bary[2] * b.ys[2];
    const double ye = bary[0] * b.ye[0] + bary[1] * b.ye[1] + bary[2] * b.ye[2];
    if (y < ys - 1e-9 * (1.0 + std::abs(ys)) || y > ye + end_tol) return 0.0;
    const glm::dvec3 dl = bary[0] * b.dp[0] + bary[1] * b.dp[1] + bary[2] * b.dp[2];
    const double stretch = glm::length(dl);   // distance along the local ray per unit y (1 / cos)
    dir = dl / stretch;
    const double weight = bary[0] * b.w[0] + bary[1] * b.w[1] + bary[2] * b.w[2];
    double a = std::abs(area);
    if (a < b.a_min) {
        a = b.a_min;
        ++counters.clamped;
    }
    const double path = std::max(0.0, y - ys) * stretch;
    return b.flux * weight * std::exp(-sigma_t * path) * stretch / a;
}


}  // namespace

BeamStatus make_beam(const std::array<EdgeRay, 3>& edges, double flux, int medium, double clamp_ratio, Beam& out) {
    Beam b;
    b.flux = flux;
    b.medium = medium;
    glm::dvec3 mean_dir = edges[0].dir + edges[1].dir + edges[2].dir;
    if (!(glm::length(mean_dir) > 1e-9)) return BeamStatus::Degenerate;
    b.n = glm::normalize(mean_dir);
    b.c = (edges[0].start + edges[1].start + edges[2].start) / 3.0;
    // In-plane basis: e1 along the start triangle's first edge projected into the plane, where it exists.
    glm::dvec3 t = edges[1].start - edges[0].start;
    t -= glm::dot(t, b.n) * b.n;
    if (!(glm::length(t) > 1e-300)) t = std::abs(b.n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    t -= glm::dot(t, b.n) * b.n;
    b.e1 = glm::normalize(t);
    b.e2 = glm::cross(b.n, b.e1);
    for (int i = 0; i < 3; ++i) {
        const double cn = glm::dot(edges[i].dir, b.n);
        if (!(cn > 0.05)) return BeamStatus::Degenerate;
        b.dp[i] = edges[i].dir / cn;
        const glm::dvec3 s = edges[i].start - b.c;
        b.ys[i] = glm::dot(s, b.n);
        b.ye[i] = b.ys[i] + edges[i].length * cn;
        const glm::dvec3 v = s - b.ys[i] * b.dp[i];   // the edge's point at y = 0, relative to c
        b.p[i] = {glm::dot(v, b.e1), glm::dot(v, b.e2)};
        b.g[i] = {glm::dot(b.dp[i], b.e1), glm::dot(b.dp[i], b.e2)};
        b.w[i] = edges[i].weight;
    }
    const glm::dvec2 u = b.p[1] - b.p[0], v = b.p[2] - b.p[0], gu = b.g[1] - b.g[0], gv = b.g[2] - b.g[0];
    b.a0 = 0.5 * cross2(u, v);
    b.a1 = 0.5 * (cross2(u, gv) + cross2(gu, v));
    b.a2 = 0.5 * cross2(gu, gv);
    b.y0 = std::min({b.ys[0], b.ys[1], b.ys[2]});
    b.y1 = std::max({b.ye[0], b.ye[1], b.ye[2]});
    // The start area: the cross-section at the mean start (for a start triangle in the base plane, A(0)).
    const double ystart = (b.ys[0] + b.ys[1] + b.ys[2]) / 3.0;
    const double a_start = std::abs(b.area(ystart));
    const double scale = glm::dot(edges[1].start - edges[0].start, edges[1].start - edges[0].start) +
                         glm::dot(edges[2].start - edges[0].start, edges[2].start - edges[0].start);
    if (!(a_start > 1e-10 * scale) || !(a_start > 0.0)) return BeamStatus::Degenerate;
    b.a_min = clamp_ratio * a_start;
    b.flipped = passes_focus(b);
    out = b;
    return BeamStatus::Ok;
}

double min_area_ratio(const Beam& b) {
    const double ystart = (b.ys[0] + b.ys[1] + b.ys[2]) / 3.0;
    const double a_start = std::abs(b.area(ystart));
    double m = std::min(std::abs(b.area(b.y0)), std::abs(b.area(b.y1)));
    if (b.a2 != 0.0) {
        const double yv = -b.a1 / (2.0 * b.a2);
        if (yv > b.y0 && yv < b.y1) m = std::min(m, std::abs(b.area(yv)));
    }
    double r[2];
    int nr = 0;
    real_roots(b.a0, b.a1, b.a2, r, nr);
    for (int k = 0; k < nr; ++k)
        if (r[k] > b.y0 && r[k] < b.y1) m = 0.0;
    return a_start > 0.0 ? m / a_start : 0.0;
}

bool cut_by_energy(Beam& b, double sigma_t, double cutoff) {
    if (!(cutoff > 0.0)) return true;
    const double ystart = (b.ys[0] + b.ys[1] + b.ys[2]) / 3.0;
    const double a_start = std::max(std::abs(b.area(ystart)), b.a_min);
    const double stretch = (glm::length(b.dp[0]) + glm::length(b.dp[1]) + glm::length(b.dp[2])) / 3.0;
    // Relative density at y along the mean edge: extinction times the area ratio (clamped at foci).
    auto density = [&](double y) {
        return std::exp(-sigma_t * std::max(0.0, y - ystart) * stretch) * a_start /
               std::max(std::abs(b.area(y)), b.a_min);
    };
    // The last of kSteps + 1 samples at or above the cutoff, searched from the end: most beams end above it,
    // so one sample usually decides.
    constexpr int kSteps = 32;
    double last_above = b.y0;
    bool any = false;
    for (int k = kSteps; k >= 0 && !any; --k) {
        const double y = b.y0 + (b.y1 - b.y0) * k / kSteps;
        if (density(y) >= cutoff) {
            last_above = y;
            any = true;
        }
    }
    if (!any) return false;
    const double y_cut = std::min(b.y1, last_above + (b.y1 - b.y0) / kSteps);
    if (y_cut >= b.y1) return true;
    for (int i = 0; i < 3; ++i) b.ye[i] = std::min(b.ye[i], y_cut);
    b.y1 = std::max({b.ye[0], b.ye[1], b.ye[2]});
    return b.y1 > b.y0;
}

double surface_irradiance(const Beam& b, double sigma_t, const glm::dvec3& x, const glm::dvec3& m, bool one_sided,
                          double end_tol, BeamCounters& counters) {
    const glm::dvec3 r = x - b.c;
    const double y = glm::dot(r, b.n);
    if (y < b.y0 || y > b.y1 + end_tol * (b.y1 - b.y0)) return 0.0;
    const glm::dvec2 q{glm::dot(r, b.e1), glm::dot(r, b.e2)};
    std::array<double, 3> bary;
    double area = 0.0;
    if (!barycentric(b, q, y, bary, area)) return 0.0;
    if (bary[0] < 0.0 || bary[1] < 0.0 || bary[2] < 0.0) return 0.0;
    glm::dvec3 dir;
    const double e = local_density(b, bary, y, area, sigma_t, end_tol * (b.y1 - b.y0), dir, counters);
    if (e == 0.0) return 0.0;
    const double cm = glm::dot(dir, m);
    if (one_sided && cm >= 0.0) return 0.0;
    return e * std::abs(cm);
}

double volume_radiance(const Beam& b, const MediumCoefficients& medium, const glm::dvec3& o, const glm::dvec3& w,
                       double s_max, int samples, BeamCounters& counters, double s_min) {
    return RayBeam(b, o, medium).radiance(w, s_max, samples, counters, s_min);
}

double volume_radiance_pointwise(const Beam& b, const MediumCoefficients& medium, const glm::dvec3& o,
                                 const glm::dvec3& w, double s_max, int samples, BeamCounters& counters,
                                 double s_min) {
    const glm::dvec3 r0 = o - b.c;
    const double yo = glm::dot(r0, b.n), yw = glm::dot(w, b.n);
    const glm::dvec2 q0{glm::dot(r0, b.e1), glm::dot(r0, b.e2)}, qw{glm::dot(w, b.e1), glm::dot(w, b.e2)};
    // Bound s by the slab y in [y0, y1] (or, for a ray parallel to it, by the hull's bounding sphere).
    double s_lo = s_min, s_hi = s_max;
    if (std::abs(yw) > 1e-12) {
        double sa = (b.y0 - yo) / yw, sb = (b.y1 - yo) / yw;
        if (sa > sb) std::swap(sa, sb);
        s_lo = std::max(s_lo, sa);
        s_hi = std::min(s_hi, sb);
    } else {
        if (yo < b.y0 || yo > b.y1) return 0.0;
        glm::dvec3 centre(0.0);
        for (int i = 0; i < 3; ++i) centre += b.point(i, b.y0) + b.point(i, b.y1);
        centre /= 6.0;
        double rad = 0.0;
        for (int i = 0; i < 3; ++i)
            rad = std::max({rad, glm::length(b.point(i, b.y0) - centre), glm::length(b.point(i, b.y1) - centre)});
        const double sc = glm::dot(centre - o, w);
        s_lo = std::max(s_lo, sc - rad);
        s_hi = std::min(s_hi, sc + rad);
    }
    if (!(s_hi > s_lo)) return 0.0;
    // Edge functions F_k(s) = cross(P_j(s) - q(s), P_l(s) - q(s)), each quadratic in s, and 2 A = sum F_k.
    double cand[16];
    int nc = 0;
    cand[nc++] = s_lo;
    double A0 = 0, A1 = 0, A2 = 0;
    for (const auto& pr : kSidePairs) {
        const int j = pr[0], l = pr[1];
        const glm::dvec2 a = b.p[j] + yo * b.g[j] - q0, bb = yw * b.g[j] - qw;
        const glm::dvec2 c = b.p[l] + yo * b.g[l] - q0, d = yw * b.g[l] - qw;
        const double f0 = cross2(a, c), f1 = cross2(a, d) + cross2(bb, c), f2 = cross2(bb, d);
        real_roots(f0, f1, f2, cand, nc);
        A0 += f0, A1 += f1, A2 += f2;
    }
    real_roots(A0, A1, A2, cand, nc);
    int kept = 1;
    for (int k = 1; k < nc; ++k)
        if (cand[k] > s_lo && cand[k] < s_hi) cand[kept++] = cand[k];
    nc = kept;
    cand[nc++] = s_hi;
    std::sort(cand, cand + nc);
    const GaussRule& gq = gauss_rule(samples);
    const double sigma_t = medium.extinction();
    double total = 0.0;
    for (int k = 0; k + 1 < nc; ++k) {
        const double sa = cand[k], sb = cand[k + 1];
        if (!(sb > sa)) continue;
        // The midpoint decides the whole sub-interval: its ends are the roots where the ray crosses a side.
        {
            const double sm = 0.5 * (sa + sb);
            std::array<double, 3> bary;
            double area = 0.0;
            if (!barycentric(b, q0 + sm * qw, yo + sm * yw, bary, area)) continue;
            if (bary[0] < 0.0 || bary[1] < 0.0 || bary[2] < 0.0) continue;
        }
        const double half = 0.5 * (sb - sa), mid = 0.5 * (sa + sb);
        for (int i = 0; i < gq.n; ++i) {
            const double s = mid + half * gq.x[i];
            const double y = yo + s * yw;
            std::array<double, 3> bary;
            double area = 0.0;
            if (!barycentric(b, q0 + s * qw, y, bary, area)) continue;
            glm::dvec3 dir;
            const double e = local_density(b, bary, y, area, sigma_t, 0.0, dir, counters);
            if (e == 0.0) continue;
            const double phase = henyey_greenstein(glm::dot(dir, -w), medium.anisotropy);
            total += gq.w[i] * half * medium.scattering * phase * e * std::exp(-sigma_t * s);
        }
    }
    return total;
}

bool hull_corners(const Beam& b, HullType type, std::array<glm::dvec3, 6>& out) {
    std::array<glm::dvec3, 3> base, top;
    for (int i = 0; i < 3; ++i) {
        base[i] = b.point(i, b.y0);
        top[i] = b.point(i, b.y1);
        out[i] = base[i];
        out[3 + i] = top[i];
    }
    if (type == HullType::Tight) return true;
    // Ernst et al. 2005: for each base edge (i, j), the plane through it and the top corner that leaves
    // all six corners on the side of the opposite base corner.
    glm::dvec3 normal[3];
    double offset[3];
    double scale = 0.0;
    for (int i = 0; i < 6; ++i) scale = std::max(scale, glm::length(out[i] - out[0]));
    for (int e = 0; e < 3; ++e) {
        const int i = e, j = (e + 1) % 3, k = (e + 2) % 3;
        bool found = false;
        for (int m = 0; m < 3 && !found; ++m) {
            glm::dvec3 nrm = glm::cross(base[j] - base[i], top[m] - base[i]);
            const double len = glm::length(nrm);
            if (!(len > 1e-12 * scale * scale)) continue;
            nrm /= len;
            if (glm::dot(nrm, base[k] - base[i]) > 0.0) nrm = -nrm;   // outward
            bool ok = true;
            for (int q = 0; q < 6 && ok; ++q) ok = glm::dot(nrm, out[q] - base[i]) <= 1e-9 * scale;
            if (ok) {
                normal[e] = nrm;
                offset[e] = glm::dot(nrm, base[i]);
                found = true;
            }
        }
        if (!found) return false;
    }
    // Top corner at base vertex i: planes of edges (i-1, i) and (i, i+1) and the slab's top y = y1.
    const glm::dvec3 ntop = b.n;
    const double otop = glm::dot(b.n, b.c) + b.y1;
    std::array<glm::dvec3, 3> prism_top;
    for (int i = 0; i < 3; ++i) {
        const int ea = (i + 2) % 3, eb = i;
        const glm::dmat3 M = glm::transpose(glm::dmat3(normal[ea], normal[eb], ntop));
        const double det = glm::determinant(M);
        if (!(std::abs(det) > 1e-9)) return false;
        prism_top[i] = glm::inverse(M) * glm::dvec3(offset[ea], offset[eb], otop);
        if (!std::isfinite(prism_top[i].x + prism_top[i].y + prism_top[i].z)) return false;
    }
    for (int i = 0; i < 3; ++i) out[3 + i] = prism_top[i];
    return true;
}

}  // namespace caustics::adaptive_beams
