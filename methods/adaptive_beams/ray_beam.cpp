// The ray-beam integral per fragment with the beam's constants hoisted (Sec. 5.1, 5.2; see ray_beam.hpp).
#include "ray_beam.hpp"

#include "gauss_legendre.hpp"

#include <algorithm>
#include <cmath>

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

double RayBeam::radiance(const glm::dvec3& w, double s_max, int samples, BeamCounters& counters, double s_min) const {
    const double yw = glm::dot(w, n_);
    const glm::dvec2 qw{glm::dot(w, e1_), glm::dot(w, e2_)};
    // Bound s by the slab y in [y0, y1] (or, for a ray parallel to it, by the hull's bounding sphere).
    double s_lo = s_min, s_hi = s_max;
    if (std::abs(yw) > 1e-12) {
        double sa = (y0_ - yo_) / yw, sb = (y1_ - yo_) / yw;
        if (sa > sb) std::swap(sa, sb);
        s_lo = std::max(s_lo, sa);
        s_hi = std::min(s_hi, sb);
    } else {
        if (yo_ < y0_ || yo_ > y1_) return 0.0;
        const double sc = glm::dot(to_centre_, w);
        s_lo = std::max(s_lo, sc - radius_);
        s_hi = std::min(s_hi, sc + radius_);
    }
    if (!(s_hi > s_lo)) return 0.0;
    // The edge functions' coefficients for this direction, and 2 A(y(s)) as their sum.
    double f1[3], f2[3];
    for (int k = 0; k < 3; ++k) {
        f1[k] = yw * k1_[k] + cross2(c1_[k], qw);
        f2[k] = yw * (yw * G_[k] - cross2(h_[k], qw));
    }
    double cand[10];
    int nc = 0;
    cand[nc++] = s_lo;
    for (int k = 0; k < 3; ++k) real_roots(f0_[k], f1[k], f2[k], cand, nc);
    // A(y(s)) has a root inside the slab only where the beam passes a focus.
    if (flipped_) real_roots(f0_[0] + f0_[1] + f0_[2], f1[0] + f1[1] + f1[2], f2[0] + f2[1] + f2[2], cand, nc);
    int kept = 1;
    for (int k = 1; k < nc; ++k) insert_interval_end(cand[k], s_lo, s_hi, cand, kept);
    nc = kept;
    cand[nc++] = s_hi;
    const GaussRule& gq = gauss_rule(samples);
    auto edges = [&](double s, double F[3]) {
        for (int k = 0; k < 3; ++k) F[k] = f0_[k] + s * (f1[k] + s * f2[k]);
        return F[0] + F[1] + F[2];
    };
    double total = 0.0;
    for (int k = 0; k + 1 < nc; ++k) {
        const double sa = cand[k], sb = cand[k + 1];
        if (!(sb > sa)) continue;
        const double half = 0.5 * (sb - sa), mid = 0.5 * (sa + sb);
        // The midpoint decides the whole sub-interval: its ends are the roots where the ray crosses a side.
        {
            double F[3];
            const double a2 = edges(mid, F);
            if (!inside_section(F, a2)) continue;
        }
        for (int i = 0; i < gq.n; ++i) {
            const double s = mid + half * gq.x[i];
            const double y = yo_ + s * yw;
            double F[3];
            const double a2 = edges(s, F);
            if (a2 == 0.0) continue;
            const double inv = 1.0 / a2;
            const double b0 = F[0] * inv, b1 = F[1] * inv, b2 = 1.0 - b0 - b1;
            // The local ray through the node (beam.cpp, local_density): its start, direction, weight.
            const double ys = b0 * ys_[0] + b1 * ys_[1] + b2 * ys_[2];
            const double ye = b0 * ye_[0] + b1 * ye_[1] + b2 * ye_[2];
            if (y < ys - 1e-9 * (1.0 + std::abs(ys)) || y > ye) continue;
            const glm::dvec3 dl = b0 * dp_[0] + b1 * dp_[1] + b2 * dp_[2];
            const double stretch = std::sqrt(glm::dot(dl, dl));
            if (!(stretch > 0.0)) continue;   // a degenerate section carries nothing (as the pointwise form)
            const double weight = b0 * w_[0] + b1 * w_[1] + b2 * w_[2];
            double a = std::abs(0.5 * a2);
            if (a < a_min_) {
                a = a_min_;
                ++counters.clamped;
            }
            const double path = std::max(0.0, y - ys) * stretch;
            // sigma_s p_HG(cos) E_perp with E_perp = flux weight stretch / |A| (beam.cpp, local_density) and
            // p_HG = (1 - g^2) / (4 pi d^1.5), d = 1 + g^2 - 2 g cos: one division for the three.
            const double d = hg_a_ - hg_b_ * (-glm::dot(dl, w) / stretch);
            // Extinction along the light's path in the beam and then towards the camera, one exponential.
            total += gq.w[i] * half * k_ * weight * stretch * std::exp(-sigma_t_ * (path + s)) / (a * d * std::sqrt(d));
        }
    }
    return total;
}

}  // namespace caustics::adaptive_beams
