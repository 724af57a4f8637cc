// The ray-beam integral of many rays against one beam in AVX2 lanes (Sec. 5.1, 5.2; see ray_beam.hpp): the
// edge polynomials and their roots for four rays at a time, and the quadrature nodes four at a time as the
// rays' inside intervals produce them. The steps and their order are RayBeam::radiance's, the exponential
// is the same scalar call, and no multiply and add are fused, so each ray's value equals the one-ray form's
// to the bit (tests/test_adaptive_beams_ray_beam.cpp). Where the CPU lacks AVX2 the rays take the one-ray
// form.
#include "ray_beam.hpp"

#include "gauss_legendre.hpp"

#include <cmath>

#include <caustics/util/target_clones.hpp>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define CAUSTICS_RAY_LANES 1
#endif

namespace caustics::adaptive_beams {

#ifdef CAUSTICS_RAY_LANES
namespace {

#define CAUSTICS_LANES __attribute__((target("avx2")))

// std::max(a, b) = a < b ? b : a and std::min(a, b) = b < a ? b : a, NaNs and signed zeros included:
// _mm256_max_pd(x, y) is x > y ? x : y.
CAUSTICS_LANES inline __m256d max_of(__m256d a, __m256d b) { return _mm256_max_pd(b, a); }
CAUSTICS_LANES inline __m256d min_of(__m256d a, __m256d b) { return _mm256_min_pd(b, a); }
CAUSTICS_LANES inline __m256d abs_of(__m256d v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }
CAUSTICS_LANES inline __m256d select(__m256d mask, __m256d yes, __m256d no) { return _mm256_blendv_pd(no, yes, mask); }
CAUSTICS_LANES inline __m256d lt(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_LT_OQ); }
CAUSTICS_LANES inline __m256d le(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_LE_OQ); }
CAUSTICS_LANES inline __m256d gt(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
CAUSTICS_LANES inline __m256d ge(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_GE_OQ); }
CAUSTICS_LANES inline __m256d ne(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_NEQ_UQ); }
CAUSTICS_LANES inline __m256d eq(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_EQ_OQ); }
CAUSTICS_LANES inline __m256d splat(double v) { return _mm256_set1_pd(v); }
CAUSTICS_LANES inline __m256d negate(__m256d v) { return _mm256_xor_pd(v, _mm256_set1_pd(-0.0)); }

// Both roots of a + b s + c s^2 as real_roots (beam.hpp) finds them, NaN where it finds none.
CAUSTICS_LANES inline void roots_lanes(__m256d a, __m256d b, __m256d c, __m256d& r0, __m256d& r1) {
    const __m256d nan = splat(std::nan("")), zero = _mm256_setzero_pd();
    const __m256d scale = max_of(max_of(abs_of(a), abs_of(b)), abs_of(c));
    const __m256d none = eq(scale, zero);
    const __m256d linear = le(abs_of(c), _mm256_mul_pd(splat(1e-12), scale));
    // The linear case (a vanishing quadratic coefficient) is rare: its division only where a lane has it.
    const __m256d lin = _mm256_movemask_pd(linear) == 0
                            ? nan
                            : select(gt(abs_of(b), _mm256_mul_pd(splat(1e-14), scale)), _mm256_div_pd(negate(a), b), nan);
    const __m256d disc = _mm256_sub_pd(_mm256_mul_pd(b, b), _mm256_mul_pd(_mm256_mul_pd(splat(4.0), a), c));
    const __m256d real = ge(disc, zero);
    const __m256d root = _mm256_sqrt_pd(max_of(disc, zero));
    const __m256d sign = _mm256_and_pd(b, splat(-0.0));
    const __m256d q = _mm256_mul_pd(splat(-0.5), _mm256_add_pd(b, _mm256_or_pd(root, sign)));
    const bool any_real = _mm256_movemask_pd(real) != 0;   // else no lane has a root: skip the divisions
    const __m256d q0 = any_real ? select(real, _mm256_div_pd(q, c), nan) : nan;
    const __m256d q1 = any_real ? select(_mm256_and_pd(real, ne(q, zero)), _mm256_div_pd(a, q), nan) : nan;
    r0 = select(none, nan, select(linear, lin, q0));
    r1 = select(_mm256_or_pd(none, linear), nan, q1);
}

}  // namespace

CAUSTICS_LANES void RayBeam::radiance_avx2(const glm::dvec3* w, const double* s_max, int n, int samples,
                                            BeamCounters& counters, double s_min, double* out) const {
    const GaussRule& gq = gauss_rule(samples);
    const __m256d zero = _mm256_setzero_pd();
    // The pending quadrature nodes (up to four), with their rays' data.
    alignas(32) double ps[4], pwt[4], pyw[4], pwx[4], pwy[4], pwz[4], pf1[3][4], pf2[3][4];
    int pray[4], pending = 0;
    const __m256d vys[3] = {splat(ys_[0]), splat(ys_[1]), splat(ys_[2])}, vye[3] = {splat(ye_[0]), splat(ye_[1]), splat(ye_[2])};
    const __m256d vw[3] = {splat(w_[0]), splat(w_[1]), splat(w_[2])};
    auto flush = [&]() CAUSTICS_LANES {
        for (int l = pending; l < 4; ++l) {   // idle lanes: a harmless copy of lane 0, dropped below
            ps[l] = ps[0], pwt[l] = pwt[0], pyw[l] = pyw[0], pwx[l] = pwx[0], pwy[l] = pwy[0], pwz[l] = pwz[0];
            for (int k = 0; k < 3; ++k) pf1[k][l] = pf1[k][0], pf2[k][l] = pf2[k][0];
        }
        const __m256d s = _mm256_load_pd(ps), yw = _mm256_load_pd(pyw);
        const __m256d y = _mm256_add_pd(splat(yo_), _mm256_mul_pd(s, yw));
        __m256d F[3];
        for (int k = 0; k < 3; ++k)
            F[k] = _mm256_add_pd(splat(f0_[k]), _mm256_mul_pd(s, _mm256_add_pd(_mm256_load_pd(pf1[k]), _mm256_mul_pd(s, _mm256_load_pd(pf2[k])))));
        const __m256d a2 = _mm256_add_pd(_mm256_add_pd(F[0], F[1]), F[2]);
        const __m256d nonzero = ne(a2, zero);
        const __m256d inv = _mm256_div_pd(splat(1.0), select(nonzero, a2, splat(1.0)));
        const __m256d b0 = _mm256_mul_pd(F[0], inv), b1 = _mm256_mul_pd(F[1], inv);
        const __m256d b2 = _mm256_sub_pd(_mm256_sub_pd(splat(1.0), b0), b1);
        auto mix = [&](const __m256d* v) CAUSTICS_LANES {
            return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(b0, v[0]), _mm256_mul_pd(b1, v[1])), _mm256_mul_pd(b2, v[2]));
        };
        const __m256d ys = mix(vys), ye = mix(vye), weight = mix(vw);
        __m256d dl[3];
        for (int c = 0; c < 3; ++c) {
            const __m256d v[3] = {splat(dp_[0][c]), splat(dp_[1][c]), splat(dp_[2][c])};
            dl[c] = mix(v);
        }
        const __m256d len2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dl[0], dl[0]), _mm256_mul_pd(dl[1], dl[1])),
                                           _mm256_mul_pd(dl[2], dl[2]));
        const __m256d stretch = _mm256_sqrt_pd(len2);
        const __m256d tol = _mm256_mul_pd(splat(1e-9), _mm256_add_pd(splat(1.0), abs_of(ys)));
        const __m256d before = lt(y, _mm256_sub_pd(ys, tol)), after = gt(y, ye);
        const __m256d carries = _mm256_andnot_pd(_mm256_or_pd(before, after), _mm256_and_pd(nonzero, gt(stretch, zero)));
        const __m256d a_raw = abs_of(_mm256_mul_pd(splat(0.5), a2));
        const __m256d clamp = lt(a_raw, splat(a_min_));
        const __m256d a = select(clamp, splat(a_min_), a_raw);
        const __m256d path = _mm256_mul_pd(max_of(zero, _mm256_sub_pd(y, ys)), stretch);
        const __m256d dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dl[0], _mm256_load_pd(pwx)), _mm256_mul_pd(dl[1], _mm256_load_pd(pwy))),
                                          _mm256_mul_pd(dl[2], _mm256_load_pd(pwz)));
        const __m256d cosine = _mm256_div_pd(negate(dot), select(gt(stretch, zero), stretch, splat(1.0)));
        const __m256d d = _mm256_sub_pd(splat(hg_a_), _mm256_mul_pd(splat(hg_b_), cosine));
        const __m256d pre = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(_mm256_load_pd(pwt), splat(k_)), weight), stretch);
        const __m256d arg = _mm256_mul_pd(splat(-sigma_t_), _mm256_add_pd(path, s));
        const __m256d den = _mm256_mul_pd(_mm256_mul_pd(a, d), _mm256_sqrt_pd(d));
        alignas(32) double v_pre[4], v_arg[4], v_den[4];
        _mm256_store_pd(v_pre, pre), _mm256_store_pd(v_arg, arg), _mm256_store_pd(v_den, den);
        const int carry_bits = _mm256_movemask_pd(carries), clamp_bits = _mm256_movemask_pd(clamp);
        for (int l = 0; l < pending; ++l) {
            if (!(carry_bits >> l & 1)) continue;
            counters.clamped += clamp_bits >> l & 1;
            out[pray[l]] += v_pre[l] * std::exp(v_arg[l]) / v_den[l];
        }
        pending = 0;
    };

    for (int j0 = 0; j0 < n; j0 += 4) {
        const int lanes = n - j0 < 4 ? n - j0 : 4;
        alignas(32) double wx[4], wy[4], wz[4], smax[4];
        for (int l = 0; l < 4; ++l) {
            const int j = j0 + (l < lanes ? l : 0);
            wx[l] = w[j].x, wy[l] = w[j].y, wz[l] = w[j].z, smax[l] = s_max[j];
        }
        const __m256d vx = _mm256_load_pd(wx), vy = _mm256_load_pd(wy), vz = _mm256_load_pd(wz);
        auto dot3 = [&](const glm::dvec3& c) CAUSTICS_LANES {
            return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, splat(c.x)), _mm256_mul_pd(vy, splat(c.y))),
                                 _mm256_mul_pd(vz, splat(c.z)));
        };
        const __m256d yw = dot3(n_), qx = dot3(e1_), qy = dot3(e2_);
        // The slab [y0, y1] bounds s, or for a ray parallel to it the hull's bounding sphere.
        const __m256d parallel = _mm256_cmp_pd(abs_of(yw), splat(1e-12), _CMP_NGT_UQ);   // !(|yw| > 1e-12), as radiance
        const __m256d sa = _mm256_div_pd(splat(y0_ - yo_), yw), sb = _mm256_div_pd(splat(y1_ - yo_), yw);
        const __m256d vmin = splat(s_min), vmax = _mm256_load_pd(smax);
        const __m256d lo1 = max_of(vmin, min_of(sa, sb)), hi1 = min_of(vmax, max_of(sa, sb));
        const __m256d sc = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(splat(to_centre_.x), vx), _mm256_mul_pd(splat(to_centre_.y), vy)),
                                         _mm256_mul_pd(splat(to_centre_.z), vz));
        const __m256d lo2 = max_of(vmin, _mm256_sub_pd(sc, splat(radius_)));
        const __m256d hi2 = (yo_ < y0_ || yo_ > y1_) ? lo2 : min_of(vmax, _mm256_add_pd(sc, splat(radius_)));
        alignas(32) double lo[4], hi[4], f1[3][4], f2[3][4], roots[8][4], ywv[4];
        _mm256_store_pd(lo, select(parallel, lo2, lo1));
        _mm256_store_pd(hi, select(parallel, hi2, hi1));
        _mm256_store_pd(ywv, yw);
        __m256d g1[3], g2[3];
        for (int k = 0; k < 3; ++k) {
            g1[k] = _mm256_add_pd(_mm256_mul_pd(yw, splat(k1_[k])),
                                  _mm256_sub_pd(_mm256_mul_pd(splat(c1_[k].x), qy), _mm256_mul_pd(splat(c1_[k].y), qx)));
            g2[k] = _mm256_mul_pd(yw, _mm256_sub_pd(_mm256_mul_pd(yw, splat(G_[k])),
                                                    _mm256_sub_pd(_mm256_mul_pd(splat(h_[k].x), qy), _mm256_mul_pd(splat(h_[k].y), qx))));
            _mm256_store_pd(f1[k], g1[k]);
            _mm256_store_pd(f2[k], g2[k]);
            __m256d r0, r1;
            roots_lanes(splat(f0_[k]), g1[k], g2[k], r0, r1);
            _mm256_store_pd(roots[2 * k], r0);
            _mm256_store_pd(roots[2 * k + 1], r1);
        }
        if (flipped_) {
            __m256d r0, r1;
            roots_lanes(splat(f0_[0] + f0_[1] + f0_[2]), _mm256_add_pd(_mm256_add_pd(g1[0], g1[1]), g1[2]),
                        _mm256_add_pd(_mm256_add_pd(g2[0], g2[1]), g2[2]), r0, r1);
            _mm256_store_pd(roots[6], r0);
            _mm256_store_pd(roots[7], r1);
        }
        const int nroots = flipped_ ? 8 : 6;
        for (int l = 0; l < lanes; ++l) {
            const int j = j0 + l;
            out[j] = 0.0;
            const double s_lo = lo[l], s_hi = hi[l];
            if (!(s_hi > s_lo)) continue;
            double cand[10];
            int nc = 1;
            cand[0] = s_lo;
            for (int r = 0; r < nroots; ++r) insert_interval_end(roots[r][l], s_lo, s_hi, cand, nc);
            cand[nc++] = s_hi;
            for (int k = 0; k + 1 < nc; ++k) {
                const double a = cand[k], b = cand[k + 1];
                if (!(b > a)) continue;
                const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
                double F[3];
                for (int e = 0; e < 3; ++e) F[e] = f0_[e] + mid * (f1[e][l] + mid * f2[e][l]);
                if (!inside_section(F, F[0] + F[1] + F[2])) continue;
                for (int i = 0; i < gq.n; ++i) {
                    ps[pending] = mid + half * gq.x[i];
                    pwt[pending] = gq.w[i] * half;
                    pyw[pending] = ywv[l], pwx[pending] = wx[l], pwy[pending] = wy[l], pwz[pending] = wz[l];
                    for (int e = 0; e < 3; ++e) pf1[e][pending] = f1[e][l], pf2[e][pending] = f2[e][l];
                    pray[pending] = j;
                    if (++pending == 4) flush();
                }
            }
        }
    }
    if (pending > 0) flush();
}

#undef CAUSTICS_LANES

bool RayBeam::lanes_available() { return cpu_has_avx2(); }

#else

bool RayBeam::lanes_available() { return false; }

#endif

void RayBeam::radiance_lanes(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                             double s_min, double* out) const {
#ifdef CAUSTICS_RAY_LANES
    if (lanes_available()) {
        radiance_avx2(w, s_max, n, samples, counters, s_min, out);
        return;
    }
#endif
    radiance_each(w, s_max, n, samples, counters, s_min, out);
}

void RayBeam::radiance_each(const glm::dvec3* w, const double* s_max, int n, int samples, BeamCounters& counters,
                            double s_min, double* out) const {
    for (int j = 0; j < n; ++j) out[j] = radiance(w[j], s_max[j], samples, counters, s_min);
}

}  // namespace caustics::adaptive_beams
