// Downward layer-by-layer fast sweeping for Mercier's eikonal texture (Mercier 2013, Sec. 3; an O(N)
// alternative to fast marching). Light enters through the interface and travels down, so once the
// layer above is final a layer depends only on itself: it is solved by Gauss-Seidel sweeps in the four
// horizontal orderings (Zhao 2005) until no cell changes. Only cells whose lateral neighbour changed
// since their last update are revisited, so the sweeps after the first cost little where the front
// moves mostly down.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "eikonal_solver.hpp"
#include "eikonal_update.hpp"

namespace caustics::eikonal {
namespace {

using detail::AxisTerm;
using detail::kInf;

// Upwind term along one axis (coordinate a of n cells, stride st); unreached cells are +inf, so the
// usable neighbours are the finite ones. Same choices as the fast-marching update.
template <int Order>
inline void axis_term(const double* p, int a, int n, std::ptrdiff_t st, AxisTerm* t, int& m) {
    double best = kInf;
    int dir = 0;
    if (a > 0 && p[-st] < best) {
        best = p[-st];
        dir = -1;
    }
    if (a + 1 < n && p[st] < best) {
        best = p[st];
        dir = 1;
    }
    if (dir == 0) return;
    AxisTerm term{best, 1.0, best};
    if constexpr (Order >= 2) {
        const int a2 = a + 2 * dir;
        if (a2 >= 0 && a2 < n) {
            const double second = p[2 * dir * st];
            if (second <= best) {
                term.alpha = 2.25;
                term.b = (4.0 * best - second) / 3.0;
            }
        }
    }
    t[m++] = term;
}

// First order: the nearest upwind neighbour on each axis, sorted (a <= b <= c, +inf when none), and
// the root of sum (x - v)^2 = (F h)^2 over the smallest ones for which it is upwind of all they use.
inline double first_order_update(const double* p, const VolumeShape& s, int i, int j, int k, double fh) {
    const std::ptrdiff_t sy = s.nx, sz = static_cast<std::ptrdiff_t>(s.nx) * s.ny;
    auto nearest = [p](int a, int n, std::ptrdiff_t st) {
        const double lo = a > 0 ? p[-st] : kInf, hi = a + 1 < n ? p[st] : kInf;
        return std::min(lo, hi);
    };
    double a = nearest(i, s.nx, 1), b = nearest(j, s.ny, sy), c = nearest(k, s.nz, sz);
    if (b < a) std::swap(a, b);
    if (c < b) std::swap(b, c);
    if (b < a) std::swap(a, b);
    double x = a + fh;
    if (x > b) {
        const double d = b - a;
        x = 0.5 * (a + b + std::sqrt(2.0 * fh * fh - d * d));
        if (x > c) {
            const double sum = a + b + c;
            const double disc = sum * sum - 3.0 * (a * a + b * b + c * c - fh * fh);
            x = (sum + std::sqrt(std::max(disc, 0.0))) / 3.0;
        }
    }
    return x;
}

template <int Order>
inline double cell_update(const double* p, const VolumeShape& s, int i, int j, int k, double fh) {
    if constexpr (Order == 1) {
        return first_order_update(p, s, i, j, k, fh);
    } else {
        AxisTerm t[3];
        int m = 0;
        const std::ptrdiff_t sy = s.nx, sz = static_cast<std::ptrdiff_t>(s.nx) * s.ny;
        axis_term<Order>(p, i, s.nx, 1, t, m);
        axis_term<Order>(p, j, s.ny, sy, t, m);
        axis_term<Order>(p, k, s.nz, sz, t, m);
        return detail::solve_terms(t, m, fh);
    }
}

// One layer swept until no cell changes by more than tol_. Only cells flagged dirty are visited.
template <int Order>
class LayerSweep {
public:
    explicit LayerSweep(Field& f)
        : f_(f), s_(f.shape), dirty_(static_cast<std::size_t>(f.shape.nx) * f.shape.ny),
          row_dirty_(static_cast<std::size_t>(f.shape.ny)), tol_(1e-7 * f.shape.spacing) {}

    // Sweeps layer k from every cell flagged; false when the pass limit was reached first.
    bool run(int k) {
        constexpr int kMaxPasses = 64;
        const std::size_t sy = static_cast<std::size_t>(s_.nx);
        const std::size_t base = sy * s_.ny * static_cast<std::size_t>(k);
        double* phi = f_.phi.data();
        const std::uint8_t* frozen = f_.frozen.data();
        std::fill(dirty_.begin(), dirty_.end(), std::uint8_t{1});
        std::fill(row_dirty_.begin(), row_dirty_.end(), s_.nx);
        std::size_t pending = dirty_.size();
        auto mark = [&](std::size_t cell, int row) {
            if (dirty_[cell]) return;
            dirty_[cell] = 1;
            ++row_dirty_[static_cast<std::size_t>(row)];
            ++pending;
        };
        for (int pass = 0; pass < kMaxPasses && pending > 0; ++pass) {
            const bool i_up = (pass & 1) == 0, j_up = (pass & 2) == 0;
            for (int jj = 0; jj < s_.ny; ++jj) {
                const int j = j_up ? jj : s_.ny - 1 - jj;
                if (row_dirty_[static_cast<std::size_t>(j)] == 0) continue;
                const std::size_t row = static_cast<std::size_t>(j) * sy;
                for (int ii = 0; ii < s_.nx; ++ii) {
                    const int i = i_up ? ii : s_.nx - 1 - ii;
                    const std::size_t lc = row + static_cast<std::size_t>(i);
                    if (!dirty_[lc]) continue;
                    dirty_[lc] = 0;
                    --row_dirty_[static_cast<std::size_t>(j)];
                    --pending;
                    const std::size_t c = base + lc;
                    if (frozen[c]) continue;
                    const double fh = (f_.cost ? static_cast<double>((*f_.cost)[c]) : 1.0) * s_.spacing;
                    const double v = cell_update<Order>(phi + c, s_, i, j, k, fh);
                    if (!(v < phi[c] - tol_)) continue;
                    phi[c] = v;
                    // Revisit the lateral neighbours this cell is now upwind of (a neighbour's update
                    // ignores values not below its own); second order also reads two cells away.
                    for (int r = 1; r <= Order; ++r) {
                        if (i - r >= 0 && v < phi[c - r]) mark(lc - r, j);
                        if (i + r < s_.nx && v < phi[c + r]) mark(lc + r, j);
                        if (j - r >= 0 && v < phi[c - r * sy]) mark(lc - r * sy, j - r);
                        if (j + r < s_.ny && v < phi[c + r * sy]) mark(lc + r * sy, j + r);
                    }
                }
            }
        }
        return pending == 0;
    }

private:
    Field& f_;
    const VolumeShape& s_;
    std::vector<std::uint8_t> dirty_;
    std::vector<int> row_dirty_;
    double tol_;  // changes below 1e-7 h move the Laplacian by < 1e-7 / h, far below any caustic signal
};

// Layer by layer from the top; each layer's sweeps visit every cell once, then only the cells a change
// reached. Sequential: splitting a layer into strips swept in parallel and then repaired along the
// strip edges cost more than it saved (the repairs spread far into the strips where fronts are tilted).
template <int Order>
void sweep_layers(Field& f, Stats& stats) {
    LayerSweep<Order> sweep(f);
    for (int k = f.shape.nz - 1; k >= 0; --k)
        if (!sweep.run(k)) ++stats.not_converged;
}

}  // namespace

void sweep_down(Field& f, int order, Stats& stats) {
    const std::size_t layer = static_cast<std::size_t>(f.shape.nx) * f.shape.ny;
    tbb::parallel_for(0, f.shape.nz, [&](int k) {
        for (std::size_t c = layer * static_cast<std::size_t>(k), end = c + layer; c < end; ++c)
            if (!f.frozen[c]) f.phi[c] = kInf;
    });
    if (order >= 2) sweep_layers<2>(f, stats);
    else sweep_layers<1>(f, stats);
}

}  // namespace caustics::eikonal
