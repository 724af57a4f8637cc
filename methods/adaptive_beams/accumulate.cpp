// Scan conversion of the beam hulls into the camera and the receiver map (Sec. 5.1-5.3).
#include "accumulate.hpp"
#include "ray_beam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/raster.hpp>

namespace caustics::adaptive_beams {
namespace {

constexpr int kBandRows = 8;

double cross2(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain: the convex hull of `pts`, counter-clockwise.
std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> pts) {
    std::sort(pts.begin(), pts.end(), [](const glm::dvec2& a, const glm::dvec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    if (pts.size() < 3) return pts;
    std::vector<glm::dvec2> h(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
        h[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && cross2(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
        h[k++] = pts[i - 1];
    }
    h.resize(k - 1);
    return h;
}

// A beam's footprint in the image: the convex polygon its hull projects to (pixel coordinates).
struct Footprint {
    std::vector<glm::dvec2> poly;
    int y_lo = 0, y_hi = -1;   // rows whose centres it may hold
};

// Projects the hull's corners, first clipping their convex hull by the near plane: the part in front is
// the hull of the corners in front and of the crossings of every pair of corners with the plane.
Footprint footprint(const std::array<glm::dvec3, 6>& corners, const CameraModel& cam, int width, int height,
                    bool& clipped) {
    constexpr double kNear = 1e-4;
    double z[6];
    std::vector<glm::dvec3> front;
    for (int i = 0; i < 6; ++i) {
        z[i] = glm::dot(corners[i] - cam.position, cam.forward);
        if (z[i] > kNear) front.push_back(corners[i]);
    }
    clipped = front.size() < 6;
    Footprint f;
    if (front.empty()) return f;
    if (clipped)
        for (int i = 0; i < 6; ++i)
            for (int j = i + 1; j < 6; ++j)
                if ((z[i] > kNear) != (z[j] > kNear)) {
                    const double t = (kNear - z[i]) / (z[j] - z[i]);
                    front.push_back(corners[i] + t * (corners[j] - corners[i]));
                }
    std::vector<glm::dvec2> pts;
    for (const glm::dvec3& p : front) {
        double px = 0.0, py = 0.0;
        if (cam.project(p, px, py)) pts.push_back({px, py});
    }
    f.poly = convex_hull(pts);
    double lo = 1e300, hi = -1e300;
    for (const glm::dvec2& p : f.poly) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    f.y_lo = static_cast<int>(std::max(0.0, std::ceil(lo - 0.5)));
    f.y_hi = static_cast<int>(std::min(height - 1.0, std::floor(hi - 0.5)));
    return f;
}

// Pixel columns whose centres lie in the convex polygon on row y: [x0, x1], empty when x0 > x1.
void row_span(const Footprint& f, int y, int width, int& x0, int& x1) {
    const double yc = y + 0.5;
    double lo = 1e300, hi = -1e300;
    const std::size_t n = f.poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = f.poly[i], b = f.poly[(i + 1) % n];
        if ((a.y <= yc && b.y >= yc) || (b.y <= yc && a.y >= yc)) {
            if (a.y == b.y) {
                lo = std::min({lo, a.x, b.x});
                hi = std::max({hi, a.x, b.x});
            } else {
                const double x = a.x + (yc - a.y) / (b.y - a.y) * (b.x - a.x);
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
        }
    }
    x0 = static_cast<int>(std::max(0.0, std::ceil(lo - 0.5)));
    x1 = static_cast<int>(std::min(width - 1.0, std::floor(hi - 0.5)));
}

// A beam's pixels: the union of the footprints of up to three pieces of its slab. A beam that passes a
// focus (A(y) = 0, Sec. 4.3) is cut there: the convex hull of all six corners fills the waist between
// its two cones with pixels whose rays miss the beam (on `sphere_fog` a third of all fragments); each
// piece [ya, yb] still holds its part of the beam, as P_i(y) is linear in y and so every cross-section
// in it lies in the hull of P_i(ya), P_i(yb).
struct Coverage {
    std::array<Footprint, 3> part;
    int parts = 0;
    int y_lo = 0, y_hi = -1;
};

Coverage coverage(const Beam& b, HullType hull, const std::array<glm::dvec3, 6>& corners, const CameraModel& cam,
                  int width, int height, bool& clipped) {
    Coverage cov;
    double cut[4] = {b.y0};
    int nc = 1;
    if (hull == HullType::Tight && b.flipped) {
        double r[2];
        int nr = 0;
        real_roots(b.a0, b.a1, b.a2, r, nr);
        std::sort(r, r + nr);
        for (int k = 0; k < nr; ++k)
            if (r[k] > b.y0 && r[k] < b.y1) cut[nc++] = r[k];
    }
    cut[nc++] = b.y1;
    clipped = false;
    for (int k = 0; k + 1 < nc; ++k) {
        std::array<glm::dvec3, 6> piece = corners;
        if (nc > 2)
            for (int i = 0; i < 3; ++i) piece[i] = b.point(i, cut[k]), piece[3 + i] = b.point(i, cut[k + 1]);
        bool c = false;
        Footprint f = footprint(piece, cam, width, height, c);
        clipped = clipped || c;
        if (f.y_lo > f.y_hi) continue;
        cov.y_lo = cov.parts == 0 ? f.y_lo : std::min(cov.y_lo, f.y_lo);
        cov.y_hi = cov.parts == 0 ? f.y_hi : std::max(cov.y_hi, f.y_hi);
        cov.part[static_cast<std::size_t>(cov.parts++)] = std::move(f);
    }
    return cov;
}

// The pixel columns of row y the coverage holds, as disjoint sorted spans [x0, x1]; returns their number.
int row_spans(const Coverage& cov, int y, int width, int (&spans)[3][2]) {
    int n = 0;
    for (int k = 0; k < cov.parts; ++k) {
        const Footprint& f = cov.part[static_cast<std::size_t>(k)];
        if (y < f.y_lo || y > f.y_hi) continue;
        int x0, x1;
        row_span(f, y, width, x0, x1);
        if (x0 > x1) continue;
        int m = n++;
        while (m > 0 && spans[m - 1][0] > x0) spans[m][0] = spans[m - 1][0], spans[m][1] = spans[m - 1][1], --m;
        spans[m][0] = x0, spans[m][1] = x1;
    }
    int kept = 0;
    for (int k = 0; k < n; ++k)
        if (kept > 0 && spans[k][0] <= spans[kept - 1][1] + 1)
            spans[kept - 1][1] = std::max(spans[kept - 1][1], spans[k][1]);
        else
            spans[kept][0] = spans[k][0], spans[kept][1] = spans[k][1], ++kept;
    return kept;
}

// The paper's low-pass filter of the surface caustics (Sec. 7): a tent of radius r over the covered
// pixels of the same object (so that edges between objects stay sharp), normalised by the weights used.
void low_pass(Image& img, const CameraGBuffer& g, int r) {
    if (r <= 0) return;
    const Image src = img;
    tbb::parallel_for(tbb::blocked_range<int>(0, g.height, kBandRows), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < g.width; ++x) {
                const std::size_t i = g.index(x, y);
                if (!g.covered[i]) continue;
                double sum = 0.0, wsum = 0.0;
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx) {
                        const int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= g.width || yy >= g.height) continue;
                        const std::size_t j = g.index(xx, yy);
                        if (!g.covered[j] || g.object[j] != g.object[i]) continue;
                        const double w = (r + 1.0 - std::abs(dx)) * (r + 1.0 - std::abs(dy));
                        sum += w * src.at(xx, yy);
                        wsum += w;
                    }
                img.at(x, y) = static_cast<float>(sum / wsum);
            }
    });
}

}  // namespace

void accumulate_camera(const BeamSet& set, const Scene& scene, const CameraGBuffer& g, const AccumulateSettings& s,
                       Image* surface, Image* volume, AccumulateStats& stats) {
    Camera camera = scene.camera;
    camera.width = g.width;
    camera.height = g.height;
    const CameraModel cam(camera);
    const MediumCoefficients cam_medium = medium_at(scene, g.medium_object);
    const bool want_volume = volume && cam_medium.scatters();
    if (surface) *surface = Image(g.width, g.height);
    if (volume) *volume = Image(g.width, g.height);
    // Which beams take part: volume beams in the camera's medium, surface beams that end on a diffuse surface.
    const std::size_t nb = set.beams.size();
    std::vector<Coverage> fp(nb);
    std::vector<std::uint8_t> use(nb, 0);
    std::vector<std::uint8_t> clipped(nb, 0), fallback(nb, 0);
    // Each volume beam seen from the camera, once (what its fragments share).
    std::vector<RayBeam> seen(want_volume ? nb : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 32), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const Beam& b = set.beams[n];
            const bool vol = want_volume && b.medium == g.medium_object;
            const bool surf = surface && (set.ends[n] & kEndsOnDiffuse);
            if (!vol && !surf) continue;
            use[n] = static_cast<std::uint8_t>((vol ? 1 : 0) | (surf ? 2 : 0));
            if (vol) seen[n] = RayBeam(b, cam.position, cam_medium);
            std::array<glm::dvec3, 6> corners;
            if (!hull_corners(b, s.hull, corners)) {
                fallback[n] = 1;
                hull_corners(b, HullType::Tight, corners);
            }
            bool c = false;
            fp[n] = coverage(b, s.hull, corners, cam, g.width, g.height, c);
            clipped[n] = c;
        }
    });
    for (std::size_t n = 0; n < nb; ++n) {
        if (!use[n]) continue;
        stats.near_clipped += clipped[n];
        stats.prism_fallback += fallback[n];
        stats.offscreen += fp[n].y_lo > fp[n].y_hi;
    }
    // Primary ray directions and the distances to the pixels' first hits, once.
    std::vector<glm::dvec3> dirs(static_cast<std::size_t>(g.width) * g.height);
    std::vector<double> s_max(dirs.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, g.height, kBandRows), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < g.width; ++x) {
                const std::size_t i = g.index(x, y);
                dirs[i] = cam.ray_direction(x + 0.5, y + 0.5);
                s_max[i] = g.object[i] >= 0 ? glm::length(glm::dvec3(g.position[i]) - cam.position)
                                            : std::numeric_limits<double>::infinity();
            }
    });
    const int bands = (g.height + kBandRows - 1) / kBandRows;
    std::vector<std::int64_t> fill(static_cast<std::size_t>(bands), 0), clamp(static_cast<std::size_t>(bands), 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& br) {
        for (int band = br.begin(); band != br.end(); ++band) {
            const int r0 = band * kBandRows, r1 = std::min(g.height, r0 + kBandRows) - 1;
            BeamCounters counters;
            std::int64_t touched = 0;
            for (std::size_t n = 0; n < nb; ++n) {
                if (!use[n] || fp[n].y_hi < r0 || fp[n].y_lo > r1) continue;
                const Beam& b = set.beams[n];
                const MediumCoefficients mc = medium_at(scene, b.medium);
                for (int y = std::max(r0, fp[n].y_lo); y <= std::min(r1, fp[n].y_hi); ++y) {
                    int spans[3][2];
                    const int ns = row_spans(fp[n], y, g.width, spans);
                    for (int k = 0; k < ns; ++k) {
                        for (int x = spans[k][0]; x <= spans[k][1]; ++x) {
                            ++touched;
                            const std::size_t i = g.index(x, y);
                            const glm::dvec3 w = dirs[i];
                            if (use[n] & 1)
                                volume->at(x, y) += static_cast<float>(
                                    seen[n].radiance(w, s_max[i], s.volume_samples, counters, kVolumeNearDistance));
                            if ((use[n] & 2) && g.covered[i])
                                surface->at(x, y) += static_cast<float>(surface_irradiance(
                                    b, mc.extinction(), glm::dvec3(g.position[i]), glm::dvec3(g.normal[i]), true, s.end_tol,
                                    counters));
                        }
                    }
                }
            }
            fill[static_cast<std::size_t>(band)] = touched;
            clamp[static_cast<std::size_t>(band)] = counters.clamped;
        }
    });
    for (int band = 0; band < bands; ++band) {
        stats.fill += fill[static_cast<std::size_t>(band)];
        stats.clamped += clamp[static_cast<std::size_t>(band)];
    }
    if (surface) low_pass(*surface, g, s.filter);
}

void accumulate_receiver(const BeamSet& set, const Scene& scene, const ReceiverChart& chart, const AccumulateSettings& s,
                         Image& receiver, AccumulateStats& stats) {
    const int W = chart.width(), H = chart.height();
    receiver = Image(W, H);
    const std::size_t nb = set.beams.size();
    // Beams that end on the receiver with all three edges deposit the flux they bring over their end
    // section (the triangle of their edges' hits), split among the bins by exact area coverage: flux is
    // conserved however small the section (a beam focused on the receiver), where point samples of
    // Phi / |A| hit or miss it (on `sphere` 3 x 3 samples per bin lost 40 % of the flux in the focus bin).
    // The others (partly on another surface) are point-sampled below.
    std::vector<glm::vec2> positions;
    std::vector<glm::uvec3> triangles;
    std::vector<float> values;
    // A plane receiver also takes the beams that leave its edge (each edge ends on it or on nothing): their
    // edges are extended to its plane and the raster clips what falls outside it.
    const glm::dvec3 plane_p = chart.point(0.5, 0.5), plane_n = chart.normal(0.5, 0.5);
    std::vector<std::uint8_t> deposited(nb, 0);
    for (std::size_t n = 0; n < nb; ++n) {
        const std::uint8_t e = set.ends[n];
        const bool all = e & kAllOnReceiver, extend = chart.is_plane() && (e & kEndsOnReceiver) && (e & kReceiverOrNothing);
        if (!all && !extend) continue;
        const Beam& b = set.beams[n];
        const double sigma_t = medium_at(scene, b.medium).extinction();
        double arriving = 0.0;
        glm::dvec3 ends[3];
        double lengths[3];
        bool ok = true;
        for (int i = 0; i < 3; ++i) {
            const double stretch = glm::length(b.dp[i]);
            ends[i] = b.point(i, b.ye[i]);
            lengths[i] = (b.ye[i] - b.ys[i]) * stretch;
            if (!all) {
                const glm::dvec3 start = b.point(i, b.ys[i]), d = b.dp[i] / stretch;
                const double dn = glm::dot(d, plane_n);
                const double t = dn != 0.0 ? glm::dot(plane_p - start, plane_n) / dn : -1.0;
                if (!(t > 0.0)) ok = false;
                ends[i] = start + t * d;
                lengths[i] = t;
            }
        }
        if (!ok) continue;
        deposited[n] = 1;
        const auto base = static_cast<unsigned>(positions.size());
        for (int i = 0; i < 3; ++i) {
            double u = 0.0, v = 0.0;
            chart.coords(ends[i], u, v);
            positions.emplace_back(static_cast<float>(u * W), static_cast<float>(v * H));
            arriving += b.w[i] * std::exp(-sigma_t * lengths[i]) / 3.0;
        }
        triangles.emplace_back(base, base + 1, base + 2);
        values.push_back(static_cast<float>(b.flux * arriving));
    }
    {
        TriangleRaster raster;
        RasterOptions options;
        options.coverage = RasterCoverage::Area;
        raster.draw({positions, triangles, values, {}}, options, receiver);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) receiver.at(x, y) = static_cast<float>(receiver.at(x, y) / chart.bin_area(x, y));
    }
    struct Box { int x0 = 0, x1 = -1, y0 = 0, y1 = -1; };
    std::vector<Box> box(nb);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            if (!(set.ends[n] & kEndsOnReceiver) || deposited[n]) continue;
            const Beam& b = set.beams[n];
            double slo = 1e300, shi = -1e300, tlo = 1e300, thi = -1e300;
            for (int i = 0; i < 3; ++i) {
                double u = 0.0, v = 0.0;
                chart.coords(b.point(i, b.ye[i]), u, v);
                slo = std::min(slo, u), shi = std::max(shi, u), tlo = std::min(tlo, v), thi = std::max(thi, v);
            }
            // Grown by a tenth of its size and a bin: the bilinear sides bulge between the corners.
            const double gs = 0.1 * (shi - slo) + 1.0 / W, gt = 0.1 * (thi - tlo) + 1.0 / H;
            Box& bx = box[n];
            bx.x0 = std::max(0, static_cast<int>(std::floor((slo - gs) * W)));
            bx.x1 = std::min(W - 1, static_cast<int>(std::floor((shi + gs) * W)));
            bx.y0 = std::max(0, static_cast<int>(std::floor((tlo - gt) * H)));
            bx.y1 = std::min(H - 1, static_cast<int>(std::floor((thi + gt) * H)));
        }
    });
    const int ss = std::max(1, s.receiver_samples);
    // Sample positions in a bin: the R2 sequence (Roberts 2018), stratified and with irrational offsets, so
    // that no sample lies exactly on a beam's side shared by two beams (counted twice) on symmetric grids.
    std::vector<glm::dvec2> offsets(static_cast<std::size_t>(ss * ss));
    for (int k = 0; k < ss * ss; ++k)
        offsets[static_cast<std::size_t>(k)] = {std::fmod(0.5 + 0.7548776662466927 * (k + 1), 1.0),
                                                std::fmod(0.5 + 0.5698402909980532 * (k + 1), 1.0)};
    const int bands = (H + kBandRows - 1) / kBandRows;
    std::vector<std::int64_t> clamp(static_cast<std::size_t>(bands), 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& br) {
        for (int band = br.begin(); band != br.end(); ++band) {
            const int r0 = band * kBandRows, r1 = std::min(H, r0 + kBandRows) - 1;
            BeamCounters counters;
            for (std::size_t n = 0; n < nb; ++n) {
                const Box& bx = box[n];
                if (bx.x1 < bx.x0 || bx.y1 < r0 || bx.y0 > r1) continue;
                const Beam& b = set.beams[n];
                const double sigma_t = medium_at(scene, b.medium).extinction();
                for (int y = std::max(r0, bx.y0); y <= std::min(r1, bx.y1); ++y)
                    for (int x = bx.x0; x <= bx.x1; ++x) {
                        double sum = 0.0;
                        for (std::size_t k = 0; k < offsets.size(); ++k) {
                            const double u = (x + offsets[k].x) / W, v = (y + offsets[k].y) / H;
                            sum += surface_irradiance(b, sigma_t, chart.point(u, v), chart.normal(u, v), false,
                                                      s.end_tol, counters);
                        }
                        receiver.at(x, y) += static_cast<float>(sum / (ss * ss));
                    }
            }
            clamp[static_cast<std::size_t>(band)] = counters.clamped;
        }
    });
    for (std::int64_t c : clamp) stats.clamped += c;
}

}  // namespace caustics::adaptive_beams
