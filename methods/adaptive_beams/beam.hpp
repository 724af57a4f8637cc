#pragma once
// One caustic beam (Liktor and Dachsbacher 2011, Sec. 4.3; Ernst et al. 2005): three edge rays
// X_i(y) = v_i + y d_i / (d_i . n) in "beam space", whose y axis n is normal to the planes the beam's
// cross-sections are taken in. At every y the cross-section is the triangle P_0(y) P_1(y) P_2(y) (the
// bilinear side patches cut a plane of constant y in straight lines), so its signed area
//   A(y) = a0 + a1 y + a2 y^2                                                (Sec. 4.3, "Area Function")
// is quadratic in y, and the beam's flux Phi crosses every cross-section: the irradiance perpendicular to
// the local ray direction is Phi |sum b_i d_i'| / |A(y)| (b: barycentric coordinates in the cross-section).
// A changes sign where the beam passes a focus; |A| is clamped from below there, never divided by zero.
//
// The base plane goes through the centroid of the three start points (the specular surface) with n the
// mean edge direction, so that beams leaving a curved surface or a second interface are all expressed
// alike; each edge keeps its own start ys_i and end ye_i (first surface hit, or extrusion limit).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include <caustics/scene/scene.hpp>

namespace caustics::adaptive_beams {

// z of the cross product of two plane vectors: twice the signed area of the triangle they span.
inline double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// The sides of a beam's triangular section: side k joins corners kSidePairs[k] (opposite corner k).
inline constexpr int kSidePairs[3][2] = {{1, 2}, {2, 0}, {0, 1}};

struct EdgeRay {
    glm::dvec3 start{0.0};   // where the light leaves the specular surface
    glm::dvec3 dir{0.0};     // unit direction it travels in
    double length = 0.0;     // distance to the end (surface hit or extrusion limit)
    double weight = 1.0;     // power transmittance up to start (Fresnel, extinction before the segment)
};

struct Beam {
    glm::dvec3 c{0.0}, n{0, 0, 1}, e1{1, 0, 0}, e2{0, 1, 0};   // beam space: origin, axis, in-plane basis
    std::array<glm::dvec2, 3> p{};    // v_i in (e1, e2) at y = 0
    std::array<glm::dvec2, 3> g{};    // in-plane part of d_i' = d_i / (d_i . n)
    std::array<glm::dvec3, 3> dp{};   // d_i' (world), with d_i' . n = 1
    std::array<double, 3> ys{}, ye{}; // per edge: start and end in y
    std::array<double, 3> w{};        // per edge: power transmittance at the start
    double a0 = 0, a1 = 0, a2 = 0;    // signed A(y)
    double a_min = 0;                 // |A| is clamped to at least this (a fraction of the start area)
    double flux = 0;                  // Phi [W] the light sends into the beam
    double y0 = 0, y1 = 0;            // the hull's slab: min ys, max ye
    int medium = -1;                  // object whose inside holds the beam, -1 outside every dielectric
    bool flipped = false;             // A changes sign within [y0, y1]: the beam passes a focus

    double area(double y) const { return a0 + y * (a1 + y * a2); }
    glm::dvec3 point(int i, double y) const { return c + p[i].x * e1 + p[i].y * e2 + y * dp[i]; }
};

enum class BeamStatus { Ok, Degenerate };

// Builds the beam of three edge rays with flux `flux` in `medium`. Degenerate: an edge nearly parallel to
// the cross-section planes (|d_i . n| < 0.05) or a start triangle of (numerically) zero area.
// `clamp_ratio`: |A| >= clamp_ratio |A(start)|.
BeamStatus make_beam(const std::array<EdgeRay, 3>& edges, double flux, int medium, double clamp_ratio, Beam& out);

// Trims the beam where its flux density has fallen below `cutoff` of its start value (extinction
// sigma_t and divergence, Sec. 4.3 "we maximize the beam extrusion using energy approximation"). Returns
// false when nothing is left.
bool cut_by_energy(Beam& b, double sigma_t, double cutoff);

// Whether A(y) reaches |A| <= a_min... (the focus) within [y0, y1] and the smallest |A| / |A(start)| there.
double min_area_ratio(const Beam& b);

struct BeamCounters {
    std::int64_t clamped = 0;   // evaluations where |A| was clamped (at a focus)
};

// Irradiance on a surface point x with unit normal m [W/m^2] (point-in-beam, Sec. 5.3): 0 outside the
// beam or beyond its local end (`end_tol` of the beam's length allowed past it). With one_sided, light
// arriving on the back of m (d . m >= 0) gives 0.
double surface_irradiance(const Beam& b, double sigma_t, const glm::dvec3& x, const glm::dvec3& m, bool one_sided,
                          double end_tol, BeamCounters& counters);

// Radiance [W/(m^2 sr)] scattered once towards the camera at o by the beam along the camera ray
// o + s w, s in [s_min, s_max] (Sec. 5, first equation): the exact interval(s) where the ray is inside the
// beam (roots of the three edge functions and of A, quadratic in s), each integrated by Gauss-Legendre
// with `samples` points (1: the paper's midpoint), with extinction along the light's path in the beam and
// towards the camera, and the Henyey-Greenstein phase function.
// Evaluated through RayBeam (ray_beam.hpp), which hoists what one origin shares.
double volume_radiance(const Beam& b, const MediumCoefficients& medium, const glm::dvec3& o, const glm::dvec3& w,
                       double s_max, int samples, BeamCounters& counters, double s_min = 0.0);

// The same integral point by point: each node's cross-section, barycentric coordinates and local ray
// built afresh. RayBeam's regrouped sums are checked against it (equal to rounding).
double volume_radiance_pointwise(const Beam& b, const MediumCoefficients& medium, const glm::dvec3& o,
                                 const glm::dvec3& w, double s_max, int samples, BeamCounters& counters,
                                 double s_min = 0.0);

// Real roots of a + b s + c s^2 appended to `out` (a linear or constant polynomial where c vanishes
// against the other coefficients).
template <typename T>
inline void real_roots(T a, T b, T c, T* out, int& n) {
    const T scale = std::max({std::abs(a), std::abs(b), std::abs(c)});
    if (scale == T(0)) return;
    if (std::abs(c) <= T(1e-12) * scale) {
        if (std::abs(b) > T(1e-14) * scale) out[n++] = -a / b;
        return;
    }
    const T disc = b * b - T(4) * a * c;
    if (disc < T(0)) return;
    const T q = T(-0.5) * (b + std::copysign(std::sqrt(disc), b));
    out[n++] = q / c;
    if (q != T(0)) out[n++] = a / q;
}

// Whether A(y) changes sign inside the beam's slab (y0, y1): the beam passes a focus there.
inline bool passes_focus(const Beam& b) {
    double r[2];
    int nr = 0;
    real_roots(b.a0, b.a1, b.a2, r, nr);
    for (int k = 0; k < nr; ++k)
        if (r[k] > b.y0 && r[k] < b.y1) return true;
    return false;
}

enum class HullType { Tight, Prism };

// The bounding volume's corners (Sec. 4.3, Fig. 5). Tight: the six corners P_i(y0), P_i(y1), whose
// convex hull holds the beam (the six triangles the paper selects are faces of that hull). Prism (Ernst
// et al. 2005): three planes, each through a base edge and the top corner that leaves the whole beam on
// one side, cut by the slab [y0, y1]; false where no such plane exists or two are parallel (the corners
// are then the tight ones, as the paper falls back).
bool hull_corners(const Beam& b, HullType type, std::array<glm::dvec3, 6>& out);

}  // namespace caustics::adaptive_beams
