// 3-D scalar grids for volume caustic textures: lookup, Laplacian, fast-marching heap.
#include <caustics/blocks/volume/volume_grid.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <limits>

#include <tbb/parallel_for.h>

namespace caustics {

bool VolumeShape::contains(const glm::dvec3& p) const {
    const glm::dvec3 hi = origin + extent();
    return p.x >= origin.x && p.y >= origin.y && p.z >= origin.z && p.x <= hi.x && p.y <= hi.y &&
           p.z <= hi.z;
}

VolumeShape VolumeShape::padded(int lateral, int vertical) const {
    VolumeShape s = *this;
    s.origin -= spacing * glm::dvec3(lateral, lateral, vertical);
    s.nx += 2 * lateral;
    s.ny += 2 * lateral;
    s.nz += 2 * vertical;
    return s;
}

namespace {

// Continuous index along one axis: lower centre index and weight of the upper one, clamped.
inline void axis_coord(double x, int n, int& i0, int& i1, float& w) {
    const double g = std::clamp(x - 0.5, 0.0, static_cast<double>(n - 1));
    i0 = std::min(static_cast<int>(g), std::max(n - 2, 0));
    i1 = std::min(i0 + 1, n - 1);
    w = static_cast<float>(g - i0);
}

}  // namespace

bool trilinear(const VolumeF& grid, const glm::dvec3& p, float& value) {
    const VolumeShape& s = grid.shape;
    value = 0.0f;
    if (!(s.size() > 0) || !s.contains(p)) return false;
    const glm::dvec3 g = (p - s.origin) / s.spacing;
    int i0, i1, j0, j1, k0, k1;
    float fx, fy, fz;
    axis_coord(g.x, s.nx, i0, i1, fx);
    axis_coord(g.y, s.ny, j0, j1, fy);
    axis_coord(g.z, s.nz, k0, k1, fz);
    auto v = [&](int i, int j, int k) { return grid.data[s.index(i, j, k)]; };
    const float c00 = v(i0, j0, k0) + fx * (v(i1, j0, k0) - v(i0, j0, k0));
    const float c10 = v(i0, j1, k0) + fx * (v(i1, j1, k0) - v(i0, j1, k0));
    const float c01 = v(i0, j0, k1) + fx * (v(i1, j0, k1) - v(i0, j0, k1));
    const float c11 = v(i0, j1, k1) + fx * (v(i1, j1, k1) - v(i0, j1, k1));
    const float c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
    value = c0 + fz * (c1 - c0);
    return true;
}

namespace {

// Second difference along one axis at index a of n, with stride; quadratic extrapolation at faces.
inline double second_difference(const double* p, int a, int n, std::ptrdiff_t stride) {
    if (n < 3) return 0.0;
    if (a == 0) return p[0] - 2.0 * p[stride] + p[2 * stride];
    if (a == n - 1) return p[0] - 2.0 * p[-stride] + p[-2 * stride];
    return p[-stride] - 2.0 * p[0] + p[stride];
}

}  // namespace

void laplacian(const VolumeD& phi, VolumeF& out) {
    const VolumeShape& s = phi.shape;
    out.shape = s;
    out.data.resize(s.size());
    const double inv_h2 = 1.0 / (s.spacing * s.spacing);
    const std::ptrdiff_t sy = s.nx, sz = static_cast<std::ptrdiff_t>(s.nx) * s.ny;
    tbb::parallel_for(0, s.nz, [&](int k) {
        for (int j = 0; j < s.ny; ++j) {
            const std::size_t row = s.index(0, j, k);
            const double* p = phi.data.data() + row;
            float* o = out.data.data() + row;
            const bool interior_yz = j > 0 && j + 1 < s.ny && k > 0 && k + 1 < s.nz;
            for (int i = 0; i < s.nx; ++i) {
                double lap;
                if (interior_yz && i > 0 && i + 1 < s.nx) {
                    lap = p[i - 1] + p[i + 1] + p[i - sy] + p[i + sy] + p[i - sz] + p[i + sz] - 6.0 * p[i];
                } else {
                    lap = second_difference(p + i, i, s.nx, 1) + second_difference(p + i, j, s.ny, sy) +
                          second_difference(p + i, k, s.nz, sz);
                }
                o[i] = static_cast<float>(lap * inv_h2);
            }
        }
    });
}

void CellHeap::push_or_decrease(std::size_t cell, double key) {
    std::uint32_t at = pos_[cell];
    if (at == kAbsent) {
        at = static_cast<std::uint32_t>(heap_.size());
        heap_.push_back({key, static_cast<std::uint32_t>(cell)});
        pos_[cell] = at;
    } else {
        if (!(key < heap_[at].key)) return;
        heap_[at].key = key;
    }
    sift_up(at);
}

std::size_t CellHeap::pop(double& key) {
    const Entry top = heap_.front();
    key = top.key;
    pos_[top.cell] = kAbsent;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) {
        heap_[0] = last;
        pos_[last.cell] = 0;
        sift_down(0);
    }
    return top.cell;
}

void CellHeap::sift_up(std::size_t at) {
    const Entry e = heap_[at];
    while (at > 0) {
        const std::size_t parent = (at - 1) / 2;
        if (!(e.key < heap_[parent].key)) break;
        heap_[at] = heap_[parent];
        pos_[heap_[at].cell] = static_cast<std::uint32_t>(at);
        at = parent;
    }
    heap_[at] = e;
    pos_[e.cell] = static_cast<std::uint32_t>(at);
}

void CellHeap::sift_down(std::size_t at) {
    const Entry e = heap_[at];
    const std::size_t n = heap_.size();
    for (;;) {
        std::size_t child = 2 * at + 1;
        if (child >= n) break;
        if (child + 1 < n && heap_[child + 1].key < heap_[child].key) ++child;
        if (!(heap_[child].key < e.key)) break;
        heap_[at] = heap_[child];
        pos_[heap_[at].cell] = static_cast<std::uint32_t>(at);
        at = child;
    }
    heap_[at] = e;
    pos_[e.cell] = static_cast<std::uint32_t>(at);
}

// ---- Height-field interfaces ----

const ObjectInstance* find_water_interface(const FrameGeometry& frame) {
    for (const ObjectInstance& o : frame.objects)
        if (o.object && o.object->shape == ShapeType::HeightField &&
            o.object->material.type == MaterialType::Dielectric && o.heightfield)
            return &o;
    return nullptr;
}

std::string volume_caustics_unsupported(const Scene& scene) {
    bool water = false;
    for (const Object& o : scene.objects)
        if (o.shape == ShapeType::HeightField && o.material.type == MaterialType::Dielectric) water = true;
    if (!water) return "needs a height-field dielectric interface (water surface); the scene has none";
    if (scene.lights.empty() || scene.lights.front().type != LightType::Directional)
        return "needs a directional light (the caustic volume is propagated from the interface along one "
               "light direction); the scene's first light is not directional";
    if (scene.lights.front().direction.z >= 0.0) return "the directional light does not travel downward onto the interface";
    return {};
}

double extended_height(const HeightField& hf, double x, double y, glm::dvec2* gradient) {
    const glm::dvec2 lo = hf.origin, hi = hf.origin + hf.extent();
    const double xc = std::clamp(x, lo.x, hi.x), yc = std::clamp(y, lo.y, hi.y);
    const glm::dvec2 g = hf.sample_gradient(xc, yc);
    if (gradient) *gradient = g;
    double h = hf.sample_height(xc, yc);
    if (!hf.periodic) h += g.x * (x - xc) + g.y * (y - yc);
    return h;
}

double extended_vertex_height(const HeightField& hf, int a, int b) {
    const int ac = std::clamp(a, 0, hf.nx - 1), bc = std::clamp(b, 0, hf.ny - 1);
    double h = hf.z(ac, bc);
    if (ac != a || bc != b) {
        const glm::vec2 g = hf.grad(ac, bc);
        h += g.x * (a - ac) * hf.spacing.x + g.y * (b - bc) * hf.spacing.y;
    }
    return h;
}

namespace {

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
glm::dvec3 closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

// min(best, squared distance from p to the two triangles of height-field cell (a, b)), extended past
// the edge. The triangles lie in the box over the cell's rectangle between its lowest and highest
// vertex; when that box is no nearer than `best`, the triangles are not visited.
double cell_distance2(const HeightField& hf, int a, int b, const glm::dvec3& p, double best) {
    const double x0 = hf.origin.x + a * hf.spacing.x, y0 = hf.origin.y + b * hf.spacing.y;
    const double x1 = hf.origin.x + (a + 1) * hf.spacing.x, y1 = hf.origin.y + (b + 1) * hf.spacing.y;
    const double dx = std::max(0.0, std::max(x0 - p.x, p.x - x1)), dy = std::max(0.0, std::max(y0 - p.y, p.y - y1));
    const double horizontal = dx * dx + dy * dy;
    if (horizontal >= best) return best;
    double z00, z10, z01, z11;
    if (a >= 0 && b >= 0 && a + 1 < hf.nx && b + 1 < hf.ny) {
        z00 = hf.z(a, b), z10 = hf.z(a + 1, b), z01 = hf.z(a, b + 1), z11 = hf.z(a + 1, b + 1);
    } else {
        z00 = extended_vertex_height(hf, a, b), z10 = extended_vertex_height(hf, a + 1, b);
        z01 = extended_vertex_height(hf, a, b + 1), z11 = extended_vertex_height(hf, a + 1, b + 1);
    }
    const double zlo = std::min(std::min(z00, z10), std::min(z01, z11)), zhi = std::max(std::max(z00, z10), std::max(z01, z11));
    const double dz = std::max(0.0, std::max(zlo - p.z, p.z - zhi));
    if (horizontal + dz * dz >= best) return best;
    const glm::dvec3 v00(x0, y0, z00), v10(x1, y0, z10), v01(x0, y1, z01), v11(x1, y1, z11);
    const glm::dvec3 q1 = closest_on_triangle(p, v00, v10, v11) - p;
    const glm::dvec3 q2 = closest_on_triangle(p, v00, v11, v01) - p;
    return std::min(best, std::min(glm::dot(q1, q1), glm::dot(q2, q2)));
}

// Height-field cell containing coordinate x along one axis (may lie outside the rectangle).
inline int cell_of(double x, double origin, double spacing) { return static_cast<int>(std::floor((x - origin) / spacing)); }

}  // namespace

double signed_distance_to_interface(const HeightField& hf, const glm::dvec3& p) {
    glm::dvec2 g;
    const double gap = p.z - extended_height(hf, p.x, p.y, &g);
    // Foot point: p - S(q) is parallel to the normal (-g, 1), i.e. q = p.xy + (p.z - h(q)) g(q). The
    // foot point lies within |gap| of p horizontally (the vertical gap bounds the distance).
    glm::dvec2 q(p.x, p.y);
    for (int it = 0; it < 8; ++it) {
        glm::dvec2 gq;
        const double hq = extended_height(hf, q.x, q.y, &gq);
        glm::dvec2 step = glm::dvec2(p.x, p.y) + (p.z - hq) * gq - q;
        glm::dvec2 next = q + step;
        const glm::dvec2 off = next - glm::dvec2(p.x, p.y);
        const double len = glm::length(off);
        if (len > std::fabs(gap)) next = glm::dvec2(p.x, p.y) + off * (std::fabs(gap) / len);
        const bool done = glm::length(next - q) < 1e-4 * std::min(hf.spacing.x, hf.spacing.y);
        q = next;
        if (done) break;
    }
    // Exact over the cells within two of the foot point's cell and one of p's own cell. The foot point's
    // cell goes first so the bound skips most of the others without changing the minimum.
    const int qa = cell_of(q.x, hf.origin.x, hf.spacing.x), qb = cell_of(q.y, hf.origin.y, hf.spacing.y);
    const int pa = cell_of(p.x, hf.origin.x, hf.spacing.x), pb = cell_of(p.y, hf.origin.y, hf.spacing.y);
    double d2 = cell_distance2(hf, qa, qb, p, std::numeric_limits<double>::infinity());
    auto visit = [&](int a, int b) { d2 = cell_distance2(hf, a, b, p, d2); };
    for (int b = qb - 2; b <= qb + 2; ++b)
        for (int a = qa - 2; a <= qa + 2; ++a)
            if (a != qa || b != qb) visit(a, b);
    for (int b = pb - 1; b <= pb + 1; ++b)
        for (int a = pa - 1; a <= pa + 1; ++a)
            if (std::abs(a - qa) > 2 || std::abs(b - qb) > 2) visit(a, b);
    const double d = std::min(std::sqrt(d2), std::fabs(gap));
    return gap > 0.0 ? -d : d;
}

namespace {

// Cubic cells of `spacing` over the rectangle [lo, hi], from one cell above the water's highest point
// (hmax) to one below the lowest receiver (zmin), centred on the rectangle.
VolumeShape cells_over(const glm::dvec2& lo, const glm::dvec2& hi, double spacing, double hmax, double zmin) {
    const glm::dvec2 ext = hi - lo;
    VolumeShape s;
    s.spacing = spacing;
    s.nx = std::max(1, static_cast<int>(std::ceil(ext.x / s.spacing - 1e-6)));
    s.ny = std::max(1, static_cast<int>(std::ceil(ext.y / s.spacing - 1e-6)));
    const double top = hmax + s.spacing, bottom = zmin - s.spacing;
    s.nz = std::max(2, static_cast<int>(std::ceil((top - bottom) / s.spacing - 1e-6)));
    const glm::dvec2 mid = 0.5 * (lo + hi);
    s.origin = glm::dvec3(mid.x - 0.5 * s.nx * s.spacing, mid.y - 0.5 * s.ny * s.spacing, top - s.nz * s.spacing);
    return s;
}

}  // namespace

VolumeShape caustic_volume(const FrameGeometry& frame, const ObjectInstance& water, int grid, double margin_fraction) {
    const HeightField& hf = *water.heightfield;
    const glm::dvec2 rect_lo = hf.origin, rect_hi = hf.origin + hf.extent();
    double hmin = 0.0, hmax = 0.0;
    height_range(hf, hmin, hmax);
    glm::dvec2 lo(1e300), hi(-1e300);
    double zmin = 1e300;
    for (const ObjectInstance& o : frame.objects) {
        if (!o.object || o.object->material.type != MaterialType::Diffuse || !o.bounds.valid()) continue;
        const glm::dvec2 blo = glm::max(glm::dvec2(o.bounds.lo), rect_lo);
        const glm::dvec2 bhi = glm::min(glm::dvec2(o.bounds.hi), rect_hi);
        if (blo.x > bhi.x || blo.y > bhi.y || o.bounds.lo.z >= hmax) continue;
        lo = glm::min(lo, blo);
        hi = glm::max(hi, bhi);
        zmin = std::min(zmin, o.bounds.lo.z);
    }
    if (lo.x > hi.x) {
        lo = rect_lo;
        hi = rect_hi;
    }
    glm::dvec2 ext = hi - lo;
    double longest = std::max(ext.x, ext.y);
    if (!(longest > 0.0)) longest = std::max(std::max(hf.extent().x, hf.extent().y), 1e-3);
    if (zmin > 1e299) zmin = hmin - 0.5 * longest;
    lo -= margin_fraction * ext;
    hi += margin_fraction * ext;
    return cells_over(lo, hi, longest * (1.0 + 2.0 * margin_fraction) / std::max(grid, 1), hmax, zmin);
}

VolumeShape caustic_volume_along(const FrameGeometry& frame, const ObjectInstance& water, int grid,
                                 const glm::dvec3& refracted, double spread, double margin_fraction) {
    const HeightField& hf = *water.heightfield;
    const glm::dvec2 rect_lo = hf.origin, rect_hi = hf.origin + hf.extent();
    double hmin = 0.0, hmax = 0.0;
    height_range(hf, hmin, hmax);
    // Horizontal run of a ray per metre of depth.
    const glm::dvec2 run = glm::dvec2(refracted) / std::max(-refracted.z, 1e-6);
    glm::dvec2 lo(1e300), hi(-1e300);
    double zmin = 1e300;
    for (const ObjectInstance& o : frame.objects) {
        if (!o.object || o.object->material.type != MaterialType::Diffuse || !o.bounds.valid()) continue;
        if (o.bounds.lo.z >= hmax) continue;
        const glm::dvec2 shift = run * (hmax - o.bounds.lo.z);
        const glm::dvec2 blo = glm::max(glm::dvec2(o.bounds.lo), rect_lo + glm::min(shift, glm::dvec2(0.0)));
        const glm::dvec2 bhi = glm::min(glm::dvec2(o.bounds.hi), rect_hi + glm::max(shift, glm::dvec2(0.0)));
        if (blo.x > bhi.x || blo.y > bhi.y) continue;
        lo = glm::min(lo, blo);
        hi = glm::max(hi, bhi);
        zmin = std::min(zmin, o.bounds.lo.z);
    }
    if (lo.x > hi.x) return caustic_volume(frame, water, grid, margin_fraction);
    const glm::dvec2 footprint = hi - lo;
    double longest = std::max(footprint.x, footprint.y);
    if (!(longest > 0.0)) longest = std::max(std::max(hf.extent().x, hf.extent().y), 1e-3);
    // Where the receivers' light enters: the footprint moved back up the rays over the depth.
    const double depth = hmax - zmin;
    const glm::dvec2 back = run * depth, widen(spread * depth);
    const glm::dvec2 elo = glm::max(lo - glm::max(back, glm::dvec2(0.0)) - widen, rect_lo);
    const glm::dvec2 ehi = glm::min(hi - glm::min(back, glm::dvec2(0.0)) + widen, rect_hi);
    if (elo.x <= ehi.x && elo.y <= ehi.y) {
        lo = glm::min(lo, elo);
        hi = glm::max(hi, ehi);
    }
    lo -= margin_fraction * footprint;
    hi += margin_fraction * footprint;
    return cells_over(lo, hi, longest * (1.0 + 2.0 * margin_fraction) / std::max(grid, 1), hmax, zmin);
}

}  // namespace caustics
