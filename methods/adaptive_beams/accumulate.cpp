// Scan conversion of the beam hulls into the camera and the receiver map (Sec. 5.1-5.3).
#include "accumulate.hpp"
#include "hull_raster.hpp"
#include "ray_beam.hpp"
#include "surface_coverage.hpp"
#include "volume_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/raster.hpp>
#include <caustics/util/timing.hpp>

namespace caustics::adaptive_beams {
namespace {

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

// The image area a coverage spans [pixels]: its parts' projected polygons clipped to the W x H image (parts of a
// beam cut at a focus may overlap: a measure of the beam's cost, not an exact count).
double covered_pixels(const Coverage& cov, int W, int H) {
    double area = 0.0;
    std::vector<glm::dvec2> poly, next;
    for (int k = 0; k < cov.parts; ++k) {
        poly = cov.part[static_cast<std::size_t>(k)].poly;
        // Sutherland-Hodgman against x >= 0, x <= W, y >= 0, y <= H.
        for (int side = 0; side < 4 && !poly.empty(); ++side) {
            auto inside = [&](const glm::dvec2& q) {
                return side == 0 ? q.x >= 0.0 : side == 1 ? q.x <= W : side == 2 ? q.y >= 0.0 : q.y <= H;
            };
            auto cut = [&](const glm::dvec2& a, const glm::dvec2& b) {
                const double t = side == 0   ? (0.0 - a.x) / (b.x - a.x)
                                 : side == 1 ? (W - a.x) / (b.x - a.x)
                                 : side == 2 ? (0.0 - a.y) / (b.y - a.y)
                                             : (H - a.y) / (b.y - a.y);
                return a + t * (b - a);
            };
            next.clear();
            for (std::size_t i = 0; i < poly.size(); ++i) {
                const glm::dvec2& a = poly[i];
                const glm::dvec2& b = poly[(i + 1) % poly.size()];
                if (inside(a)) {
                    next.push_back(a);
                    if (!inside(b)) next.push_back(cut(a, b));
                } else if (inside(b)) {
                    next.push_back(cut(a, b));
                }
            }
            poly.swap(next);
        }
        double twice = 0.0;
        for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) twice += cross2(poly[j], poly[i]);
        area += 0.5 * std::abs(twice);
    }
    return area;
}

// Culling by contribution (issue lever): a beam's in-scattered power sigma_s Phi w (1 - exp(-sigma_t L)) /
// sigma_t (its flux times its mean edge transmittance, scattered along its mean edge length L; the phase
// function and the extinction towards the camera left out) is an intensity towards the camera that spreads
// over the beam's projected area, pixels x d^2 x the pixel's solid angle at its distance d: the mean radiance
// it adds where it adds any is that power over pixels x d^2, up to a factor common to all beams. Beams below
// `fraction` of the measures' 99th percentile are dropped from `beams`: the cost of the volume view is the pixels each beam
// spans. Beams in no pixel of the image (nothing to cost or add) and beams whose measure is not finite are
// kept and set no scale. Returns how many were dropped.
std::int64_t cull_faint_beams(std::vector<VolumeBeam>& beams, const std::vector<const Beam*>& source, double sigma_t,
                              const glm::dvec3& eye, int W, int H, double fraction) {
    if (!(fraction > 0.0) || beams.empty()) return 0;
    std::vector<double> mean_radiance(beams.size());
    for (std::size_t k = 0; k < beams.size(); ++k) {
        const Beam& b = *source[k];
        double length = 0.0, w = 0.0;
        glm::dvec3 centre(0.0);
        for (int i = 0; i < 3; ++i) {
            length += (b.ye[i] - b.ys[i]) * glm::length(b.dp[i]) / 3.0;
            w += b.w[i] / 3.0;
            centre += b.point(i, 0.5 * (b.ys[i] + b.ye[i])) / 3.0;
        }
        const double scattered = sigma_t > 0.0 ? -std::expm1(-sigma_t * length) / sigma_t : length;
        const double pixels = covered_pixels(*beams[k].pixels, W, H);
        const double d2 = glm::dot(centre - eye, centre - eye);
        const double r = b.flux * w * scattered / (std::max(1.0, pixels) * d2);
        mean_radiance[k] = pixels > 0.0 && std::isfinite(r) ? r : -1.0;
    }
    // The scale: the 99th percentile of the beams' measures (a few beams that pass next to the camera, whose d
    // is small, would otherwise set it alone).
    std::vector<double> sorted;
    for (double r : mean_radiance)
        if (r >= 0.0) sorted.push_back(r);
    if (sorted.empty()) return 0;
    const auto at = sorted.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), at, sorted.end());
    const double scale = *at;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < beams.size(); ++k)
        if (mean_radiance[k] < 0.0 || mean_radiance[k] >= fraction * scale) beams[kept++] = beams[k];
    const auto culled = static_cast<std::int64_t>(beams.size() - kept);
    beams.resize(kept);
    return culled;
}

}  // namespace

void accumulate_camera(const BeamSet& set, const Scene& scene, const CameraGBuffer& g, const RayTracer* tracer,
                       const AccumulateSettings& s, Image* surface, Image* volume, AccumulateStats& stats) {
    Camera camera = scene.camera;
    camera.width = g.width;
    camera.height = g.height;
    const CameraModel cam(camera);
    const MediumCoefficients cam_medium = medium_at(scene, g.medium_object);
    const bool want_volume = volume && cam_medium.scatters();
    if (surface) *surface = Image(g.width, g.height);
    if (volume) *volume = Image(g.width, g.height);
    Stopwatch clock;
    // Which beams take part: volume beams in the camera's medium, surface beams that end on a diffuse
    // surface. A volume beam's pixels are its hull's; a surface beam's are those of its end region only
    // (from end_tol of its length before its first edge's end to end_tol past its last): a diffuse
    // surface reaches into a beam where the beam's edges end on it, so a surface smaller than the finest
    // light-space cell inside a beam (which stops none of its edges) is not lit by that beam.
    const std::size_t nb = set.beams.size();
    std::vector<Coverage> vol_px(nb), surf_px(nb);
    std::vector<std::uint8_t> use(nb, 0);
    std::vector<std::uint8_t> clipped(nb, 0), fallback(nb, 0);
    // Each volume beam seen from the camera, once (what its fragments share).
    std::vector<RayBeam> seen(want_volume ? nb : 0);
    // The beams that end on one plane, box-filtered by coverage (surface_coverage.hpp); the point-in-beam
    // pass takes the others.
    Image plane_light;
    std::vector<std::uint8_t> by_coverage(nb, 0);
    double coverage_ms = 0.0;   // part of the camera's surface stage, not of the hulls'
    if (surface && s.surface_coverage) {
        Stopwatch coverage_clock;
        plane_light = Image(g.width, g.height);
        by_coverage = deposit_plane_beams(set, scene, g, cam, plane_light, stats.coverage_beams);
        coverage_ms = coverage_clock.ms();
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 32), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const Beam& b = set.beams[n];
            const bool vol = want_volume && b.medium == g.medium_object;
            const bool surf = surface && (set.ends[n] & kEndsOnDiffuse) && !by_coverage[n];
            if (!vol && !surf) continue;
            use[n] = static_cast<std::uint8_t>((vol ? 1 : 0) | (surf ? 2 : 0));
            bool c = false;
            if (vol) {
                seen[n] = RayBeam(b, cam.position, cam_medium);
                std::array<glm::dvec3, 6> corners;
                if (!hull_corners(b, s.hull, corners)) {
                    fallback[n] = 1;
                    hull_corners(b, HullType::Tight, corners);
                }
                vol_px[n] = coverage(b, s.hull, corners, cam, g.height, c);
            }
            if (surf) {
                const double tol = s.end_tol * (b.y1 - b.y0);
                const double ya = std::max(b.y0, std::min({b.ye[0], b.ye[1], b.ye[2]}) - tol);
                bool cs = false;
                surf_px[n] = slab_coverage(b, ya, b.y1 + tol, cam, g.height, cs);
                c = c || cs;
            }
            clipped[n] = c;
        }
    });
    for (std::size_t n = 0; n < nb; ++n) {
        if (!use[n]) continue;
        stats.near_clipped += clipped[n];
        stats.prism_fallback += fallback[n];
        stats.offscreen += (!(use[n] & 1) || vol_px[n].y_lo > vol_px[n].y_hi) &&
                           (!(use[n] & 2) || surf_px[n].y_lo > surf_px[n].y_hi);
    }
    stats.hulls_ms += clock.ms() - coverage_ms;
    stats.surface_ms += coverage_ms;
    if (surface) {
        clock.reset();
        const int bands = (g.height + kBandRows - 1) / kBandRows;
        std::vector<std::int64_t> fill(static_cast<std::size_t>(bands), 0), clamp(static_cast<std::size_t>(bands), 0);
        tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& br) {
            for (int band = br.begin(); band != br.end(); ++band) {
                const int r0 = band * kBandRows, r1 = std::min(g.height, r0 + kBandRows) - 1;
                BeamCounters counters;
                std::int64_t touched = 0;
                for (std::size_t n = 0; n < nb; ++n) {
                    const Coverage& cov = surf_px[n];
                    if (!(use[n] & 2) || cov.y_hi < r0 || cov.y_lo > r1) continue;
                    const Beam& b = set.beams[n];
                    const double sigma_t = medium_at(scene, b.medium).extinction();
                    for (int y = std::max(r0, cov.y_lo); y <= std::min(r1, cov.y_hi); ++y) {
                        int spans[3][2];
                        const int ns = row_spans(cov, y, g.width, false, spans);
                        for (int k = 0; k < ns; ++k)
                            for (int x = spans[k][0]; x <= spans[k][1]; ++x) {
                                ++touched;
                                const std::size_t i = g.index(x, y);
                                if (!g.covered[i]) continue;
                                surface->at(x, y) += static_cast<float>(surface_irradiance(
                                    b, sigma_t, glm::dvec3(g.position[i]), glm::dvec3(g.normal[i]), true, s.end_tol,
                                    counters));
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
        low_pass(*surface, g, s.filter);
        if (!plane_light.pixels.empty())
            for (std::size_t i = 0; i < surface->pixels.size(); ++i) surface->pixels[i] += plane_light.pixels[i];
        stats.surface_ms += clock.ms();
    }
    if (want_volume) {
        clock.reset();
        std::vector<VolumeBeam> beams;
        std::vector<const Beam*> source;
        for (std::size_t n = 0; n < nb; ++n)
            if (use[n] & 1) beams.push_back({&seen[n], &vol_px[n]}), source.push_back(&set.beams[n]);
        stats.volume_culled += cull_faint_beams(beams, source, cam_medium.extinction(), cam.position, g.width, g.height,
                                                s.volume.cull);
        VolumeStats vs;
        render_volume(beams, cam, g, tracer, s.volume, *volume, vs);
        stats.fill += vs.fill;
        stats.clamped += vs.clamped;
        stats.volume_rays += vs.rays;
        stats.volume_refined += vs.refined;
        stats.volume_edge_pixels += vs.edge_pixels;
        stats.volume_ms += clock.ms();
    }
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
    // edges are extended to its plane and the raster clips what falls outside it. That includes beams none of
    // whose edges ends on it: at a corner of a water surface as wide as the floor, the light through the
    // surface's last lattice row and column lands a hair outside the floor, and a beam spanning the corner
    // (all three edges just outside) covered 2.5 x 2.5 bins of floor that stayed dark (nrmse 0.0089 on a
    // weak `gaussian` caustic, all of it there).
    const glm::dvec3 plane_p = chart.point(0.5, 0.5), plane_n = chart.normal(0.5, 0.5);
    std::vector<std::uint8_t> deposited(nb, 0);
    const double far_out = 16.0 * std::max(W, H);   // bins
    for (std::size_t n = 0; n < nb; ++n) {
        const std::uint8_t e = set.ends[n];
        const bool all = e & kAllOnReceiver, extend = chart.is_plane() && (e & kReceiverOrNothing);
        if (!all && !extend) continue;
        const Beam& b = set.beams[n];
        const double sigma_t = medium_at(scene, b.medium).extinction();
        double arriving = 0.0;
        glm::dvec3 ends[3];
        double lengths[3];
        bool ok = true;
        // Beams that leave the receiver's edge, and beams the energy cut ended short of it, are carried on to its
        // plane (the camera's coverage pass places them alike, surface_coverage.hpp).
        const PlaneEnd how = all && (!chart.is_plane() || ends_on_plane(b, plane_p, plane_n)) ? PlaneEnd::Own : PlaneEnd::Extend;
        for (int i = 0; i < 3; ++i) ok = edge_end_on_plane(b, i, plane_p, plane_n, how, ends[i], lengths[i]) && ok;
        // An end carried far beyond the receiver (an edge nearly parallel to its plane) is not drawn here, as the
        // camera's coverage pass does not draw one (far_out there): the raster's float coordinates stay exact,
        // and a beam with an edge on the receiver falls to the point samples below.
        double u[3], v[3];
        for (int i = 0; i < 3 && ok; ++i) {
            chart.coords(ends[i], u[i], v[i]);
            ok = std::abs(u[i] * W) < far_out && std::abs(v[i] * H) < far_out;
        }
        if (!ok) continue;
        deposited[n] = 1;
        const auto base = static_cast<unsigned>(positions.size());
        for (int i = 0; i < 3; ++i) {
            positions.emplace_back(static_cast<float>(u[i] * W), static_cast<float>(v[i] * H));
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
