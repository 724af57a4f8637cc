// caustic_triangles: the passes over the surface grid, per frame: bilinear resampling of the water surface,
// the flux through each surface triangle, the refraction of every vertex onto the receiver (double
// precision with a secant search on height-field floors, single precision on planes) and the triangles'
// values for the raster.
#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "caustic_triangles.hpp"
#include "plane_refraction.hpp"

namespace caustics::caustic_triangles {

// Bilinear resampling of the surface at grid x grid vertices spanning the height field's rectangle.
void CausticTriangles::resample_surface(const HeightField& hf) {
    const int g = grid_;
    xs_.resize(static_cast<std::size_t>(g));
    ys_.resize(static_cast<std::size_t>(g));
    height_.resize(static_cast<std::size_t>(g) * g);
    gradient_.resize(static_cast<std::size_t>(g) * g);
    struct Tap {
        int i0;
        float f;
    };
    auto taps = [g](int n, std::vector<Tap>& out) {
        out.resize(static_cast<std::size_t>(g));
        for (int k = 0; k < g; ++k) {
            const double u = static_cast<double>(k) * (n - 1) / (g - 1);
            const int i0 = std::clamp(static_cast<int>(std::floor(u)), 0, std::max(0, n - 2));
            out[static_cast<std::size_t>(k)] = {i0, static_cast<float>(n > 1 ? u - i0 : 0.0)};
        }
    };
    std::vector<Tap> tx, ty;
    taps(hf.nx, tx);
    taps(hf.ny, ty);
    const glm::dvec2 extent = hf.extent();
    for (int k = 0; k < g; ++k) {
        xs_[static_cast<std::size_t>(k)] = hf.origin.x + extent.x * k / (g - 1);
        ys_[static_cast<std::size_t>(k)] = hf.origin.y + extent.y * k / (g - 1);
    }
    if (hf.nx == g && hf.ny == g) {   // the grid is the height field's own: every tap has weight 1
        std::copy(hf.height.begin(), hf.height.end(), height_.begin());
        std::copy(hf.gradient.begin(), hf.gradient.end(), gradient_.begin());
        return;
    }
    const int dx = hf.nx > 1 ? 1 : 0;
    const int dy = hf.ny > 1 ? hf.nx : 0;
    tbb::parallel_for(tbb::blocked_range<int>(0, g, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const Tap b = ty[static_cast<std::size_t>(j)];
            for (int i = 0; i < g; ++i) {
                const Tap a = tx[static_cast<std::size_t>(i)];
                const std::size_t k00 = static_cast<std::size_t>(b.i0) * hf.nx + a.i0;
                const std::size_t k10 = k00 + dx, k01 = k00 + dy, k11 = k01 + dx;
                const float w00 = (1 - a.f) * (1 - b.f), w10 = a.f * (1 - b.f), w01 = (1 - a.f) * b.f, w11 = a.f * b.f;
                const std::size_t out = static_cast<std::size_t>(j) * g + i;
                height_[out] = w00 * hf.height[k00] + w10 * hf.height[k10] + w01 * hf.height[k01] + w11 * hf.height[k11];
                gradient_[out] = w00 * hf.gradient[k00] + w10 * hf.gradient[k10] + w01 * hf.gradient[k01] +
                                 w11 * hf.gradient[k11];
            }
        }
    });
}

// Flux through each surface triangle: E0 times its area projected perpendicular to the light (the
// triangle's area vector dotted with -L); triangles facing away from the light get none.
void CausticTriangles::compute_triangle_flux(const glm::dvec3& light_dir, double e0) {
    const int g = grid_;
    flux_.resize(triangles_.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, g - 1, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j) {
            for (int i = 0; i + 1 < g; ++i) {
                const std::size_t t = 2 * (static_cast<std::size_t>(j) * (g - 1) + i);
                // The cell's corners (ensure_topology: {v00, v10, v11}, {v00, v11, v01}) span dx, dy
                // horizontally: the cross products of the edge vectors from v00 in closed form.
                const std::size_t v00 = static_cast<std::size_t>(j) * g + i, v01 = v00 + g;
                const double dx = xs_[i + 1] - xs_[i], dy = ys_[j + 1] - ys_[j];
                const double h00 = height_[v00], h10 = height_[v00 + 1], h01 = height_[v01], h11 = height_[v01 + 1];
                const glm::dvec3 area_vector[2] = {0.5 * glm::dvec3(-(h10 - h00) * dy, dx * (h10 - h11), dx * dy),
                                                   0.5 * glm::dvec3(dy * (h01 - h11), -dx * (h01 - h00), dx * dy)};
                for (int half = 0; half < 2; ++half)
                    flux_[t + half] = static_cast<float>(e0 * std::max(0.0, -glm::dot(area_vector[half], light_dir)));
            }
        }
    });
}

// Refracts every surface vertex (exact Snell with the vertex normal) and intersects the receiver.
CausticTriangles::Counters CausticTriangles::refract_vertices(const FrameGeometry& frame, const ChartMap& map,
                                                              int width, int height, double ior, double absorption,
                                                              const glm::dvec3& light_dir, bool periodic_target) {
    const int g = grid_;
    const bool fresnel = frame.scene->fresnel;
    const double eta = 1.0 / ior;   // air above, water below
    image_.resize(static_cast<std::size_t>(g) * g);
    weight_.resize(image_.size());
    if (map.plane) return refract_to_plane(map, width, height, ior, absorption, light_dir, fresnel, periodic_target);
    tbb::combinable<Counters> counters;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    tbb::parallel_for(tbb::blocked_range<int>(0, g, 8), [&](const tbb::blocked_range<int>& rows) {
        Counters& c = counters.local();
        for (int j = rows.begin(); j != rows.end(); ++j) {
            for (int i = 0; i < g; ++i) {
                const std::size_t v = static_cast<std::size_t>(j) * g + i;
                const glm::dvec2 grad(gradient_[v]);
                const glm::dvec3 n = glm::normalize(glm::dvec3(-grad.x, -grad.y, 1.0));
                const double cos_i = -glm::dot(light_dir, n);
                image_[v] = {nan, nan};
                weight_[v] = 0.0f;
                if (!(cos_i > 0.0)) {   // the vertex faces away from the light
                    ++c.lost;
                    continue;
                }
                const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
                const double cos_t = std::sqrt(1.0 - sin2_t);   // no total internal reflection entering water
                const glm::dvec3 dir = eta * light_dir + (eta * cos_i - cos_t) * n;
                double transmittance = 1.0;
                if (fresnel) {   // unpolarised Fresnel transmittance
                    const double rs = (cos_i - ior * cos_t) / (cos_i + ior * cos_t);
                    const double rp = (ior * cos_i - cos_t) / (ior * cos_i + cos_t);
                    transmittance = 1.0 - 0.5 * (rs * rs + rp * rp);
                }
                const glm::dvec3 p(xs_[static_cast<std::size_t>(i)], ys_[static_cast<std::size_t>(j)], height_[v]);
                double t = -1.0;
                if (map.plane) {
                    const double denom = glm::dot(map.normal, dir);
                    if (std::abs(denom) > 1e-12) t = glm::dot(map.normal, map.origin - p) / denom;
                } else if (dir.z < 0.0) {
                    // Height-field floor: secant iterations on f(t) = z(t) - h(x(t), y(t)), started from
                    // the floor height below the vertex and one fixed-point step.
                    auto f = [&](double tt) {
                        const glm::dvec3 q = p + tt * dir;
                        return q.z - map.floor->sample_height(q.x, q.y);
                    };
                    double t0 = (map.floor->sample_height(p.x, p.y) - p.z) / dir.z;
                    double f0 = f(t0);
                    double t1 = t0 - f0 / dir.z;
                    double f1 = f(t1);
                    bool converged = std::abs(f1) < 1e-7;
                    for (int it = 0; it < 12 && !converged; ++it) {
                        const double slope = (f1 - f0) / (t1 - t0);
                        const double t2 = (std::isfinite(slope) && std::abs(slope) > 1e-12) ? t1 - f1 / slope
                                                                                          : t1 - f1 / dir.z;
                        t0 = t1;
                        f0 = f1;
                        t1 = t2;
                        f1 = f(t1);
                        converged = std::abs(f1) < 1e-7;
                    }
                    if (!converged) ++c.not_converged;
                    t = t1;
                }
                if (!(t > 0.0) || !std::isfinite(t)) {
                    ++c.lost;
                    continue;
                }
                const glm::dvec2 st = map.coords(p + t * dir);
                // A periodic target (texture tile) wraps: a point outside the tile is not lost.
                if (!periodic_target && !(st.x >= 0.0 && st.x <= 1.0 && st.y >= 0.0 && st.y <= 1.0)) ++c.lost;
                image_[v] = {static_cast<float>(st.x * width), static_cast<float>(st.y * height)};
                weight_[v] = static_cast<float>(absorption != 0.0 ? transmittance * std::exp(-absorption * t)
                                                                  : transmittance);   // exp(-0) == 1
            }
        }
    });
    Counters total;
    counters.combine_each([&](const Counters& c) {
        total.lost += c.lost;
        total.not_converged += c.not_converged;
    });
    return total;
}

// Plane receiver (the real-time case): refract_vertices in single precision (plane_refraction.hpp), a
// straight loop over the grid with the vertices taken relative to the plane's origin.
CausticTriangles::Counters CausticTriangles::refract_to_plane(const ChartMap& map, int width, int height, double ior,
                                                              double absorption, const glm::dvec3& light_dir,
                                                              bool fresnel, bool periodic_target) {
    const int g = grid_;
    caustic_triangles::PlaneRefraction c;
    c.light = glm::vec3(light_dir);
    c.eta = static_cast<float>(1.0 / ior);
    c.ior = static_cast<float>(ior);
    c.fresnel = fresnel;
    c.absorption = static_cast<float>(absorption);
    c.normal = glm::vec3(map.normal);
    c.dual_s = glm::vec3(map.dual_s);
    c.dual_t = glm::vec3(map.dual_t);
    c.width = static_cast<float>(width);
    c.height = static_cast<float>(height);
    xr_.resize(static_cast<std::size_t>(g));
    for (std::size_t i = 0; i < xr_.size(); ++i) xr_[i] = static_cast<float>(xs_[i] - map.origin.x);
    const float zr = static_cast<float>(-map.origin.z);
    constexpr int kRun = 64;   // vertices per run of each half (plane_refraction.hpp)
    tbb::combinable<Counters> counters;
    tbb::parallel_for(tbb::blocked_range<int>(0, g, 8), [&](const tbb::blocked_range<int>& rows) {
        std::int64_t lost = 0;
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const float yr = static_cast<float>(ys_[static_cast<std::size_t>(j)] - map.origin.y);
            const std::size_t row = static_cast<std::size_t>(j) * g;
            for (int i0 = 0; i0 < g; i0 += kRun) {
                const int n = std::min(kRun, g - i0);
                caustic_triangles::RefractedRay rays[kRun];
                for (int k = 0; k < n; ++k) rays[k] = caustic_triangles::refract_ray(c, gradient_[row + i0 + k]);
                for (int k = 0; k < n; ++k) {
                    const int i = i0 + k;
                    const std::size_t v = row + i;
                    const caustic_triangles::RefractedVertex rv =
                        caustic_triangles::intersect_plane(c, rays[k], glm::vec3(xr_[i], yr, height_[v] + zr));
                    image_[v] = rv.image;
                    weight_[v] = rv.weight;
                    // A periodic target (texture tile) wraps: a point outside the tile is not lost.
                    lost += (rv.lost || (!periodic_target && rv.outside)) ? 1 : 0;
                }
            }
        }
        counters.local().lost += lost;
    });
    Counters total;
    counters.combine_each([&](const Counters& k) { total.lost += k.lost; });
    return total;
}

// Triangle value for the raster: flux * mean vertex weight * scale (1 / bin area on planes, whose bins
// all have the same area), divided by the image area in bins for centre sampling. Triangles with a
// vertex that missed get 0 (the raster skips them).
void CausticTriangles::triangle_values(const ChartMap& map, double scale, Counters& counters) {
    const int g = grid_;
    values_.resize(triangles_.size());
    const bool per_centre = coverage_ == RasterCoverage::PixelCenter;
    std::atomic<std::int64_t> folded{0};
    auto value_of = [&](std::size_t t, std::size_t ia, std::size_t ib, std::size_t ic, std::int64_t& local_folded) {
        const glm::vec2 a = image_[ia], b = image_[ib], c = image_[ic];
        const float w = weight_[ia] + weight_[ib] + weight_[ic];
        const bool valid = std::isfinite(a.x) && std::isfinite(b.x) && std::isfinite(c.x);
        values_[t] = valid ? static_cast<float>(flux_[t] * (w / 3.0f) * scale) : 0.0f;
        if (valid && flux_[t] > 0.0f) {
            const double signed_area = 0.5 * ((double(b.x) - a.x) * (double(c.y) - a.y) -
                                              (double(b.y) - a.y) * (double(c.x) - a.x));
            if (signed_area * map.orientation < 0.0) ++local_folded;
            // Centre sampling writes a value per covered bin: the irradiance, i.e. flux / image area (not
            // flux conserving; zero-area images cover no centre).
            if (per_centre)
                values_[t] = signed_area != 0.0 ? static_cast<float>(values_[t] / std::abs(signed_area)) : 0.0f;
        }
    };
    // The grid's cells in order (ensure_topology: {v00, v10, v11}, {v00, v11, v01}).
    tbb::parallel_for(tbb::blocked_range<int>(0, g - 1, 16), [&](const tbb::blocked_range<int>& rows) {
        std::int64_t local_folded = 0;
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i + 1 < g; ++i) {
                const std::size_t t = 2 * (static_cast<std::size_t>(j) * (g - 1) + i);
                const std::size_t v00 = static_cast<std::size_t>(j) * g + i, v01 = v00 + g;
                value_of(t, v00, v00 + 1, v01 + 1, local_folded);
                value_of(t + 1, v00, v01 + 1, v01, local_folded);
            }
        folded += local_folded;
    });
    counters.folded += folded.load();
}

}  // namespace caustics::caustic_triangles
