#pragma once
// Image-space ray / receiver intersection estimators of Shah et al. 2007 (Sec. III.C-D and appendix),
// generic over the lookup so that they can be tested on synthetic positions textures.
//
// A Lookup provides
//   bool fetch(const glm::dvec3& p, glm::dvec3& q) const;   // stored surface point along p's light ray;
//                                                          // false: the paper's null value
//   double depth(const glm::dvec3& p) const;                // light-view depth (side tests)
// and optionally
//   double side(const glm::dvec3& p, const glm::dvec3& q) const;   // the sign of depth(p) - depth(q)
// and the ray is v + d r (r unit). f(d) = |P(d) - fetch(P(d))| (Eq. 3) vanishes at the intersection;
// side(d) = depth(P) - depth(fetch(P)) is its signed counterpart (< 0: in front of the surface seen
// from the light, > 0: behind it), used to keep a bracket [lo, hi] for the bisection safeguard and to
// check the sign of Newton's derivative.
//
//   approx   d_{k+1} = |fetch(v + d_k r) - v| (the paper's estimator, started from d0 = 1 in the paper)
//   newton   d_{k+1} = d_k - g(d_k) / g'(d_k), g = sign(side) f the signed form of the paper's f (the
//            same step away from the surface, smooth through it), g' by a forward difference of step eps
//            (appendix; two lookups per iteration). A derivative that is not positive (it would step
//            away from the surface) or not finite, and a step to d <= 0, fall back to the approx step for
//            that iteration (counted in bad_derivative); nothing divides by zero.
//   oscillation  the last two steps have opposite signs and the second is not at least halved (a
//            two-cycle, Sec. III.D). With safeguard=bisection and a sign change of side() between a
//            point in front and one behind, the estimate switches to bisection on that bracket for the
//            remaining iterations (at least `bisection_steps`).
// Like the shader, the result is the stored surface point looked up at the final estimate; with `normal`
// (and a Lookup whose fetch(p, q, normal) also interpolates the stored normal), that lookup also gives the
// normal there (the exit point's normal of double-surface refraction, without a second lookup).
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace caustics::caustic_mapping {

enum class EstimatorKind { Approx, Newton };
enum class Safeguard { None, Bisection };

struct EstimatorSettings {
    EstimatorKind kind = EstimatorKind::Newton;
    int iterations = 3;
    double d0 = 0.0;
    double eps = 0.01;          // Newton forward-difference step [m]
    Safeguard safeguard = Safeguard::Bisection;
    double tolerance = 1e-4;    // |d_{k+1} - d_k| below this: converged [m]
    int bisection_steps = 8;
};

struct EstimateResult {
    bool hit = false;           // a receiver point was found (false: null value or non-finite)
    glm::dvec3 point{0.0};      // the stored surface point at the final estimate
    double d = 0.0;             // final distance along the ray
    int lookups = 0;
    int iterations = 0;         // updates of d performed
    bool converged = false;
    bool null_value = false;
    bool oscillating = false;
    bool bisected = false;
    int bad_derivative = 0;
    bool nonfinite = false;
};

template <class Lookup>
EstimateResult estimate_intersection(const Lookup& tex, const glm::dvec3& v, const glm::dvec3& r,
                                     const EstimatorSettings& s, double d_start, glm::dvec3* normal = nullptr) {
    EstimateResult out;
    constexpr double inf = std::numeric_limits<double>::infinity();
    double lo = -inf, hi = inf;              // bracket: side(lo) < 0 < side(hi)
    double d = d_start;
    double prev_step = 0.0;
    bool have_prev = false;
    glm::dvec3 q;
    auto eval = [&](double dd, glm::dvec3& qq, double& side, glm::dvec3* nn = nullptr) -> bool {
        const glm::dvec3 p = v + dd * r;
        ++out.lookups;
        bool found;
        if constexpr (requires { tex.fetch(p, qq, nn); }) found = tex.fetch(p, qq, nn);
        else found = tex.fetch(p, qq);
        if (!found) return false;
        if constexpr (requires { tex.side(p, qq); }) side = tex.side(p, qq);
        else side = tex.depth(p) - tex.depth(qq);
        if (side < 0.0) lo = std::max(lo, dd);
        else if (side > 0.0) hi = std::min(hi, dd);
        return true;
    };
    auto fail = [&](bool null) {
        out.null_value = null;
        out.nonfinite = !null;
        out.hit = false;
        out.d = d;
        return out;
    };
    int k = 0;
    for (; k < s.iterations; ++k) {
        if (!std::isfinite(d)) return fail(false);
        double side = 0.0;
        if (!eval(d, q, side)) return fail(true);
        const glm::dvec3 p = v + d * r;
        const double approx_next = glm::length(q - v);
        double next = approx_next;
        if (s.kind == EstimatorKind::Newton) {
            // Newton on the signed distance g(d) = sign(side) f(d): the same iteration as on the paper's
            // f away from the surface (g = -f in front, +f behind), but g is smooth through the root,
            // where f has a kink. A forward difference taken on f across the root (d < d* < d + eps, the
            // estimate once it has converged to within eps) gives a slope of the wrong sign and used to
            // be discarded as a bad derivative on every converged ray; on g it is the true slope.
            auto sgn = [](double x) { return x < 0.0 ? -1.0 : 1.0; };
            const double g = sgn(side) * glm::length(q - p);
            glm::dvec3 q2;
            double side2 = 0.0;
            bool ok = eval(d + s.eps, q2, side2);
            double deriv = 0.0;
            if (ok) {
                deriv = (sgn(side2) * glm::length(q2 - (p + s.eps * r)) - g) / s.eps;
                // The ray passes from in front of the surface (g < 0) to behind it (g > 0): g must rise.
                ok = std::isfinite(deriv) && deriv > 1e-12;
            }
            if (ok) {
                next = d - g / deriv;
                if (!(next > 0.0) || !std::isfinite(next)) ok = false;
            }
            if (!ok) {
                ++out.bad_derivative;
                next = approx_next;
            }
        }
        const double step = next - d;
        ++out.iterations;
        if (have_prev && step * prev_step < 0.0 && std::abs(step) > 0.5 * std::abs(prev_step) &&
            std::abs(step) > s.tolerance) {
            out.oscillating = true;
            if (s.safeguard == Safeguard::Bisection && std::isfinite(lo) && std::isfinite(hi) && lo < hi) {
                out.bisected = true;
                const int steps = std::max(s.iterations - k - 1, s.bisection_steps);
                for (int b = 0; b < steps && hi - lo > s.tolerance; ++b) {
                    const double mid = 0.5 * (lo + hi);
                    glm::dvec3 qm;
                    double sm = 0.0;
                    if (!eval(mid, qm, sm)) break;   // a hole inside the bracket: keep what we have
                    if (sm == 0.0) lo = hi = mid;
                }
                d = 0.5 * (lo + hi);
                out.converged = hi - lo <= s.tolerance;
                k = s.iterations;
                break;
            }
        }
        d = next;
        prev_step = step;
        have_prev = true;
        if (std::abs(step) <= s.tolerance) {
            out.converged = true;
            break;
        }
    }
    if (!std::isfinite(d)) return fail(false);
    double side = 0.0;
    if (!eval(d, q, side, normal)) return fail(true);
    out.hit = true;
    out.point = q;
    out.d = d;
    return out;
}

}  // namespace caustics::caustic_mapping
