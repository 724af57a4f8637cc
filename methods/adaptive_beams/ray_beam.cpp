// The ray-beam integral per fragment with the beam's constants hoisted (Sec. 5.1, 5.2; see ray_beam.hpp).
#include "ray_beam.hpp"

#include "gauss_legendre.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace caustics::adaptive_beams {

RayBeam::RayBeam(const Beam& b, const glm::dvec3& o, const MediumCoefficients& medium)
    : n_(b.n), e1_(b.e1), e2_(b.e2), y0_(b.y0), y1_(b.y1), dp_{b.dp[0], b.dp[1], b.dp[2]},
      ys_{b.ys[0], b.ys[1], b.ys[2]}, ye_{b.ye[0], b.ye[1], b.ye[2]}, w_{b.w[0], b.w[1], b.w[2]},
      a_min_(b.a_min), flipped_(b.flipped), sigma_t_(medium.extinction()),
      k_(medium.scattering * b.flux * (1.0 - medium.anisotropy * medium.anisotropy) / (4.0 * 3.14159265358979323846)),
      hg_a_(1.0 + medium.anisotropy * medium.anisotropy), hg_b_(2.0 * medium.anisotropy) {
    const glm::dvec3 r0 = o - b.c;
    yo_ = glm::dot(r0, b.n);
    const glm::dvec2 q0{glm::dot(r0, b.e1), glm::dot(r0, b.e2)};
    glm::dvec2 a[3];
    for (int i = 0; i < 3; ++i) a[i] = b.p[i] + yo_ * b.g[i] - q0;
    for (int k = 0; k < 3; ++k) {
        const int j = kSidePairs[k][0], l = kSidePairs[k][1];
        f0_[k] = cross2(a[j], a[l]);
        k1_[k] = cross2(a[j], b.g[l]) + cross2(b.g[j], a[l]);
        c1_[k] = a[l] - a[j];
        G_[k] = cross2(b.g[j], b.g[l]);
        h_[k] = b.g[j] - b.g[l];
    }
    for (int i = 0; i < 3; ++i) centre_ += b.point(i, b.y0) + b.point(i, b.y1);
    centre_ /= 6.0;
    for (int i = 0; i < 3; ++i)
        radius_ = std::max({radius_, glm::length(b.point(i, b.y0) - centre_), glm::length(b.point(i, b.y1) - centre_)});
    to_centre_ = centre_ - o;
}

// In T = double every operation is the one the lanes (ray_beam_lanes.cpp) reproduce to the bit; in T = float
// the beam's constants and the direction are rounded to float once and everything after is float, as
// single-precision lanes would compute it (the sum over the nodes too).
template <typename T>
double RayBeam::radiance_in(const glm::dvec3& w_in, double s_max, int samples, BeamCounters& counters, double s_min) const {
    using V2 = glm::vec<2, T>;
    using V3 = glm::vec<3, T>;
    const V3 w(w_in);
    const T yw = glm::dot(w, V3(n_));
    const V2 qw{glm::dot(w, V3(e1_)), glm::dot(w, V3(e2_))};
    const T yo = T(yo_), y0 = T(y0_), y1 = T(y1_);
    // Bound s by the slab y in [y0, y1] (or, for a ray parallel to it, by the hull's bounding sphere).
    T s_lo = T(s_min), s_hi = T(s_max);
    if (std::abs(yw) > T(1e-12)) {
        T sa = (y0 - yo) / yw, sb = (y1 - yo) / yw;
        if (sa > sb) std::swap(sa, sb);
        s_lo = std::max(s_lo, sa);
        s_hi = std::min(s_hi, sb);
    } else {
        if (yo < y0 || yo > y1) return 0.0;
        const T sc = glm::dot(V3(to_centre_), w);
        s_lo = std::max(s_lo, sc - T(radius_));
        s_hi = std::min(s_hi, sc + T(radius_));
    }
    if (!(s_hi > s_lo)) return 0.0;
    // The edge functions' coefficients for this direction, and 2 A(y(s)) as their sum.
    T f0[3], f1[3], f2[3];
    for (int k = 0; k < 3; ++k) {
        const V2 c1(c1_[k]), h(h_[k]);
        f0[k] = T(f0_[k]);
        f1[k] = yw * T(k1_[k]) + (c1.x * qw.y - c1.y * qw.x);
        f2[k] = yw * (yw * T(G_[k]) - (h.x * qw.y - h.y * qw.x));
    }
    T cand[10];
    int nc = 0;
    cand[nc++] = s_lo;
    for (int k = 0; k < 3; ++k) real_roots(f0[k], f1[k], f2[k], cand, nc);
    // A(y(s)) has a root inside the slab only where the beam passes a focus.
    if (flipped_) real_roots(f0[0] + f0[1] + f0[2], f1[0] + f1[1] + f1[2], f2[0] + f2[1] + f2[2], cand, nc);
    int kept = 1;
    for (int k = 1; k < nc; ++k) insert_interval_end(cand[k], s_lo, s_hi, cand, kept);
    nc = kept;
    cand[nc++] = s_hi;
    const GaussRule& gq = gauss_rule(samples);
    auto edges = [&](T s, T F[3]) {
        for (int k = 0; k < 3; ++k) F[k] = f0[k] + s * (f1[k] + s * f2[k]);
        return F[0] + F[1] + F[2];
    };
    const V3 dp[3] = {V3(dp_[0]), V3(dp_[1]), V3(dp_[2])};
    const T ys_c[3] = {T(ys_[0]), T(ys_[1]), T(ys_[2])}, ye_c[3] = {T(ye_[0]), T(ye_[1]), T(ye_[2])};
    const T w_c[3] = {T(w_[0]), T(w_[1]), T(w_[2])};
    const T a_min = T(a_min_), k_c = T(k_), hg_a = T(hg_a_), hg_b = T(hg_b_), sigma_t = T(sigma_t_);
    // The slack before a local ray's start: 1e-9 relative in double; in float, whose rounding step is 6e-8
    // relative, 8 of its steps (1e-9 would be no slack at all).
    const T start_slack = std::is_same_v<T, double> ? T(1e-9) : T(8) * std::numeric_limits<T>::epsilon();
    T total = T(0);
    for (int k = 0; k + 1 < nc; ++k) {
        const T sa = cand[k], sb = cand[k + 1];
        if (!(sb > sa)) continue;
        const T half = T(0.5) * (sb - sa), mid = T(0.5) * (sa + sb);
        // The midpoint decides the whole sub-interval: its ends are the roots where the ray crosses a side.
        {
            T F[3];
            const T a2 = edges(mid, F);
            if (!inside_section(F, a2)) continue;
        }
        for (int i = 0; i < gq.n; ++i) {
            const T s = mid + half * T(gq.x[i]);
            const T y = yo + s * yw;
            T F[3];
            const T a2 = edges(s, F);
            if (a2 == T(0)) continue;
            const T inv = T(1) / a2;
            const T b0 = F[0] * inv, b1 = F[1] * inv, b2 = T(1) - b0 - b1;
            // The local ray through the node (beam.cpp, local_density): its start, direction, weight.
            const T ys = b0 * ys_c[0] + b1 * ys_c[1] + b2 * ys_c[2];
            const T ye = b0 * ye_c[0] + b1 * ye_c[1] + b2 * ye_c[2];
            if (y < ys - start_slack * (T(1) + std::abs(ys)) || y > ye) continue;
            const V3 dl = b0 * dp[0] + b1 * dp[1] + b2 * dp[2];
            const T stretch = std::sqrt(glm::dot(dl, dl));
            if (!(stretch > T(0))) continue;   // a degenerate section carries nothing (as the pointwise form)
            const T weight = b0 * w_c[0] + b1 * w_c[1] + b2 * w_c[2];
            T a = std::abs(T(0.5) * a2);
            if (a < a_min) {
                a = a_min;
                ++counters.clamped;
            }
            const T path = std::max(T(0), y - ys) * stretch;
            // sigma_s p_HG(cos) E_perp with E_perp = flux weight stretch / |A| (beam.cpp, local_density) and
            // p_HG = (1 - g^2) / (4 pi d^1.5), d = 1 + g^2 - 2 g cos: one division for the three.
            const T d = hg_a - hg_b * (-glm::dot(dl, w) / stretch);
            // Extinction along the light's path in the beam and then towards the camera, one exponential.
            total += T(gq.w[i]) * half * k_c * weight * stretch * std::exp(-sigma_t * (path + s)) / (a * d * std::sqrt(d));
        }
    }
    return static_cast<double>(total);
}

template double RayBeam::radiance_in<double>(const glm::dvec3&, double, int, BeamCounters&, double) const;
template double RayBeam::radiance_in<float>(const glm::dvec3&, double, int, BeamCounters&, double) const;

double RayBeam::radiance(const glm::dvec3& w, double s_max, int samples, BeamCounters& counters, double s_min) const {
    return radiance_in<double>(w, s_max, samples, counters, s_min);
}

void RayBeam::radiance_each_single(const glm::dvec3* w, const double* s_max, int n, int samples,
                                   BeamCounters& counters, double s_min, double* out) const {
    for (int j = 0; j < n; ++j) out[j] = radiance_in<float>(w[j], s_max[j], samples, counters, s_min);
}

}  // namespace caustics::adaptive_beams
