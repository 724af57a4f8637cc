#pragma once
// The ray-beam integral of Sec. 5.1, 5.2 for the many rays of one camera: every fragment of a beam's hull
// is a ray from the same origin o, so everything in volume_radiance that depends only on the beam and on o
// is computed once per beam (the paper's vertex stage) and each fragment pays only for its direction w.
//
// With q(s) = q0 + s qw the ray's in-plane point and y(s) = yo + s yw its height in beam space, the edge
// function of the side (j, l) is
//   F_k(s) = cross(P_j(y) - q, P_l(y) - q) = f0_k + f1_k s + f2_k s^2,
//   f0_k = cross(a_j, a_l),  a_i = p_i + yo g_i - q0                                   (per beam)
//   f1_k = yw cross(a_j, g_l) + yw cross(g_j, a_l) + cross(a_l - a_j, qw)
//   f2_k = yw^2 cross(g_j, g_l) - yw cross(g_j - g_l, qw)                               (per fragment),
// the barycentric coordinates in the cross-section are F_k / sum F, and sum F = 2 A(y(s)) (Sec. 4.3). So
// the point-in-beam tests and the interpolation at the quadrature nodes are polynomials in s instead of
// a new cross-section per node; the sums are regrouped, so results equal volume_radiance_pointwise to
// rounding (tests/test_adaptive_beams_ray_beam.cpp).
#include <glm/glm.hpp>

#include <caustics/scene/scene.hpp>

#include "beam.hpp"

namespace caustics::adaptive_beams {

// The ends of a ray's sub-intervals in the slab, cand[0] = s_lo, then the crossing roots kept sorted in
// cand[1 .. kept): a root v joins them where it lies strictly inside (s_lo, s_hi) (NaN, no root, never does).
// RayBeam::radiance and its lanes share it; cand may hold v itself at an index >= kept.
template <typename T>
inline void insert_interval_end(T v, T s_lo, T s_hi, T* cand, int& kept) {
    if (!(v > s_lo && v < s_hi)) return;
    int m = kept++;
    while (m > 1 && cand[m - 1] > v) cand[m] = cand[m - 1], --m;
    cand[m] = v;
}

// Whether the point whose edge functions are F (their sum a2 = 2 A) lies in the cross-section: every F_k has
// the sign of A (or is zero).
template <typename T>
inline bool inside_section(const T F[3], T a2) {
    return a2 > T(0) ? (F[0] >= T(0) && F[1] >= T(0) && F[2] >= T(0)) : a2 < T(0) && (F[0] <= T(0) && F[1] <= T(0) && F[2] <= T(0));
}

class RayBeam {
public:
    // The beam seen from o; `medium` is the medium both the beam and the camera are in.
    RayBeam() = default;
    RayBeam(const Beam& b, const glm::dvec3& o, const MediumCoefficients& medium);

    // The radiance volume_radiance(b, medium, o, w, s_max, samples, counters, s_min) returns.
    double radiance(const glm::dvec3& w, double s_max, int samples, BeamCounters& counters, double s_min = 0.0) const;

    // out[j] = radiance(w[j], s_max[j], samples, counters, s_min) for j < n, to the bit: the edge polynomials'
    // roots of four rays and the quadrature nodes four at a time in AVX2 lanes (ray_beam_lanes.cpp), where
    // lanes_available(); elsewhere one ray at a time.
    void radiance_lanes(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                        double s_min, double* out) const;
    static bool lanes_available();
    // The same, one ray at a time (where the CPU lacks AVX2, and for timing comparisons).
    void radiance_each(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                       double s_min, double* out) const;
    // The same with each fragment's arithmetic in single precision (the beam's constants rounded to float,
    // the direction too), one ray at a time: what float lanes would cost in error (volume_precision=float;
    // there are no float lanes, and this path is slower than the double lanes).
    void radiance_each_single(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                              double s_min, double* out) const;

private:
    // radiance's body in the arithmetic T (double: radiance itself; float: radiance_each_single).
    template <typename T>
    double radiance_in(const glm::dvec3& w, double s_max, int samples, BeamCounters& counters, double s_min) const;

    // radiance_lanes' AVX2 body (called only where lanes_available()).
    void radiance_avx2(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                       double s_min, double* out) const;

    glm::dvec3 n_, e1_, e2_;
    double yo_ = 0.0, y0_ = 0.0, y1_ = 0.0;
    double f0_[3]{}, k1_[3]{}, G_[3]{};   // f0_k; f1_k's part over yw; f2_k's part over yw^2
    glm::dvec2 c1_[3]{}, h_[3]{};         // f1_k's part in qw: a_l - a_j; f2_k's: g_j - g_l
    glm::dvec3 centre_{0.0}, to_centre_{0.0};   // bounding sphere of the hull (rays parallel to the slab)
    double radius_ = 0.0;
    glm::dvec3 dp_[3]{};
    double ys_[3]{}, ye_[3]{}, w_[3]{};
    double a_min_ = 0.0;
    bool flipped_ = false;
    double sigma_t_ = 0.0;
    double k_ = 0.0, hg_a_ = 1.0, hg_b_ = 0.0;   // sigma_s flux (1 - g^2) / (4 pi); 1 + g^2; 2 g
};

}  // namespace caustics::adaptive_beams
