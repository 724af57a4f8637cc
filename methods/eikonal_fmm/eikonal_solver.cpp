// Eikonal solvers for Mercier's 3-D caustic texture (Mercier 2013, Sec. 3, Algorithms 1 and 2).
#include "eikonal_solver.hpp"
#include "eikonal_update.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace caustics::eikonal {

glm::dvec3 refract_direction(const glm::dvec3& light, const glm::dvec3& normal, double ior) {
    // t = eta d + (eta cos_i - cos_t) N, eta = 1 / n (air to water: never total internal reflection).
    const double eta = 1.0 / ior, cos_i = std::max(0.0, -glm::dot(light, normal));
    const double cos_t = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)));
    return glm::normalize(eta * light + (eta * cos_i - cos_t) * normal);
}

Refraction refract_at(const HeightField& hf, double x, double y, const glm::dvec3& light, double ior) {
    Refraction r;
    glm::dvec2 g;
    r.point = glm::dvec3(x, y, extended_height(hf, x, y, &g));
    r.normal = glm::normalize(glm::dvec3(-g.x, -g.y, 1.0));
    const double cos_i = -glm::dot(light, r.normal);
    r.lit = cos_i > 0.0;
    r.direction = refract_direction(light, r.normal, ior);
    r.cos_i = std::max(0.0, cos_i);
    r.cos_t = std::max(0.0, -glm::dot(r.direction, r.normal));
    return r;
}

double refracted_foot(const HeightField& hf, const glm::dvec3& p, const glm::dvec3& light, double ior, Refraction& r) {
    // q.xy = p.xy - s t.xy(q) with s = (p.z - h(q)) / t.z(q): start below p and iterate. Each step
    // moves q by at most the horizontal run of the ray over the vertical gap, so it stays local.
    glm::dvec2 q(p.x, p.y);
    r = refract_at(hf, q.x, q.y, light, ior);
    const double tol = 1e-6 * std::min(hf.spacing.x, hf.spacing.y);
    for (int it = 0; it < 12; ++it) {
        const double s = (p.z - r.point.z) / r.direction.z;
        const glm::dvec2 next = glm::dvec2(p.x, p.y) - s * glm::dvec2(r.direction);
        const bool done = glm::length(next - q) < tol;
        q = next;
        r = refract_at(hf, q.x, q.y, light, ior);
        if (done) break;
    }
    return (p.z - r.point.z) / r.direction.z;
}

namespace {

using detail::AxisTerm;
using detail::kInf;

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Upwind update of cell c: solves sum_a alpha_a (phi - b_a)^2 = (F h)^2 over the axes with a usable
// neighbour (Sethian 1996; second order after Rickett & Fomel 2000: one-sided 3-point differences
// (3 phi - 4 phi_1 + phi_2) / 2h where the second upwind neighbour is usable and not larger).
// Drops the largest neighbours until the root is upwind of every neighbour it uses.
template <class Usable>
inline double local_update(const double* phi, const Usable& usable, const VolumeShape& s, int i, int j, int k,
                           std::size_t c, double fh, int order) {
    AxisTerm t[3];
    int m = 0;
    const int coord[3] = {i, j, k};
    const int n[3] = {s.nx, s.ny, s.nz};
    const std::ptrdiff_t stride[3] = {1, s.nx, static_cast<std::ptrdiff_t>(s.nx) * s.ny};
    for (int a = 0; a < 3; ++a) {
        double best = kInf;
        int dir = 0;
        if (coord[a] > 0) {
            const std::size_t nb = c - stride[a];
            if (usable(nb) && phi[nb] < best) { best = phi[nb]; dir = -1; }
        }
        if (coord[a] + 1 < n[a]) {
            const std::size_t nb = c + stride[a];
            if (usable(nb) && phi[nb] < best) { best = phi[nb]; dir = 1; }
        }
        if (dir == 0) continue;
        AxisTerm term{best, 1.0, best};
        if (order >= 2) {
            const int c2 = coord[a] + 2 * dir;
            if (c2 >= 0 && c2 < n[a]) {
                const std::size_t nb2 = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(c) + 2 * dir * stride[a]);
                if (usable(nb2) && phi[nb2] <= best) {
                    term.alpha = 2.25;
                    term.b = (4.0 * best - phi[nb2]) / 3.0;
                }
            }
        }
        t[m++] = term;
    }
    return detail::solve_terms(t, m, fh);
}

template <class F>
inline void for_each_neighbour(const VolumeShape& s, int i, int j, int k, std::size_t c, F&& fn) {
    const std::size_t sy = static_cast<std::size_t>(s.nx), sz = static_cast<std::size_t>(s.nx) * s.ny;
    if (i > 0) fn(i - 1, j, k, c - 1);
    if (i + 1 < s.nx) fn(i + 1, j, k, c + 1);
    if (j > 0) fn(i, j - 1, k, c - sy);
    if (j + 1 < s.ny) fn(i, j + 1, k, c + sy);
    if (k > 0) fn(i, j, k - 1, c - sz);
    if (k + 1 < s.nz) fn(i, j, k + 1, c + sz);
}

}  // namespace

void march(Field& f, int order, Stats& stats) {
    const VolumeShape& s = f.shape;
    const double h = s.spacing;
    const std::size_t count = s.size();
    std::vector<std::uint8_t> accepted(f.frozen);
    double* phi = f.phi.data();
    auto usable = [&](std::size_t n) { return accepted[n] != 0; };
    auto cost = [&](std::size_t c) { return f.cost ? static_cast<double>((*f.cost)[c]) : 1.0; };
    CellHeap heap(count);
    for (std::size_t c = 0; c < count; ++c) {
        if (!accepted[c]) phi[c] = kInf;
    }
    // Trial cells: every non-frozen neighbour of the frozen set.
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) {
                const std::size_t c = s.index(i, j, k);
                if (accepted[c]) continue;
                bool near = false;
                for_each_neighbour(s, i, j, k, c, [&](int, int, int, std::size_t n) { near = near || accepted[n]; });
                if (!near) continue;
                const double v = local_update(phi, usable, s, i, j, k, c, cost(c) * h, order);
                if (v < phi[c]) {
                    phi[c] = v;
                    heap.push_or_decrease(c, v);
                }
            }
    const std::size_t sy = static_cast<std::size_t>(s.nx), sz = sy * static_cast<std::size_t>(s.ny);
    while (!heap.empty()) {
        double key;
        const std::size_t c = heap.pop(key);
        accepted[c] = 1;
        const int k = static_cast<int>(c / sz), j = static_cast<int>((c % sz) / sy), i = static_cast<int>(c % sy);
        if (f.carry) {
            // Extension of a cell quantity along the front (Algorithm 2, first pass): copy it from the
            // accepted neighbour that reached this cell first.
            double best = kInf;
            std::size_t from = c;
            for_each_neighbour(s, i, j, k, c, [&](int, int, int, std::size_t n) {
                if (n != c && accepted[n] && phi[n] < best && n != c) { best = phi[n]; from = n; }
            });
            if (from != c) (*f.carry)[c] = (*f.carry)[from];
        }
        for_each_neighbour(s, i, j, k, c, [&](int ni, int nj, int nk, std::size_t n) {
            if (accepted[n]) return;
            const double v = local_update(phi, usable, s, ni, nj, nk, n, cost(n) * h, order);
            if (v < phi[n]) {
                phi[n] = v;
                heap.push_or_decrease(n, v);
            }
        });
    }
}

namespace {

// Algorithm 2 (Mercier 2013, Sec. 3.2): solve the side faces of the volume first, with propagation
// costs that make the face's solution match an interface extended linearly past the face, and freeze
// them for the 3-D solve. On a face normal to axis a the front moves within the face with slowness
// |grad phi projected on the face| = sqrt(1 - n_a^2) (n: unit interface normal); on a vertical edge
// with slowness |n_z| (the paper's alpha = 1 / cos theta as a speed). With the plane-wave start the
// rays leave the interface along the refracted direction t instead of n: `column_ray` holds n or t.
// Oblique light leaves the volume through its downstream faces: there the light comes from inside,
// which the 3-D solve gets right, so a face (and its edges) is treated only where the mean ray `mean`
// does not leave through it (for the paper's fronts, mean is vertical: every face is treated).
void paper_boundary(Field& f, const std::vector<glm::dvec3>& column_ray, const glm::dvec3& mean, int order,
                    Stats& stats) {
    const VolumeShape& s = f.shape;
    const double h = s.spacing;
    auto normal = [&](int i, int j) { return column_ray[static_cast<std::size_t>(j) * s.nx + i]; };
    constexpr double kLeaving = 1e-3;  // |t_a| below this: rays run along the face (the paper's case)
    // Whether the face normal to `axis` at `side` is one the light leaves through.
    auto outflow = [&](int axis, int side, int n_axis) {
        const double ta = axis == 0 ? mean.x : mean.y;
        if (n_axis == 1) return false;
        return side == 0 ? ta < -kLeaving : ta > kLeaving;
    };
    // 1-D boundaries: the four vertical edges.
    for (int j : {0, s.ny - 1})
        for (int i : {0, s.nx - 1}) {
            if ((i == s.nx - 1 && i != 0 && s.nx == 1) || (j == s.ny - 1 && j != 0 && s.ny == 1)) continue;
            if (outflow(0, i, s.nx) || outflow(1, j, s.ny)) continue;
            const double fz = std::fabs(normal(i, j).z);
            int k = s.nz - 1;
            while (k >= 0 && f.frozen[s.index(i, j, k)]) --k;
            for (; k >= 0; --k) {
                const std::size_t c = s.index(i, j, k);
                if (f.frozen[c]) continue;
                const double above = k + 1 < s.nz ? f.phi[s.index(i, j, k + 1)] : 0.0;
                f.phi[c] = above + h * fz;
                f.frozen[c] = 1;
            }
        }
    // 2-D boundaries: the four side faces, each as a grid that is one cell thick. They share only the
    // vertical edges, frozen above, so they are solved in parallel and written back in a fixed order.
    struct FaceId {
        int axis, side;
    };
    std::vector<FaceId> faces;
    for (int axis = 0; axis < 2; ++axis) {
        const int n_axis = axis == 0 ? s.nx : s.ny;
        for (int side : {0, n_axis - 1})
            if ((side == 0 || n_axis > 1) && !outflow(axis, side, n_axis)) faces.push_back({axis, side});
    }
    std::vector<Field> solved(faces.size());
    std::vector<Stats> face_stats(faces.size());
    // Cell (a, k) of a face (a: its in-plane horizontal index) in the full grid.
    auto full_index = [&](const FaceId& id, int a, int k) {
        return id.axis == 0 ? s.index(id.side, a, k) : s.index(a, id.side, k);
    };
    auto face_index = [](const FaceId& id, const VolumeShape& fs, int a, int k) {
        return id.axis == 0 ? fs.index(0, a, k) : fs.index(a, 0, k);
    };
    tbb::parallel_for(std::size_t{0}, faces.size(), [&](std::size_t q) {
        const FaceId id = faces[q];
        Field& face = solved[q];
        face.shape = s;
        if (id.axis == 0) face.shape.nx = 1; else face.shape.ny = 1;
        const VolumeShape& fs = face.shape;
        face.phi.resize(fs.size());
        face.frozen.resize(fs.size());
        std::vector<float> slowness(fs.size());
        const int n_in = id.axis == 0 ? s.ny : s.nx;
        for (int k = 0; k < s.nz; ++k)
            for (int a = 0; a < n_in; ++a) {
                const std::size_t c = full_index(id, a, k), fc = face_index(id, fs, a, k);
                face.phi[fc] = f.phi[c];
                face.frozen[fc] = f.frozen[c];
                const glm::dvec3 nrm = id.axis == 0 ? normal(id.side, a) : normal(a, id.side);
                const double na = id.axis == 0 ? nrm.x : nrm.y;
                slowness[fc] = static_cast<float>(std::sqrt(std::max(1.0 - na * na, 1e-6)));
            }
        // First pass: extend the interface cells' costs over the face at unit cost.
        face.carry = &slowness;
        march(face, 1, face_stats[q]);
        // Second pass: the face's eikonal solution with those costs.
        face.carry = nullptr;
        face.cost = &slowness;
        march(face, order, face_stats[q]);
        face.cost = nullptr;
    });
    for (std::size_t q = 0; q < faces.size(); ++q) {
        const FaceId id = faces[q];
        const VolumeShape& fs = solved[q].shape;
        const int n_in = id.axis == 0 ? s.ny : s.nx;
        for (int k = 0; k < s.nz; ++k)
            for (int a = 0; a < n_in; ++a) {
                const std::size_t c = full_index(id, a, k);
                f.phi[c] = solved[q].phi[face_index(id, fs, a, k)];
                f.frozen[c] = 1;
            }
        stats.not_converged += face_stats[q].not_converged;
        stats.nonfinite += face_stats[q].nonfinite;
    }
}

}  // namespace

VolumeD solve(const HeightField& hf, const VolumeShape& shape, const Options& options, Stats& stats) {
    Workspace ws;
    solve(hf, shape, options, stats, ws);
    return std::move(ws.phi);
}

const VolumeD& solve(const HeightField& hf, const VolumeShape& shape, const Options& options, Stats& stats,
                     Workspace& ws) {
    auto t0 = std::chrono::steady_clock::now();
    const VolumeShape& s = shape;
    const double h = s.spacing;
    Field f;
    f.shape = s;
    f.phi.swap(ws.phi.data);
    f.frozen.swap(ws.frozen);
    // Every cell is written below: resize only (no fill pass over the whole grid).
    f.phi.resize(s.size());
    f.frozen.resize(s.size());
    // The interface over every column centre, and the slope factor 1 / sqrt(1 + |grad|^2) that turns a
    // vertical gap into a distance along the normal.
    std::vector<double> column_height(static_cast<std::size_t>(s.nx) * s.ny), column_slope(column_height.size());
    std::vector<glm::dvec2> column_gradient(column_height.size());
    tbb::parallel_for(0, s.ny, [&](int j) {
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 p = s.center(i, j, 0);
            const std::size_t col = static_cast<std::size_t>(j) * s.nx + i;
            column_height[col] = extended_height(hf, p.x, p.y, &column_gradient[col]);
            column_slope[col] = 1.0 / std::sqrt(1.0 + glm::dot(column_gradient[col], column_gradient[col]));
        }
    });
    const double band = 2.0 * h;
    const bool triangle = options.init == Init::Triangle;
    const bool plane_wave = options.init_time == InitTime::PlaneWave;
    const glm::dvec3 light = glm::normalize(options.light);
    // The direction rays leave each column's interface point: the normal (paper) or the refracted
    // plane wave; with the plane wave also its arrival time there.
    std::vector<glm::dvec3> column_ray(column_height.size());
    std::vector<double> column_time(column_height.size(), 0.0);
    tbb::parallel_for(0, s.ny, [&](int j) {
        for (int i = 0; i < s.nx; ++i) {
            const std::size_t col = static_cast<std::size_t>(j) * s.nx + i;
            const glm::dvec2 g = column_gradient[col];
            if (plane_wave) {
                const glm::dvec3 p = s.center(i, j, 0);
                const Refraction r = refract_at(hf, p.x, p.y, light, options.ior);
                column_ray[col] = r.direction;
                column_time[col] = plane_wave_time(r.point, light, options.ior);
            } else {
                column_ray[col] = glm::normalize(glm::dvec3(-g.x, -g.y, 1.0));
            }
        }
    });
    // Parallel over rows, not layers: the band of exact distances spans only a few layers.
    tbb::parallel_for(0, s.nz * s.ny, [&](int row) {
        const int k = row / s.ny, j = row % s.ny;
        const double z = s.center(0, 0, k).z;
        const std::size_t first_col = static_cast<std::size_t>(j) * s.nx, first = s.index(0, j, k);
        for (int i = 0; i < s.nx; ++i) {
            const std::size_t col = first_col + i, c = first + i;
            const double gap = z - column_height[col];
            const double estimate = -gap * column_slope[col];  // > 0 below
            if (triangle && std::fabs(estimate) <= band) {
                if (plane_wave) {
                    // The exact arrival time along the refracted ray through the cell centre (extended
                    // above the interface so the Laplacian is smooth across it).
                    Refraction r;
                    const double run = refracted_foot(hf, s.center(i, j, k), light, options.ior, r);
                    f.phi[c] = plane_wave_time(r.point, light, options.ior) + run;
                } else {
                    f.phi[c] = signed_distance_to_interface(hf, s.center(i, j, k));
                }
                f.frozen[c] = 1;
            } else if (gap > 0.0) {
                // Air above the interface: frozen (light enters from the interface only), with an
                // approximate value so the Laplacian is smooth across the interface: the signed
                // distance (paper), or the column's arrival time continued up its refracted ray.
                f.phi[c] = plane_wave ? column_time[col] + gap / column_ray[col].z : estimate;
                f.frozen[c] = 1;
            } else {
                f.phi[c] = kInf;
                f.frozen[c] = 0;
            }
        }
    });
    if (options.init == Init::Vertex) {
        // Mercier 2013, Algorithm 1: each interface vertex sets its cell to its distance to the centre.
        std::vector<std::uint8_t> vertex_set(plane_wave ? s.size() : 0);
        for (int b = 0; b < hf.ny; ++b)
            for (int a = 0; a < hf.nx; ++a) {
                const glm::dvec3 v(hf.origin.x + a * hf.spacing.x, hf.origin.y + b * hf.spacing.y, hf.z(a, b));
                const glm::dvec3 g = (v - s.origin) / h;
                const int i = static_cast<int>(std::floor(g.x)), j = static_cast<int>(std::floor(g.y)),
                          k = static_cast<int>(std::floor(g.z));
                if (i < 0 || j < 0 || k < 0 || i >= s.nx || j >= s.ny || k >= s.nz) continue;
                const std::size_t c = s.index(i, j, k);
                double d = glm::length(v - s.center(i, j, k));
                if (plane_wave) {
                    // The vertex's arrival time continued along its refracted ray to the centre.
                    const Refraction r = refract_at(hf, v.x, v.y, light, options.ior);
                    d = plane_wave_time(v, light, options.ior) + glm::dot(r.direction, s.center(i, j, k) - v);
                    f.phi[c] = vertex_set[c] ? std::min(f.phi[c], d) : d;
                    vertex_set[c] = 1;
                    f.frozen[c] = 1;
                    continue;
                }
                if (!f.frozen[c] || f.phi[c] < 0.0) f.phi[c] = d;  // air estimate replaced by the vertex
                else f.phi[c] = std::min(f.phi[c], d);
                f.frozen[c] = 1;
            }
    }
    stats.init_ms += ms_since(t0);
    if (options.boundary == Boundary::Paper) {
        t0 = std::chrono::steady_clock::now();
        const glm::dvec3 mean = plane_wave ? refract_direction(light, glm::dvec3(0, 0, 1), options.ior) : glm::dvec3(0, 0, -1);
        paper_boundary(f, column_ray, mean, options.order, stats);
        stats.boundary_ms += ms_since(t0);
    }
    t0 = std::chrono::steady_clock::now();
    if (options.solver == Solver::Fmm) march(f, options.order, stats);
    else sweep_down(f, options.order, stats);
    // Cells no front reached (none in a connected grid) take the largest finite value; counted.
    const std::size_t layer = static_cast<std::size_t>(s.nx) * s.ny;
    auto layer_range = [&](int k) { return std::pair(f.phi.begin() + static_cast<std::ptrdiff_t>(k * layer),
                                                     f.phi.begin() + static_cast<std::ptrdiff_t>((k + 1) * layer)); };
    const double largest = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, s.nz), 0.0,
        [&](const tbb::blocked_range<int>& r, double m) {
            for (int k = r.begin(); k < r.end(); ++k) {
                const auto [b, e] = layer_range(k);
                for (auto it = b; it != e; ++it)
                    if (std::isfinite(*it)) m = std::max(m, *it);
            }
            return m;
        },
        [](double a, double b) { return std::max(a, b); });
    std::vector<std::int64_t> unreached(static_cast<std::size_t>(s.nz));
    tbb::parallel_for(0, s.nz, [&](int k) {
        const auto [b, e] = layer_range(k);
        for (auto it = b; it != e; ++it)
            if (!std::isfinite(*it)) {
                ++unreached[static_cast<std::size_t>(k)];
                *it = largest;
            }
    });
    for (std::int64_t n : unreached) stats.not_converged += n;
    stats.solve_ms += ms_since(t0);
    ws.phi.shape = s;
    ws.phi.data.swap(f.phi);
    ws.frozen.swap(f.frozen);
    return ws.phi;
}

}  // namespace caustics::eikonal
