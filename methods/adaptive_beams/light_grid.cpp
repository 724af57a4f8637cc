// The projected grid, its refinement and the beams of its leaves (Sec. 4.1-4.3, 6).
#include "light_grid.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/frame/ray_offset.hpp>

namespace caustics::adaptive_beams {
namespace {

// Distance from inside box b along the ray to its boundary (0 when the origin is outside).
double exit_distance(const Bounds3& b, const glm::dvec3& o, const glm::dvec3& d) {
    double t = 1e300;
    for (int k = 0; k < 3; ++k) {
        if (d[k] > 0) t = std::min(t, (b.hi[k] - o[k]) / d[k]);
        else if (d[k] < 0) t = std::min(t, (b.lo[k] - o[k]) / d[k]);
    }
    return std::max(0.0, t);
}

// Unpolarised Fresnel power transmittance (Hecht, Optics, eq. 4.42-4.43).
double fresnel_transmittance(double n1, double n2, double cos_i, double cos_t) {
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

// Whether two paths went through the same objects and media (one beam can join them).
bool same_structure(const LightPath& a, const LightPath& b) {
    if (a.status != b.status || a.object != b.object || a.segments != b.segments) return false;
    for (int k = 0; k < a.segments; ++k)
        if (a.medium[k] != b.medium[k]) return false;
    return true;
}

std::uint64_t key(int i, int j) { return (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j); }

}  // namespace

LightGrid::LightGrid(const FrameGeometry& frame, const RayTracer& tracer, const GridSettings& settings)
    : frame_(frame), tracer_(tracer), s_(settings) {
    const Light& light = frame.scene->lights.at(0);
    res_ = s_.grid << (s_.adaptive ? s_.iterations : 0);
    if (light.type == LightType::Directional) {
        proj_ = fit_orthographic(light.direction, frame.specular_bounds, res_, res_, 0.002);
    } else {
        // Clamped to 60 degrees off the axis: a specular object wider than that seen from the light is
        // cut (a cube map would be needed, not modelled).
        fit_perspective(light.position, frame.specular_bounds, res_, res_, proj_, 60.0, 0.002, true);
    }
    extent_ = frame.scene_bounds;
    extent_.extend(frame.scene->camera.position);
    const glm::dvec3 grow = 0.05 * (extent_.hi - extent_.lo) + glm::dvec3(1e-3);
    extent_.lo -= grow;
    extent_.hi += grow;
    offset_ = scene_ray_offset(frame);
}

void LightGrid::ray_at(double i, double j, glm::dvec3& origin, glm::dvec3& dir) const {
    const double px = i, py = j;
    if (proj_.type == ProjectionType::Orthographic) {
        const double tx = proj_.x0 + px / res_ * (proj_.x1 - proj_.x0);
        const double ty = proj_.y1 - py / res_ * (proj_.y1 - proj_.y0);
        origin = proj_.eye + tx * proj_.right + ty * proj_.up;
        dir = proj_.forward;
    } else {
        origin = proj_.eye;
        dir = proj_.ray_direction(px, py);
    }
}

LightPath LightGrid::trace(double i, double j) const {
    const Scene& scene = *frame_.scene;
    LightPath lp;
    glm::dvec3 o, d;
    ray_at(i, j, o, d);
    Hit hit = tracer_.intersect(o, d, offset_);
    if (!hit.valid || !scene.objects[static_cast<std::size_t>(hit.object)].material.is_specular()) return lp;
    lp.object = hit.object;
    lp.depth = hit.t;
    lp.normal = hit.shading_normal;
    double weight = 1.0;
    // A point light's flux is attenuated on its way to the specular surface; a directional light's E0 is
    // taken at the specular surface (it has no distance from the light).
    if (proj_.type == ProjectionType::Perspective) weight *= std::exp(-medium_at(scene, -1).extinction() * hit.t);
    glm::dvec3 dir = d;
    int medium = -1;
    for (int k = 0; k < kMaxSegments; ++k) {
        const Material& m = scene.objects[static_cast<std::size_t>(hit.object)].material;
        const glm::dvec3 nrm = hit.shading_normal;
        if (m.type == MaterialType::Mirror) {
            dir = dir - 2.0 * glm::dot(dir, nrm) * nrm;
        } else {
            const bool entering = glm::dot(dir, nrm) < 0.0;
            const double n1 = entering ? 1.0 : m.ior, n2 = entering ? m.ior : 1.0;
            const glm::dvec3 nn = entering ? nrm : -nrm;
            const double eta = n1 / n2, cos_i = std::min(1.0, -glm::dot(dir, nn));
            const double k2 = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
            if (k2 < 0.0) {
                lp.status = LightPath::TotalInternalReflection;
                lp.segments = k;
                return lp;
            }
            const double cos_t = std::sqrt(k2);
            if (scene.fresnel) weight *= fresnel_transmittance(n1, n2, cos_i, cos_t);
            dir = glm::normalize(eta * dir + (eta * cos_i - cos_t) * nn);
            medium = entering ? hit.object : -1;
        }
        const double limit = exit_distance(extent_, hit.position, dir);
        EdgeRay& e = lp.seg[static_cast<std::size_t>(k)];
        e.start = hit.position;
        e.dir = dir;
        e.weight = weight;
        lp.medium[static_cast<std::size_t>(k)] = medium;
        lp.segments = k + 1;
        const Hit next = tracer_.intersect(hit.position, dir, offset_, limit);
        if (!next.valid) {
            e.length = limit;
            lp.end_object[static_cast<std::size_t>(k)] = -1;
            lp.status = LightPath::Ok;
            return lp;
        }
        e.length = next.t;
        lp.end_object[static_cast<std::size_t>(k)] = next.object;
        weight *= std::exp(-medium_at(scene, medium).extinction() * next.t);
        const Material& nm = scene.objects[static_cast<std::size_t>(next.object)].material;
        if (!nm.is_specular()) {
            lp.status = LightPath::Ok;
            return lp;
        }
        // Two-sided refraction (Sec. 6): the light leaves the dielectric it is in. Any other specular
        // surface ends the path here (higher-order bounces across objects are not followed).
        if (!(medium >= 0 && next.object == medium) || k + 1 == kMaxSegments) {
            lp.status = LightPath::Lost;
            return lp;
        }
        hit = next;
    }
    lp.status = LightPath::Lost;
    return lp;
}

double LightGrid::triangle_flux(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) const {
    const Light& light = frame_.scene->lights.at(0);
    if (proj_.type == ProjectionType::Orthographic) {
        const double sx = (proj_.x1 - proj_.x0) / res_, sy = (proj_.y1 - proj_.y0) / res_;
        const glm::dvec2 u = b - a, v = c - a;
        return light.irradiance * 0.5 * std::abs(u.x * v.y - u.y * v.x) * sx * sy;
    }
    // Solid angle of the spherical triangle (Van Oosterom and Strackee 1983).
    glm::dvec3 o, da, db, dc;
    ray_at(a.x, a.y, o, da);
    ray_at(b.x, b.y, o, db);
    ray_at(c.x, c.y, o, dc);
    const double num = std::abs(glm::dot(da, glm::cross(db, dc)));
    const double den = 1.0 + glm::dot(da, db) + glm::dot(db, dc) + glm::dot(dc, da);
    return light.intensity * 2.0 * std::atan2(num, den);
}

void LatticePoints::reset(int res, std::size_t dense_limit) {
    paths.clear();
    hashed.clear();
    const std::size_t n = static_cast<std::size_t>(res) + 1;
    if (n * n <= dense_limit) {
        side = static_cast<int>(n);
        dense.assign(n * n, -1);
    } else {
        side = 0;
        dense.clear();
    }
}

void LatticePoints::insert(int i, int j, int index) {
    if (side > 0) dense[static_cast<std::size_t>(j) * side + static_cast<std::size_t>(i)] = index;
    else hashed.emplace(key(i, j), index);
}

void TriangleBeams::clear() {
    beams.clear();
    ends.clear();
    end_object.clear();
    tir = energy = degenerate = lost = flipped = 0;
    min_ratio = 1e300;
    max_view_angle = 0.0;
    folded = false;
}

// The beams of three light rays through lattice points c (one beam per segment of their path).
void LightGrid::emit(const glm::dvec2 (&c)[3], const LightPath* const (&p)[3], TriBeams& tb) const {
    const Scene& scene = *frame_.scene;
    const glm::dvec3 camera = scene.camera.position;
    if (!same_structure(*p[0], *p[1]) || !same_structure(*p[0], *p[2])) { ++tb.lost; return; }
    if (p[0]->status == LightPath::Lost) ++tb.lost;
    const double flux = triangle_flux(c[0], c[1], c[2]);
    for (int k = 0; k < p[0]->segments; ++k) {
        const std::array<EdgeRay, 3> edges{p[0]->seg[k], p[1]->seg[k], p[2]->seg[k]};
        Beam b;
        if (make_beam(edges, flux, p[0]->medium[k], s_.clamp_ratio, b) != BeamStatus::Ok) { ++tb.degenerate; continue; }
        const MediumCoefficients mc = medium_at(scene, b.medium);
        {
            // Concentration where the beam ends (the receiver): its end section against its start.
            const double ys = (b.ys[0] + b.ys[1] + b.ys[2]) / 3.0, ye = (b.ye[0] + b.ye[1] + b.ye[2]) / 3.0;
            tb.min_ratio = std::min(tb.min_ratio, std::abs(b.area(ye)) / std::abs(b.area(ys)));
        }
        if (!cut_by_energy(b, mc.extinction(), s_.energy_cutoff)) { ++tb.energy; continue; }
        tb.flipped += b.flipped;
        tb.folded = tb.folded || passes_focus(b);   // a focus inside the slab the energy cut left
        // The oracle's camera term: the closest point to the camera on the central ray (Sec. 4.2).
        const glm::dvec3 start = (edges[0].start + edges[1].start + edges[2].start) / 3.0;
        const glm::dvec3 dir = glm::normalize(edges[0].dir + edges[1].dir + edges[2].dir);
        const double len = (edges[0].length + edges[1].length + edges[2].length) / 3.0;
        const double t = std::clamp(glm::dot(camera - start, dir), 0.0, len);
        const glm::dvec3 x = start + t * dir;
        const double y = glm::dot(x - b.c, b.n);
        const double width = std::sqrt(2.0 * std::max(std::abs(b.area(y)), b.a_min));
        tb.max_view_angle = std::max(tb.max_view_angle, width / std::max(glm::length(x - camera), 1e-9));
        tb.beams.push_back(b);
        std::uint8_t ends = kAllOnReceiver | kReceiverOrNothing;
        for (const LightPath* q : p) {
            const int e = q->end_object[static_cast<std::size_t>(k)];
            if (e != scene.receiver.object_index) ends &= static_cast<std::uint8_t>(~kAllOnReceiver);
            if (e != scene.receiver.object_index && e != -1) ends &= static_cast<std::uint8_t>(~kReceiverOrNothing);
        }
        for (const LightPath* q : p) {
            const int e = q->end_object[static_cast<std::size_t>(k)];
            if (e >= 0 && !scene.objects[static_cast<std::size_t>(e)].material.is_specular()) ends |= kEndsOnDiffuse;
            if (e >= 0 && e == scene.receiver.object_index) ends |= kEndsOnReceiver;
        }
        tb.ends.push_back(ends);
        const int e0 = p[0]->end_object[static_cast<std::size_t>(k)];
        const bool one = e0 >= 0 && e0 == p[1]->end_object[static_cast<std::size_t>(k)] &&
                         e0 == p[2]->end_object[static_cast<std::size_t>(k)] &&
                         !scene.objects[static_cast<std::size_t>(e0)].material.is_specular();
        tb.end_object.push_back(one ? e0 : -1);
    }
}

// Where a triangle's corners straddle a silhouette (some rays miss the specular object, Sec. 4.1:
// "invalid triangles crossing the silhouettes ... are omitted"), `clip` bisects its edges between
// the rays that hit and those that miss (10 steps: 1/1024 of the edge) and keeps the part that hits,
// so the light at the border of a surface is not lost with whole cells.
void LightGrid::make_triangle(const Lattice& lattice, const glm::ivec2 (&ci)[3], TriBeams& tb, bool clip) const {
    const LightPath* p[3];
    glm::dvec2 c[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = &lattice.at(ci[k].x, ci[k].y);
        c[k] = glm::dvec2(ci[k]);
    }
    int tir = 0, missed = 0;
    for (const LightPath* q : p) {
        tir += q->status == LightPath::TotalInternalReflection;
        missed += q->status == LightPath::Missed;
    }
    if (missed == 3) return;
    if (tir > 0) { ++tb.tir; return; }
    if (missed == 0) {
        emit(c, p, tb);
        return;
    }
    int valid[2], nv = 0, gone[2], ng = 0;
    for (int k = 0; k < 3; ++k) (p[k]->status == LightPath::Missed ? gone[ng++] : valid[nv++]) = k;
    if (!clip || (nv == 2 && !same_structure(*p[valid[0]], *p[valid[1]]))) { ++tb.lost; return; }
    const LightPath& ref = *p[valid[0]];
    auto cut = [&](int a, int b, LightPath& out) {
        glm::dvec2 lo = c[a], hi = c[b];
        out = *p[a];
        for (int it = 0; it < 10; ++it) {
            const glm::dvec2 mid = 0.5 * (lo + hi);
            LightPath m = trace(mid.x, mid.y);
            if (m.status != LightPath::Missed && same_structure(m, ref)) lo = mid, out = m;
            else hi = mid;
        }
        return lo;
    };
    if (nv == 1) {
        const int a = valid[0];
        LightPath pb, pc;
        const glm::dvec2 qb = cut(a, gone[0], pb), qc = cut(a, gone[1], pc);
        const glm::dvec2 t[3] = {c[a], qb, qc};
        const LightPath* tp[3] = {p[a], &pb, &pc};
        emit(t, tp, tb);
    } else {
        const int a = valid[0], b = valid[1], g = gone[0];
        LightPath pa, pb;
        const glm::dvec2 qa = cut(a, g, pa), qb = cut(b, g, pb);
        const glm::dvec2 t0[3] = {c[a], c[b], qb}, t1[3] = {c[a], qb, qa};
        const LightPath* p0[3] = {p[a], p[b], &pb};
        const LightPath* p1[3] = {p[a], &pb, &pa};
        emit(t0, p0, tb);
        emit(t1, p1, tb);
    }
}

// Traces the lattice points `cells` need that are not traced yet (each cell's corners; with step 1 also its
// edge midpoints and centre, for the deviation test), in lattice order, so that the result does not depend
// on the threads.
void LightGrid::trace_points(Lattice& lattice, const std::vector<Cell>& cells, int size, int step) const {
    std::vector<std::uint64_t> need;
    for (const Cell& c : cells)
        for (int dj = 0; dj <= 2; dj += step)
            for (int di = 0; di <= 2; di += step) {
                const int i = c.i + di * size / 2, j = c.j + dj * size / 2;
                if (lattice.find(i, j) < 0) need.push_back(key(i, j));
            }
    std::sort(need.begin(), need.end());
    need.erase(std::unique(need.begin(), need.end()), need.end());
    const std::size_t first = lattice.paths.size();
    lattice.paths.resize(first + need.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, need.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n)
            lattice.paths[first + n] = trace(static_cast<int>(need[n] >> 32), static_cast<int>(need[n] & 0xffffffffu));
    });
    for (std::size_t n = 0; n < need.size(); ++n)
        lattice.insert(static_cast<int>(need[n] >> 32), static_cast<int>(need[n] & 0xffffffffu), static_cast<int>(first + n));
}

// The oracle (Sec. 4.2) on one cell of `size` lattice steps at refinement `level`: 0 drop (no light ray
// through its corners meets a specular surface), 1 leaf, 2 split.
std::uint8_t LightGrid::oracle(const Lattice& lattice, const Cell& c, int size, int level, bool can_split) const {
    const double cos_normal = std::cos(s_.normal_threshold_deg * M_PI / 180.0);
    const glm::ivec2 q[4] = {{c.i, c.j}, {c.i + size, c.j}, {c.i + size, c.j + size}, {c.i, c.j + size}};
    const LightPath* p[4];
    int missed = 0;
    for (int k = 0; k < 4; ++k) {
        p[k] = &lattice.at(q[k].x, q[k].y);
        missed += p[k]->status == LightPath::Missed;
    }
    if (missed == 4) return 0;
    if (!can_split) return 1;
    bool split = false;
    for (int k = 1; k < 4 && !split; ++k) split = !same_structure(*p[0], *p[k]);
    if (!split) {
        // Depth and normal discontinuities at the beam corners' origins.
        double dmin = 1e300, dmax = -1e300, cmin = 1.0;
        for (int a = 0; a < 4; ++a) {
            dmin = std::min(dmin, p[a]->depth), dmax = std::max(dmax, p[a]->depth);
            for (int b = a + 1; b < 4; ++b) cmin = std::min(cmin, glm::dot(p[a]->normal, p[b]->normal));
        }
        double width = size * (proj_.x1 - proj_.x0) / res_;
        if (proj_.type == ProjectionType::Perspective) width *= 0.5 * (dmin + dmax);
        split = dmax - dmin > s_.depth_threshold * width || cmin < cos_normal;
    }
    if (!split && p[0]->segments > 0) {
        // The light's hits at the cell's edge midpoints and centre against the bilinear beam's
        // (Sec. 6: "the difference of photon hits at beam edges"): where the ray map is not
        // linear over the cell, one beam misplaces the caustic.
        const int h = size / 2;
        const glm::ivec2 mid[5] = {{c.i + h, c.j}, {c.i + size, c.j + h}, {c.i + h, c.j + size}, {c.i, c.j + h},
                                   {c.i + h, c.j + h}};
        const int last = p[0]->segments - 1;
        auto end = [&](const LightPath& lp) {
            const EdgeRay& e = lp.seg[static_cast<std::size_t>(last)];
            return e.start + e.length * e.dir;
        };
        const glm::dvec3 e0 = end(*p[0]), e1 = end(*p[1]), e2 = end(*p[2]), e3 = end(*p[3]);
        const glm::dvec3 predicted[5] = {0.5 * (e0 + e1), 0.5 * (e1 + e2), 0.5 * (e2 + e3), 0.5 * (e3 + e0),
                                         0.25 * (e0 + e1 + e2 + e3)};
        const double extent = std::max(glm::length(e2 - e0), glm::length(e3 - e1));
        for (int k = 0; k < 5 && !split; ++k) {
            const LightPath& m = lattice.at(mid[k].x, mid[k].y);
            if (!same_structure(*p[0], m)) split = true;
            else split = glm::length(end(m) - predicted[k]) > s_.deviation * extent;
        }
    }
    if (!split) {
        // Convergent beams by energy (a beam at level L carries 4^-L of an initial cell's light:
        // its concentration where it ends is weighed against focus_ratio 4^L; the minimum over
        // its length would split every beam that passes a focus, to the last level), beams
        // wide as seen from the camera, and (fold_split) beams that pass a focus before they end:
        // past the first focus a fold of the ray map lies inside them, and a beam's one density
        // smears its 1/sqrt peak over the whole section (drawn sine cases at 1-1.5 x the first
        // focus: 0.11 without this test at a finest grid of 256, 0.088 with it).
        // Reused per thread (its vectors keep their capacity from cell to cell); make_triangle starts no nested
        // parallel work, so no other cell runs on this thread while it is in use.
        thread_local TriBeams tb;
        tb.clear();
        const glm::ivec2 t0[3] = {q[0], q[1], q[2]}, t1[3] = {q[0], q[2], q[3]};
        make_triangle(lattice, t0, tb, false);
        make_triangle(lattice, t1, tb, false);
        split = tb.min_ratio * s_.focus_ratio * std::ldexp(1.0, 2 * level) < 1.0 ||
                tb.max_view_angle > s_.camera_angle || (s_.fold_split && tb.folded);
    }
    return split ? 2 : 1;
}

// The leaves' beams, in leaf order. A leaf whose neighbour was refined further has that neighbour's
// corners on its side (T-junctions): it is then cut into a fan around its centre through every such
// corner, so that neighbouring beams share their edge rays and the beams tile the light without
// cracks or overlaps (otherwise the bilinear sides of a coarse beam and of its finer neighbours part
// where the ray map bends, and light is lost or counted twice).
void LightGrid::leaf_beams(const Lattice& lattice, const std::vector<Cell>& leaves, int s0, std::vector<TriBeams>& per,
                           std::vector<std::uint8_t>& corner_marks, BeamSet& out) const {
    GridStats& st = out.stats;
    // The leaves' corners: a dense table where the lattice's is dense, a hash set beyond.
    const std::size_t dense_side = static_cast<std::size_t>(lattice.side);
    std::unordered_map<std::uint64_t, char> corner;
    if (dense_side > 0) corner_marks.assign(dense_side * dense_side, 0);
    for (const Cell& c : leaves) {
        const int size = s0 >> c.level;
        for (int dj = 0; dj <= 1; ++dj)
            for (int di = 0; di <= 1; ++di) {
                const int i = c.i + di * size, j = c.j + dj * size;
                if (dense_side > 0) corner_marks[static_cast<std::size_t>(j) * dense_side + static_cast<std::size_t>(i)] = 1;
                else corner.emplace(key(i, j), 1);
            }
    }
    auto is_corner = [&](const glm::ivec2& v) {
        return dense_side > 0 ? corner_marks[static_cast<std::size_t>(v.y) * dense_side + static_cast<std::size_t>(v.x)] != 0
                              : corner.count(key(v.x, v.y)) != 0;
    };
    if (per.size() < leaves.size()) per.resize(leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
        // Per thread: make_triangle (Embree's single rays) starts no nested parallel work that could run
        // another leaf on this thread while the ring is in use.
        thread_local std::vector<glm::ivec2> ring;
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const Cell& c = leaves[n];
            per[n].clear();
            const int size = s0 >> c.level;
            const glm::ivec2 q[4] = {{c.i, c.j}, {c.i + size, c.j}, {c.i + size, c.j + size}, {c.i, c.j + size}};
            ring.clear();
            for (int side = 0; side < 4; ++side) {
                const glm::ivec2 a = q[side], b = q[(side + 1) % 4], step = (b - a) / size;
                ring.push_back(a);
                for (int t = 1; t < size; ++t) {
                    const glm::ivec2 v = a + t * step;
                    if (is_corner(v)) ring.push_back(v);
                }
            }
            if (ring.size() == 4) {
                const glm::ivec2 t0[3] = {q[0], q[1], q[2]}, t1[3] = {q[0], q[2], q[3]};
                make_triangle(lattice, t0, per[n], true);
                make_triangle(lattice, t1, per[n], true);
                continue;
            }
            const glm::ivec2 centre{c.i + size / 2, c.j + size / 2};   // traced: the leaf could have split
            for (std::size_t k = 0; k < ring.size(); ++k) {
                const glm::ivec2 t[3] = {centre, ring[k], ring[(k + 1) % ring.size()]};
                make_triangle(lattice, t, per[n], true);
            }
        }
    });
    st.cells = static_cast<std::int64_t>(leaves.size());
    std::size_t total = 0;
    for (std::size_t n = 0; n < leaves.size(); ++n) total += per[n].beams.size();
    out.beams.reserve(total);
    out.ends.reserve(total);
    out.end_object.reserve(total);
    for (std::size_t n = 0; n < leaves.size(); ++n) {
        const TriBeams& tb = per[n];
        st.discarded_tir += tb.tir;
        st.discarded_energy += tb.energy;
        st.degenerate += tb.degenerate;
        st.lost += tb.lost;
        st.flipped += tb.flipped;
        out.beams.insert(out.beams.end(), tb.beams.begin(), tb.beams.end());
        out.ends.insert(out.ends.end(), tb.ends.begin(), tb.ends.end());
        out.end_object.insert(out.end_object.end(), tb.end_object.begin(), tb.end_object.end());
    }
    st.beams_generated = static_cast<std::int64_t>(out.beams.size());
}

void LightGrid::generate(BeamSet& out, GridScratch& scratch) const {
    out.beams.clear();
    out.ends.clear();
    out.end_object.clear();
    out.stats = GridStats{};
    Lattice& lattice = scratch.lattice;
    lattice.reset(res_, scratch.dense_limit);
    const int max_level = s_.adaptive ? s_.iterations : 0;
    const int s0 = res_ / s_.grid;
    std::vector<Cell> cells;
    for (int j = 0; j < s_.grid; ++j)
        for (int i = 0; i < s_.grid; ++i) cells.push_back({0, i * s0, j * s0});
    std::vector<Cell> leaves;
    for (int level = 0; level <= max_level && !cells.empty(); ++level) {
        const int size = s0 >> level;
        const bool can_split = level < max_level;
        trace_points(lattice, cells, size, can_split ? 1 : 2);
        std::vector<std::uint8_t> action(cells.size(), 1);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t n = r.begin(); n != r.end(); ++n) action[n] = oracle(lattice, cells[n], size, level, can_split);
        });
        std::vector<Cell> next;
        for (std::size_t n = 0; n < cells.size(); ++n) {
            if (action[n] == 1) leaves.push_back(cells[n]);
            if (action[n] != 2) continue;
            ++out.stats.beams_split;
            const Cell& c = cells[n];
            const int h = size / 2;
            for (int dj = 0; dj <= 1; ++dj)
                for (int di = 0; di <= 1; ++di) next.push_back({level + 1, c.i + di * h, c.j + dj * h});
        }
        cells.swap(next);
    }
    leaf_beams(lattice, leaves, s0, scratch.leaves, scratch.corner_marks, out);
}

}  // namespace caustics::adaptive_beams
