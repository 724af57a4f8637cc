// caustic_triangles: the area-ratio method of Stam, "Periodic Caustic Textures" (shared/papers/004):
// refract every vertex of the water surface grid, intersect the refracted rays with the receiver and
// shade each surface triangle's image with irradiance = (flux through the surface triangle) / (area of
// its image). "The intensity is proportional to the area of the triangle" (ibid.), made radiometric:
// flux = E0 * (triangle area projected perpendicular to the light) * transmittance * exp(-Ka d).
// The raster (harness/raster.hpp, Area coverage) splits each triangle's flux exactly among the bins it
// covers, so nothing aliases, folded triangles (caustic fold-overs) still deposit their flux and
// degenerate images deposit it without dividing by zero.
// Dispersion (ibid., last paragraph): the image is rendered for several indices in
// [ior, ior + dispersion] and accumulated into RGB with a spectral ramp.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "method.hpp"
#include "plane_refraction.hpp"
#include "raster.hpp"
#include "registry.hpp"
#include "spectral_ramp.hpp"
#include "timing.hpp"

namespace caustics {
namespace {

// One dispersion sample's map joins the scalar map (the mean over samples, the quantity the reference
// estimates by sampling the index uniformly) and the RGB map (weighted by the sample's spectral ramp).
void add_spectral_sample(const Image& sample, float mean_weight, const std::array<float, 3>& rgb_weight,
                         Image& scalar, Image& rgb) {
    tbb::parallel_for(tbb::blocked_range<int>(0, sample.height, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < sample.width; ++x) {
                const float e = sample.at(x, y);
                scalar.at(x, y) += mean_weight * e;
                for (int ch = 0; ch < 3; ++ch) rgb.at(x, y, ch) += rgb_weight[ch] * e;
            }
    });
}

using caustic_triangles::spectral_weights;

// The receiver's chart as an affine map (plane) or an x-y rectangle (height field), read once per
// render from ReceiverChart::point so the per-vertex work needs no virtual or out-of-line call.
struct ChartMap {
    bool plane = true;
    glm::dvec3 origin{0.0}, normal{0, 0, 1};
    glm::dvec3 dual_s{1, 0, 0}, dual_t{0, 1, 0};  // s = dual_s . (q - origin), t = dual_t . (q - origin)
    const HeightField* floor = nullptr;           // height-field receiver
    double orientation = 1.0;  // sign of the chart's (s, t) orientation seen from above (folds flip it)

    // A plane through `o` spanned by the full edge vectors U, V (periodic textures: one tile).
    ChartMap(const glm::dvec3& o, const glm::dvec3& U, const glm::dvec3& V) { set_plane(o, U, V); }
    void set_plane(const glm::dvec3& o, const glm::dvec3& U, const glm::dvec3& V) {
        plane = true;
        origin = o;
        normal = glm::normalize(glm::cross(U, V));
        const double uu = glm::dot(U, U), uv = glm::dot(U, V), vv = glm::dot(V, V);
        const double det = uu * vv - uv * uv;
        dual_s = (vv * U - uv * V) / det;
        dual_t = (uu * V - uv * U) / det;
        orientation = glm::cross(U, V).z >= 0.0 ? 1.0 : -1.0;
    }

    explicit ChartMap(const ReceiverChart& chart, const FrameGeometry& frame) {
        plane = chart.is_plane();
        origin = chart.point(0.0, 0.0);
        const glm::dvec3 U = chart.point(1.0, 0.0) - origin, V = chart.point(0.0, 1.0) - origin;
        if (plane) {
            set_plane(origin, U, V);
        } else {
            dual_s = {1.0 / U.x, 0.0, 0.0};
            dual_t = {0.0, 1.0 / V.y, 0.0};
            floor = frame.receiver().heightfield.get();
            orientation = (U.x > 0.0) == (V.y > 0.0) ? 1.0 : -1.0;
        }
    }
    glm::dvec2 coords(const glm::dvec3& q) const {
        const glm::dvec3 r = q - origin;
        return {glm::dot(r, dual_s), glm::dot(r, dual_t)};
    }
};

// The height-field dielectric whose caustics this method draws (capabilities() guarantees one).
const ObjectInstance* water_surface(const FrameGeometry& frame) {
    const ObjectInstance* water = nullptr;
    for (const ObjectInstance& o : frame.objects)
        if (o.heightfield && o.object->material.type == MaterialType::Dielectric) water = &o;
    return water;
}

class CausticTriangles final : public Method {
public:
    explicit CausticTriangles(const ParamSet& p)
        : grid_(static_cast<int>(p.get_int("grid"))),
          dispersion_samples_(static_cast<int>(p.get_int("dispersion_samples"))),
          absorption_(p.get_bool("absorption")),
          coverage_(p.get_enum("coverage") == "center" ? RasterCoverage::PixelCenter : RasterCoverage::Area) {}

    Capability capabilities(const Scene& scene) const override;
    // Periodic textures: any scene this method supports (the caller checks that the surface tiles).
    Capability texture_capability(const Scene& scene) const override { return capabilities(scene); }
    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override;

private:
    struct Counters {
        std::int64_t lost = 0, folded = 0, not_converged = 0;
    };
    void ensure_topology();
    void render_texture(const FrameGeometry& frame, const TextureRequest& request, CausticOutput& out);
    void resample_surface(const HeightField& hf);
    void compute_triangle_flux(const glm::dvec3& light_dir, double e0);
    Counters refract_vertices(const FrameGeometry& frame, const ChartMap& map, int width, int height,
                              double ior, double absorption, const glm::dvec3& light_dir,
                              bool periodic_target = false);
    Counters refract_to_plane(const ChartMap& map, int width, int height, double ior, double absorption,
                              const glm::dvec3& light_dir, bool fresnel, bool periodic_target);
    void triangle_values(const ChartMap& map, double scale, Counters& counters);
    // One pass per dispersion sample (one pass without dispersion): refract every vertex with that
    // sample's index, turn the triangles into flux values and rasterise them. `scalar` receives the
    // samples' average, `rgb` their spectral sum (dispersion only); `periodic` wraps toroidally.
    void draw_dispersion_samples(const FrameGeometry& frame, const ChartMap& map, int W, int H, double scale,
                                 bool periodic, Image& scalar, Image& rgb, Counters& counters,
                                 RasterStats& raster_stats, double& refract_ms, double& raster_ms);

    int grid_;
    int dispersion_samples_;
    bool absorption_;
    RasterCoverage coverage_;

    // Per-frame buffers, kept between renders (no allocation after the first frame of a given size).
    std::vector<glm::uvec3> triangles_;    // the surface grid's triangles (fixed topology)
    std::vector<double> xs_, ys_;          // world x of grid column i, y of row j
    std::vector<float> xr_;                // plane receiver: xs_ relative to the plane's origin
    std::vector<float> height_;            // resampled surface, grid x grid
    std::vector<glm::vec2> gradient_;
    std::vector<float> flux_;              // incident flux per surface triangle [W]
    std::vector<glm::vec2> image_;         // receiver pixel coordinates of each vertex's refracted ray
    std::vector<float> weight_;            // per vertex: Fresnel transmittance * exp(-Ka d)
    std::vector<float> values_;            // per triangle: flux * weight (/ bin area on planes)
    Image sample_map_;                     // dispersion: one index's map
    TriangleRaster raster_;
};

Capability CausticTriangles::capabilities(const Scene& scene) const {
    const std::string need = "needs a height-field water surface and a directional light";
    if (scene.lights.size() != 1 || scene.lights[0].type != LightType::Directional)
        return Capability::no(need + " (exactly one directional light; point lights are not supported)");
    if (scene.lights[0].direction.z >= 0.0)
        return Capability::no(need + " (the light must shine down onto the water)");
    int water = 0;
    for (const Object& o : scene.objects) {
        if (!o.material.is_specular()) continue;
        if (o.shape == ShapeType::HeightField && o.material.type == MaterialType::Dielectric) {
            ++water;
            continue;
        }
        return Capability::no(need + " (object '" + o.name +
                              "' is a specular sphere, mesh, box, plane or mirror: not supported)");
    }
    if (water != 1) return Capability::no(need + " (exactly one dielectric height field)");
    const Object& receiver = scene.receiver_object();
    if (receiver.shape != ShapeType::Plane && receiver.shape != ShapeType::HeightField)
        return Capability::no(need + " (the receiver must be a plane or a height field)");
    return Capability::yes();
}

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

void CausticTriangles::ensure_topology() {
    const int g = grid_;
    if (triangles_.size() == 2 * static_cast<std::size_t>(g - 1) * (g - 1)) return;
    // Two counter-clockwise (seen from above) triangles per cell; fixed for the method's life.
    triangles_.clear();
    for (unsigned j = 0; j + 1 < static_cast<unsigned>(g); ++j)
        for (unsigned i = 0; i + 1 < static_cast<unsigned>(g); ++i) {
            const unsigned v00 = j * g + i, v10 = v00 + 1, v01 = v00 + g, v11 = v01 + 1;
            triangles_.push_back({v00, v10, v11});
            triangles_.push_back({v00, v11, v01});
        }
}

void CausticTriangles::draw_dispersion_samples(const FrameGeometry& frame, const ChartMap& map, int W, int H,
                                               double scale, bool periodic, Image& scalar, Image& rgb,
                                               Counters& counters, RasterStats& raster_stats, double& refract_ms,
                                               double& raster_ms) {
    const ObjectInstance* water = water_surface(frame);
    const Material& material = water->object->material;
    const glm::dvec3 light_dir = glm::normalize(frame.scene->lights[0].direction);
    const double absorption = absorption_ ? material.absorption : 0.0;
    const bool dispersive = material.dispersion > 0.0;
    const int samples = dispersive ? dispersion_samples_ : 1;
    const auto weights = dispersive ? spectral_weights(samples) : std::vector<std::array<float, 3>>{};
    if (dispersive && (sample_map_.width != W || sample_map_.height != H)) sample_map_ = Image(W, H);
    Stopwatch clock;
    for (int k = 0; k < samples; ++k) {
        // Midpoint rule over [ior, ior + dispersion]: the mean of the samples estimates the reference's
        // uniform average over that range.
        const double ior = material.ior + (dispersive ? material.dispersion * (k + 0.5) / samples : 0.0);
        clock.reset();
        const Counters c = refract_vertices(frame, map, W, H, ior, absorption, light_dir, periodic);
        counters.lost += c.lost;
        counters.not_converged += c.not_converged;
        triangle_values(map, scale, counters);
        refract_ms += clock.ms();

        clock.reset();
        Image& target = dispersive ? sample_map_ : scalar;
        const RasterStats st = raster_.draw({image_, triangles_, values_, {}}, {coverage_, periodic, false}, target);
        raster_stats.nonfinite += st.nonfinite;
        raster_stats.too_large += st.too_large;
        if (dispersive)
            add_spectral_sample(sample_map_, 1.0f / samples, weights[static_cast<std::size_t>(k)], scalar, rgb);
        raster_ms += clock.ms();
    }
}

// Periodic caustic texture (Stam, "Periodic Caustic Textures"): the surface grid spans exactly one
// spatial period (its last row and column repeat the first on a periodic surface), every vertex is
// refracted onto the horizontal plane `depth` below the base level, and the triangles are accumulated
// toroidally into the tile (a triangle leaving one side re-enters on the other), so the flux through the
// tile is conserved: mean texture = E0 cos(theta_i) * transmittance * absorption.
void CausticTriangles::render_texture(const FrameGeometry& frame, const TextureRequest& request, CausticOutput& out) {
    const Scene& scene = *frame.scene;
    const ObjectInstance* water = water_surface(frame);
    const HeightField& hf = *water->heightfield;
    const Material& material = water->object->material;
    const glm::dvec3 light_dir = glm::normalize(scene.lights[0].direction);
    const int W = request.width, H = request.height;
    if (W <= 0 || H <= 0) throw std::invalid_argument("caustic_triangles: texture size must be positive");

    Stopwatch clock;
    ensure_topology();
    resample_surface(hf);
    compute_triangle_flux(light_dir, scene.lights[0].irradiance);
    const glm::dvec2 size = hf.extent();
    const double receiver_z = water->object->heightfield.base_height - request.depth;
    const ChartMap map(glm::dvec3(hf.origin.x, hf.origin.y, receiver_z), glm::dvec3(size.x, 0.0, 0.0),
                       glm::dvec3(0.0, size.y, 0.0));
    const double scale = static_cast<double>(W) * H / (size.x * size.y);   // 1 / texel area
    double refract_ms = clock.ms(), raster_ms = 0.0;
    Counters counters;
    RasterStats raster_stats;
    out.texture = Image(W, H);
    if (material.dispersion > 0.0) out.texture_rgb = Image(W, H, 3);
    draw_dispersion_samples(frame, map, W, H, scale, true, out.texture, out.texture_rgb, counters, raster_stats,
                            refract_ms, raster_ms);
    out.stages_ms.emplace_back("texture_refract", refract_ms);
    out.stages_ms.emplace_back("texture_raster", raster_ms);
    out.health.add("lost_samples", counters.lost);
    out.health.add("folded_triangles", counters.folded);
    out.health.add("nonfinite", raster_stats.nonfinite);
    // Triangles spanning more than 3 x 3 tiles (their flux is lost): a depth far beyond the focus.
    out.health.add("texture_too_large", raster_stats.too_large);
    if (!hf.periodic) out.health.add("nonperiodic_surface", 1);
}

CausticOutput CausticTriangles::render(const FrameGeometry& frame, const RenderRequest& request) {
    CausticOutput out;
    const Scene& scene = *frame.scene;
    const Capability cap = capabilities(scene);
    if (!cap.supported) throw std::runtime_error("caustic_triangles: " + cap.reason);
    if (request.texture) {
        render_texture(frame, *request.texture, out);
        if (!request.receiver && !request.camera) return out;
    }
    const ReceiverChart* chart = request.receiver;
    if (!chart) throw std::invalid_argument("caustic_triangles: needs the receiver chart (camera lookups read it)");

    const ObjectInstance* water = water_surface(frame);
    const Material& material = water->object->material;
    const glm::dvec3 light_dir = glm::normalize(scene.lights[0].direction);
    const int W = chart->width(), H = chart->height();

    Stopwatch clock;
    ensure_topology();
    resample_surface(*water->heightfield);
    compute_triangle_flux(light_dir, scene.lights[0].irradiance);
    const ChartMap map(*chart, frame);
    const double scale = map.plane ? 1.0 / chart->bin_area(0, 0) : 1.0;
    double refract_ms = clock.ms(), raster_ms = 0.0;
    const bool dispersive = material.dispersion > 0.0;
    Counters counters;
    RasterStats raster_stats;
    out.receiver = Image(W, H);
    if (dispersive) out.receiver_rgb = Image(W, H, 3);
    draw_dispersion_samples(frame, map, W, H, scale, false, out.receiver, out.receiver_rgb, counters, raster_stats,
                            refract_ms, raster_ms);
    if (!map.plane) {   // height-field receiver: flux per bin -> irradiance by each bin's surface area
        clock.reset();
        tbb::parallel_for(tbb::blocked_range<int>(0, H, 16), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y != rows.end(); ++y)
                for (int x = 0; x < W; ++x) {
                    const float inv = static_cast<float>(1.0 / chart->bin_area(x, y));
                    out.receiver.at(x, y) *= inv;
                    if (dispersive)
                        for (int ch = 0; ch < 3; ++ch) out.receiver_rgb.at(x, y, ch) *= inv;
                }
        });
        raster_ms += clock.ms();
    }

    std::int64_t not_covered = 0;
    if (request.camera) {
        // Deferred lookup: bilinear in the receiver map at the pixel's chart coordinates.
        clock.reset();
        const CameraGBuffer& gb = *request.camera;
        out.camera = Image(gb.width, gb.height);
        const int receiver_index = scene.receiver.object_index;
        std::atomic<std::int64_t> uncovered{0};
        tbb::parallel_for(tbb::blocked_range<int>(0, gb.height, 8), [&](const tbb::blocked_range<int>& rows) {
            std::int64_t local = 0;
            for (int y = rows.begin(); y != rows.end(); ++y)
                for (int x = 0; x < gb.width; ++x) {
                    const std::size_t idx = gb.index(x, y);
                    if (!gb.covered[idx]) continue;
                    if (gb.object[idx] != receiver_index) {   // walls: this method only shades the receiver
                        ++local;
                        continue;
                    }
                    const glm::dvec2 st = map.coords(glm::dvec3(gb.position[idx]));
                    const double fx = std::clamp(st.x * W - 0.5, 0.0, W - 1.0);
                    const double fy = std::clamp(st.y * H - 0.5, 0.0, H - 1.0);
                    const int x0 = std::min(static_cast<int>(fx), W - 1), y0 = std::min(static_cast<int>(fy), H - 1);
                    const int x1 = std::min(x0 + 1, W - 1), y1 = std::min(y0 + 1, H - 1);
                    const double ax = fx - x0, ay = fy - y0;
                    const Image& r = out.receiver;
                    out.camera.at(x, y) = static_cast<float>(
                        (1 - ay) * ((1 - ax) * r.at(x0, y0) + ax * r.at(x1, y0)) +
                        ay * ((1 - ax) * r.at(x0, y1) + ax * r.at(x1, y1)));
                }
            uncovered += local;
        });
        not_covered = uncovered.load();
        out.stages_ms.emplace_back("camera", clock.ms());
    }
    out.stages_ms.insert(out.stages_ms.begin(), {{"refract", refract_ms}, {"raster", raster_ms}});

    out.health.add("lost_samples", counters.lost);
    out.health.add("folded_triangles", counters.folded);
    out.health.add("nonfinite", raster_stats.nonfinite);
    out.health.add("not_converged", counters.not_converged);
    out.health.add("not_covered", not_covered);
    return out;
}

MethodInfo caustic_triangles_info() {
    MethodInfo info;
    info.name = "caustic_triangles";
    info.doc =
        "Refracted surface triangles shaded by area ratio (Stam, Periodic Caustic Textures): every vertex of "
        "the water grid is refracted onto the receiver and each triangle deposits its flux over its image "
        "(exact area coverage); dispersion by several indices and a spectral ramp. Height-field water, "
        "directional light; walls are not covered. Periodic textures (caustics synth): the surface over one "
        "period is refracted onto a plane at the texture depth and its triangles are accumulated toroidally "
        "(flux conserving over the tile).";
    info.radiometric = true;
    info.params = {
        {"grid", ParamType::Int, "256", 2, 4096, {},
         "surface grid resolution (vertices per side) the water surface is resampled at"},
        {"iterations", ParamType::Int, "1", 1, 1, {}, "no meaning for this single-pass method; only 1 is valid"},
        {"dispersion_samples", ParamType::Int, "8", 2, 64, {},
         "indices (wavelengths) rendered in [ior, ior+dispersion] when the material has dispersion"},
        {"absorption", ParamType::Bool, "true", 0, 0, {}, "apply Beer-Lambert absorption over the path in water"},
        {"coverage", ParamType::Enum, "area", 0, 0, {"area", "center"},
         "area: exact flux-conserving area coverage; center: pixel-centre sampling (aliases below bin size)"},
    };
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<CausticTriangles>(p); };
    return info;
}

}  // namespace

CAUSTICS_REGISTER_METHOD(caustic_triangles_info);

}  // namespace caustics
