// The volume view's nodes, smooth blocks and refined pixels (Sec. 5.1, 5.2; see volume_view.hpp).
#include "volume_view.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::adaptive_beams {
namespace {

constexpr double kNoHit = std::numeric_limits<double>::infinity();
// A smooth block's pixels lie within this fraction of the bilinear depth of its nodes (a fold or a
// silhouette of one object inside the block refines it).
constexpr double kDepthTolerance = 0.05;
// Sub-rays made and integrated at once (32 bytes each: direction and end), and traced per batch.
constexpr std::size_t kChunkRays = std::size_t{1} << 20;
constexpr std::size_t kTraceBatch = 256;

// The rays of one pass: per pixel `per_pixel` rays from `first[pixel]` (-1: the pixel is not in the pass),
// and per row the sorted columns in the pass.
struct Pass {
    std::vector<int> first;
    int per_pixel = 1;
    std::vector<glm::dvec3> dir;
    std::vector<double> s_max;
    std::vector<std::vector<int>> columns;
    bool box = false;   // rays anywhere in the pixel's square: walk the pixels the hulls overlap
    std::vector<double>* ray_value = nullptr;   // when set: each ray's radiance, indexed as dir
};

double gbuffer_depth(const CameraGBuffer& g, const CameraModel& cam, std::size_t i) {
    return g.object[i] >= 0 ? glm::length(glm::dvec3(g.position[i]) - cam.position) : kNoHit;
}

// Mean over each pass pixel's rays of the sum over beams of their integrals, added to out[pixel] (pixels
// of the pass only; each beam's share is divided by the rays per pixel as it is added). Bands of rows are independent; each walks the beams in order.
void evaluate(const Pass& pass, const std::vector<VolumeBeam>& beams, const CameraGBuffer& g, const VolumeSettings& settings,
              std::vector<double>& out, VolumeStats& stats) {
    const int W = g.width, H = g.height;
    const int bands = (H + kBandRows - 1) / kBandRows;
    const int samples = settings.samples;
    const bool lanes = settings.lanes, single = settings.single;
    std::vector<VolumeStats> per_band(static_cast<std::size_t>(bands));
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& br) {
        for (int band = br.begin(); band != br.end(); ++band) {
            const int r0 = band * kBandRows, r1 = std::min(H, r0 + kBandRows) - 1;
            bool any = false;
            for (int y = r0; y <= r1 && !any; ++y) any = !pass.columns[static_cast<std::size_t>(y)].empty();
            if (!any) continue;
            BeamCounters counters;
            std::vector<double> values;
            VolumeStats& st = per_band[static_cast<std::size_t>(band)];
            for (const VolumeBeam& vb : beams) {
                const Coverage& cov = *vb.pixels;
                const int lo = pass.box ? cov.box_lo : cov.y_lo, hi = pass.box ? cov.box_hi : cov.y_hi;
                if (hi < r0 || lo > r1) continue;
                for (int y = std::max(r0, lo); y <= std::min(r1, hi); ++y) {
                    const std::vector<int>& cols = pass.columns[static_cast<std::size_t>(y)];
                    if (cols.empty()) continue;
                    int spans[3][2];
                    const int ns = row_spans(cov, y, W, pass.box, spans);
                    for (int k = 0; k < ns; ++k) {
                        auto it = std::lower_bound(cols.begin(), cols.end(), spans[k][0]);
                        while (it != cols.end() && *it <= spans[k][1]) {
                            // A run of the span's pixels whose rays lie one after the other: their integrals in
                            // lanes (ray_beam.hpp), then each pixel's mean in order.
                            auto end = it + 1;
                            while (end != cols.end() && *end <= spans[k][1] &&
                                   pass.first[g.index(*end, y)] == pass.first[g.index(*(end - 1), y)] + pass.per_pixel)
                                ++end;
                            const auto first_ray = static_cast<std::size_t>(pass.first[g.index(*it, y)]);
                            const int pixels = static_cast<int>(end - it), rays = pixels * pass.per_pixel;
                            values.resize(static_cast<std::size_t>(rays));
                            const glm::dvec3* dir = &pass.dir[first_ray];
                            const double* s_max = &pass.s_max[first_ray];
                            if (single)
                                vb.beam->radiance_each_single(dir, s_max, rays, samples, counters, kVolumeNearDistance, values.data());
                            else if (lanes)
                                vb.beam->radiance_lanes(dir, s_max, rays, samples, counters, kVolumeNearDistance, values.data());
                            else
                                vb.beam->radiance_each(dir, s_max, rays, samples, counters, kVolumeNearDistance, values.data());
                            for (int p = 0; p < pixels; ++p, ++it) {
                                const std::size_t i = g.index(*it, y);
                                const std::size_t r = first_ray + static_cast<std::size_t>(p * pass.per_pixel);
                                double sum = 0.0;
                                for (int q = 0; q < pass.per_pixel; ++q) {
                                    const double v = values[static_cast<std::size_t>(p * pass.per_pixel + q)];
                                    sum += v;
                                    if (pass.ray_value) (*pass.ray_value)[r + q] += v;
                                }
                                out[i] += pass.per_pixel > 1 ? sum / pass.per_pixel : sum;
                                ++st.fill;
                                st.rays += pass.per_pixel;
                            }
                        }
                    }
                }
            }
            st.clamped = counters.clamped;
        }
    });
    for (const VolumeStats& st : per_band) {
        stats.fill += st.fill;
        stats.rays += st.rays;
        stats.clamped += st.clamped;
    }
}

// Bilinear interpolation of a block's four corner values (x0 y0, x1 y0, x0 y1, x1 y1) at (tx, ty) in [0, 1]^2.
double bilinear(const double (&c)[4], double tx, double ty) {
    return (1 - ty) * ((1 - tx) * c[0] + tx * c[1]) + ty * ((1 - tx) * c[2] + tx * c[3]);
}

// Node positions along one axis of n pixels: 0, step, 2 step, ... and n - 1.
std::vector<int> lattice(int n, int step) {
    std::vector<int> v;
    for (int x = 0; x < n; x += step) v.push_back(x);
    if (v.back() != n - 1) v.push_back(n - 1);
    return v;
}

// The pixels `want` as the mean of sub x sub stratified rays through their squares, each ray to its own
// first hit (without a tracer: to its pixel's depth), added to out[pixel]. The rays are made, traced and
// integrated in bands of rows of at most kChunkRays rays (at least one row: 16 x 16 sub-rays of a
// 4,096-pixel row are 32 MB), so that memory stays bounded. With `edge` set and sub > 1, a pixel whose rays'
// radiances spread by more than `refine` of their mean is marked in it (out must start at zero: out[pixel]
// is then the rays' mean).
template <class Want>
void box_pass(const Want& want, int sub, const std::vector<VolumeBeam>& beams, const CameraModel& cam,
              const CameraGBuffer& g, const RayTracer* tracer, const VolumeSettings& settings, std::vector<double>& out,
              std::vector<std::uint8_t>* edge, double refine, VolumeStats& stats) {
    const int W = g.width, H = g.height;
    const std::size_t np = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    const std::size_t per_pixel = static_cast<std::size_t>(sub) * static_cast<std::size_t>(sub);
    Pass full;
    full.per_pixel = sub * sub;
    full.box = sub > 1;
    full.first.assign(np, -1);
    full.columns.resize(static_cast<std::size_t>(H));
    std::vector<double> ray_value;
    if (edge && sub > 1) full.ray_value = &ray_value;
    int y_next = 0;
    while (y_next < H) {
        const int y_begin = y_next;
        full.dir.clear();
        full.s_max.clear();
        for (; y_next < H && (y_next == y_begin || full.dir.size() + per_pixel * static_cast<std::size_t>(W) <= kChunkRays);
             ++y_next) {
            std::vector<int>& cols = full.columns[static_cast<std::size_t>(y_next)];
            for (int x = 0; x < W; ++x) {
                const std::size_t i = g.index(x, y_next);
                if (!want(i)) continue;
                cols.push_back(x);
                full.first[i] = static_cast<int>(full.dir.size());
                const double depth = gbuffer_depth(g, cam, i);   // the end of a ray when no tracer is given
                for (int a = 0; a < sub; ++a)
                    for (int b = 0; b < sub; ++b) {
                        full.dir.push_back(cam.ray_direction(x + (b + 0.5) / sub, y_next + (a + 0.5) / sub));
                        full.s_max.push_back(depth);
                    }
            }
        }
        if (sub > 1 && tracer)
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, full.dir.size(), kTraceBatch),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                std::array<RayQuery, kTraceBatch> q;
                std::array<Hit, kTraceBatch> hits;
                for (std::size_t k0 = r.begin(); k0 < r.end(); k0 += kTraceBatch) {
                    const std::size_t n = std::min(kTraceBatch, r.end() - k0);
                    for (std::size_t k = 0; k < n; ++k) q[k].origin = cam.position, q[k].dir = full.dir[k0 + k];
                    tracer->intersect(q.data(), n, hits.data());
                    for (std::size_t k = 0; k < n; ++k) full.s_max[k0 + k] = hits[k].valid ? hits[k].t : kNoHit;
                }
            });
        if (full.ray_value) ray_value.assign(full.dir.size(), 0.0);
        if (!full.dir.empty()) evaluate(full, beams, g, settings, out, stats);
        // The band's rows leave the pass: the next band's indices start again at 0.
        for (int y = y_begin; y < y_next; ++y) {
            for (int x : full.columns[static_cast<std::size_t>(y)]) {
                const std::size_t i = g.index(x, y);
                if (full.ray_value) {
                    const auto r = static_cast<std::size_t>(full.first[i]);
                    const auto [lo, hi] = std::minmax_element(ray_value.begin() + static_cast<std::ptrdiff_t>(r),
                                                              ray_value.begin() + static_cast<std::ptrdiff_t>(r + per_pixel));
                    (*edge)[i] = *hi - *lo > refine * out[i] ? 1 : 0;
                }
                full.first[i] = -1;
            }
            full.columns[static_cast<std::size_t>(y)].clear();
        }
    }
}

}  // namespace

void render_volume(const std::vector<VolumeBeam>& beams, const CameraModel& cam, const CameraGBuffer& g,
                   const RayTracer* tracer, const VolumeSettings& s, Image& volume, VolumeStats& stats) {
    const int W = g.width, H = g.height;
    const std::size_t np = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    volume = Image(W, H);
    if (np == 0) return;
    // A single row or column has no blocks: every pixel is a node (and refined, below).
    const int step = W < 2 || H < 2 ? 1 : std::max(1, s.step), sub = std::max(1, s.subpixels);
    const std::vector<int> cx = lattice(W, step), cy = lattice(H, step);

    // Nodes: one ray through each node pixel's centre.
    Pass nodes;
    nodes.first.assign(np, -1);
    nodes.columns.resize(static_cast<std::size_t>(H));
    for (int y : cy) {
        nodes.columns[static_cast<std::size_t>(y)] = cx;
        for (int x : cx) {
            const std::size_t i = g.index(x, y);
            nodes.first[i] = static_cast<int>(nodes.dir.size());
            nodes.dir.push_back(cam.ray_direction(x + 0.5, y + 0.5));
            nodes.s_max.push_back(gbuffer_depth(g, cam, i));
        }
    }
    std::vector<double> value(np, 0.0);
    evaluate(nodes, beams, g, s, value, stats);
    if (step == 1 && sub == 1) {
        for (std::size_t i = 0; i < np; ++i) volume.pixels[i] = static_cast<float>(value[i]);
        stats.refined += static_cast<std::int64_t>(np);   // every pixel evaluated in full
        return;
    }

    // Blocks between four nodes: smooth (interpolated) or refined (every pixel evaluated).
    const int bx_n = static_cast<int>(cx.size()) - 1, by_n = static_cast<int>(cy.size()) - 1;
    std::vector<std::uint8_t> rough(static_cast<std::size_t>(std::max(0, bx_n * by_n)), 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, by_n), [&](const tbb::blocked_range<int>& r) {
        for (int by = r.begin(); by != r.end(); ++by)
            for (int bx = 0; bx < bx_n; ++bx) {
                const int x0 = cx[static_cast<std::size_t>(bx)], x1 = cx[static_cast<std::size_t>(bx) + 1];
                const int y0 = cy[static_cast<std::size_t>(by)], y1 = cy[static_cast<std::size_t>(by) + 1];
                const std::size_t c[4] = {g.index(x0, y0), g.index(x1, y0), g.index(x0, y1), g.index(x1, y1)};
                double lo = value[c[0]], hi = lo;
                for (std::size_t k : c) lo = std::min(lo, value[k]), hi = std::max(hi, value[k]);
                bool smooth = hi - lo <= s.refine * 0.5 * (hi + lo);
                const int object = g.object[c[0]];
                double d[4];
                for (int k = 0; k < 4; ++k) d[k] = gbuffer_depth(g, cam, c[k]);
                for (int y = y0; y <= y1 && smooth; ++y)
                    for (int x = x0; x <= x1 && smooth; ++x) {
                        const std::size_t i = g.index(x, y);
                        if (g.object[i] != object) smooth = false;
                        else if (object >= 0) {
                            const double tx = double(x - x0) / (x1 - x0), ty = double(y - y0) / (y1 - y0);
                            const double depth = gbuffer_depth(g, cam, i);
                            smooth = std::abs(depth - bilinear(d, tx, ty)) <= kDepthTolerance * depth;
                        }
                    }
                rough[static_cast<std::size_t>(by) * bx_n + bx] = smooth ? 0 : 1;
            }
    });
    // A pixel is refined when a block holding it is (pixels on a block's edge belong to two blocks).
    auto blocks_of = [&](const std::vector<int>& nodes, int x, int& b0, int& b1) {
        const int k = static_cast<int>(std::upper_bound(nodes.begin(), nodes.end(), x) - nodes.begin()) - 1;
        const int last = static_cast<int>(nodes.size()) - 2;
        b1 = std::min(k, last);
        b0 = nodes[static_cast<std::size_t>(k)] == x && k > 0 ? k - 1 : b1;
    };
    std::vector<std::uint8_t> refined(np, 0);
    // A single row or column has no blocks: every pixel is refined.
    if (bx_n == 0 || by_n == 0) std::fill(refined.begin(), refined.end(), std::uint8_t{1});
    else tbb::parallel_for(tbb::blocked_range<int>(0, H, kBandRows), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end(); ++y) {
            int ya, yb;
            blocks_of(cy, y, ya, yb);
            for (int x = 0; x < W; ++x) {
                int xa, xb;
                blocks_of(cx, x, xa, xb);
                bool any = false;
                for (int by = ya; by <= yb && !any; ++by)
                    for (int bx = xa; bx <= xb && !any; ++bx) any = rough[static_cast<std::size_t>(by) * bx_n + bx] != 0;
                refined[g.index(x, y)] = any ? 1 : 0;
            }
        }
    });

    // Refined pixels, each as the mean of sub x sub stratified rays (centre rays: nodes are done); with
    // sub > 1, a refined pixel whose sub-rays differ by more than `refine` of their mean has a hull's edge
    // (the light cone's) inside it, and is evaluated again with edge_sub x edge_sub rays.
    std::vector<double> full_value(np, 0.0);
    // With centre rays a refined node keeps its node value (the same ray).
    auto in_full = [&](std::size_t i) { return refined[i] && (sub > 1 || nodes.first[i] < 0); };
    const int edge_sub = std::max(sub, s.edge_subpixels);
    std::vector<std::uint8_t> edge(edge_sub > sub ? np : 0, 0);
    box_pass(in_full, sub, beams, cam, g, tracer, s, full_value, edge_sub > sub ? &edge : nullptr, s.refine,
             stats);
    if (edge_sub > sub) {
        std::vector<double> edge_value(np, 0.0);
        box_pass([&](std::size_t i) { return edge[i] != 0; }, edge_sub, beams, cam, g, tracer, s, edge_value,
                 nullptr, s.refine, stats);
        for (std::size_t i = 0; i < np; ++i)
            if (edge[i]) full_value[i] = edge_value[i], ++stats.edge_pixels;
    }

    // Compose: refined pixels, nodes, and the bilinear interpolation of the rest.
    tbb::parallel_for(tbb::blocked_range<int>(0, H, kBandRows), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end(); ++y) {
            const int by = std::min(y / step, by_n - 1);
            for (int x = 0; x < W; ++x) {
                const std::size_t i = g.index(x, y);
                double v;
                if (in_full(i)) v = full_value[i];
                else if (nodes.first[i] >= 0) v = value[i];
                else {
                    const int bx = std::min(x / step, bx_n - 1);
                    const int x0 = cx[static_cast<std::size_t>(bx)], x1 = cx[static_cast<std::size_t>(bx) + 1];
                    const int y0 = cy[static_cast<std::size_t>(by)], y1 = cy[static_cast<std::size_t>(by) + 1];
                    const double c[4] = {value[g.index(x0, y0)], value[g.index(x1, y0)], value[g.index(x0, y1)],
                                         value[g.index(x1, y1)]};
                    v = bilinear(c, double(x - x0) / (x1 - x0), double(y - y0) / (y1 - y0));
                }
                volume.pixels[i] = static_cast<float>(v);
            }
        }
    });
    std::int64_t n_refined = 0;
    for (std::size_t i = 0; i < np; ++i) n_refined += refined[i];
    stats.refined += n_refined;
}

}  // namespace caustics::adaptive_beams
