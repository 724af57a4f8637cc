#pragma once
// caustic_triangles' plugin class and the receiver chart its per-vertex passes use; the passes over the
// surface grid (resampling, triangle flux, refraction, triangle values) are in surface_passes.cpp, the
// rendering (dispersion samples, periodic textures, receiver and camera maps) in caustic_triangles.cpp.
#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>
#include <caustics/blocks/raster/raster.hpp>
#include <caustics/frame/receiver_chart.hpp>

namespace caustics::caustic_triangles {

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
const ObjectInstance* water_surface(const FrameGeometry& frame);

// The claim (accuracy_claim): nrmse <= kClaimError at grid >= kClaimMinGrid while no crest shadows the
// surface and the receiver lies at most kClaimMaxFocusFraction x the first focus depth down; past the first
// focus the grid the render uses there (fold_refine x grid) must be at least kClaimMinFoldGrid.
constexpr double kClaimError = 0.07, kClaimMaxFocusFraction = 3.0;
constexpr int kClaimMinGrid = 256, kClaimMinFoldGrid = 512;
constexpr int kMaxGrid = 4096;   // the `grid` parameter's upper limit

class CausticTriangles final : public Method {
public:
    explicit CausticTriangles(const ParamSet& p)
        : base_grid_(static_cast<int>(p.get_int("grid"))),
          fold_refine_(static_cast<int>(p.get_int("fold_refine"))),
          grid_(base_grid_),
          dispersion_samples_(static_cast<int>(p.get_int("dispersion_samples"))),
          absorption_(p.get_bool("absorption")),
          coverage_(p.get_enum("coverage") == "center" ? RasterCoverage::PixelCenter : RasterCoverage::Area) {}

    Capability capabilities(const Scene& scene) const override;
    // Periodic textures: any scene this method supports (the caller checks that the surface tiles).
    Capability texture_capability(const Scene& scene) const override { return capabilities(scene); }
    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override;
    AccuracyClaim accuracy_claim(const FrameGeometry& frame) const override;

private:
    struct Counters {
        std::int64_t lost = 0, folded = 0, not_converged = 0;
    };
    void ensure_topology();
    // The grid the receiver is drawn at where the base grid's map folds: fold_refine x grid, at most the
    // largest grid the `grid` parameter accepts.
    int grid_past_focus() const { return std::min(base_grid_ * fold_refine_, kMaxGrid); }
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
    // samples' average, `rgb` their spectral sum (dispersion only); `periodic` wraps toroidally. With
    // `stop_on_fold`, returns false as soon as a sample's map folds, before drawing that sample.
    bool draw_dispersion_samples(const FrameGeometry& frame, const ChartMap& map, int W, int H, double scale,
                                 bool periodic, Image& scalar, Image& rgb, Counters& counters,
                                 RasterStats& raster_stats, double& refract_ms, double& raster_ms,
                                 bool stop_on_fold = false);

    int base_grid_;                        // the `grid` parameter
    int fold_refine_;                      // the `fold_refine` parameter (1: none)
    int grid_;                             // the grid of the pass being drawn
    int dispersion_samples_;
    bool absorption_;
    RasterCoverage coverage_;

    // Per-frame buffers, kept between renders (no allocation after the first frame of a given size).
    std::vector<glm::uvec3> triangles_;    // the surface grid's triangles (fixed topology at grid_)
    std::vector<glm::uvec3> other_triangles_;   // the other grid's (base or fold), swapped in when it is drawn
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

}  // namespace caustics::caustic_triangles
