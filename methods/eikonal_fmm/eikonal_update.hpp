#pragma once
// The local upwind update shared by the fast-marching and sweeping solvers (Sethian 1996; second order
// after Rickett & Fomel 2000). Internal to methods/eikonal_fmm.
#include <cmath>
#include <limits>
#include <utility>

namespace caustics::eikonal::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct AxisTerm {
    double v1;     // nearest upwind neighbour
    double alpha;  // 1 (first order) or 9/4 (second order)
    double b;      // phi_1 or (4 phi_1 - phi_2) / 3
};

// Solves sum_a alpha_a (phi - b_a)^2 = (F h)^2 over the m (<= 3) axes with a usable neighbour,
// dropping the largest neighbours until the root is upwind of every neighbour it uses.
inline double solve_terms(AxisTerm* t, int m, double fh) {
    if (m == 0) return kInf;
    // Sort the (at most three) terms by their nearest neighbour.
    if (m > 1 && t[1].v1 < t[0].v1) std::swap(t[0], t[1]);
    if (m > 2 && t[2].v1 < t[1].v1) {
        std::swap(t[1], t[2]);
        if (t[1].v1 < t[0].v1) std::swap(t[0], t[1]);
    }
    for (int use = m; use >= 2; --use) {
        double A = 0.0, B = 0.0, C = -fh * fh;
        for (int q = 0; q < use; ++q) {
            A += t[q].alpha;
            B += t[q].alpha * t[q].b;
            C += t[q].alpha * t[q].b * t[q].b;
        }
        const double disc = B * B - A * C;
        if (disc < 0.0) continue;
        const double x = (B + std::sqrt(disc)) / A;
        if (x >= t[use - 1].v1) return x;
    }
    return t[0].b + fh / std::sqrt(t[0].alpha);
}

}  // namespace caustics::eikonal::detail
