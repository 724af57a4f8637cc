// caustic_triangles: the area-ratio method of Stam, "Periodic Caustic Textures" (docs/papers.md):
// refract every vertex of the water surface grid, intersect the refracted rays with the receiver and
// shade each surface triangle's image with irradiance = (flux through the surface triangle) / (area of
// its image). "The intensity is proportional to the area of the triangle" (ibid.), made radiometric:
// flux = E0 * (triangle area projected perpendicular to the light) * transmittance * exp(-Ka d).
// The raster (harness/blocks/raster/raster.hpp, Area coverage) splits each triangle's flux exactly among the bins it
// covers, so nothing aliases, folded triangles (caustic fold-overs) still deposit their flux and
// degenerate images deposit it without dividing by zero.
// Dispersion (ibid., last paragraph): the image is rendered for several indices in
// [ior, ior + dispersion] and accumulated into RGB with a spectral ramp.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/regime/first_focus.hpp>

#include "caustic_triangles.hpp"
#include <caustics/api/method.hpp>
#include <caustics/blocks/raster/raster.hpp>
#include <caustics/api/registry.hpp>
#include "spectral_ramp.hpp"
#include <caustics/util/timing.hpp>

namespace caustics {
namespace caustic_triangles {
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


}  // namespace

const ObjectInstance* water_surface(const FrameGeometry& frame) {
    const ObjectInstance* water = nullptr;
    for (const ObjectInstance& o : frame.objects)
        if (o.heightfield && o.object->material.type == MaterialType::Dielectric) water = &o;
    return water;
}

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

// Every grid triangle's flux is carried to where its refracted corners land, so folds past the focus,
// oblique light, Fresnel and absorption are exact up to the grid's sampling of the surface (its error falls
// as grid^-2: tests/test_conformance.cpp). What the model leaves out is visibility: a crest that shadows
// the next trough, or a refracted ray that meets the surface again. Neither can happen while the light's
// tilt keeps every facet lit and every refracted ray descending more steeply than the steepest slope:
// tan(tilt) max|grad h| < 1 (and the refracted ray's tan of the same, which is smaller).
AccuracyClaim CausticTriangles::accuracy_claim(const FrameGeometry& frame) const {
    const ObjectInstance* water = water_surface(frame);
    if (!water || !water->heightfield) return AccuracyClaim::outside("no height-field water surface in the frame");
    double steepest = 0.0;
    for (const glm::vec2& g : water->heightfield->gradient) steepest = std::max(steepest, static_cast<double>(glm::length(g)));
    const glm::dvec3 l = glm::normalize(frame.scene->lights[0].direction);
    const double tan_tilt = std::sqrt(l.x * l.x + l.y * l.y) / -l.z;
    // Measured on the conformance cases and 800 drawn sine and Gaussian cases (four seeds; README.md): the
    // error is the grid's sampling of the surface. Before the first focus grid 256 stays under 0.03. Past it
    // the folds sharpen: at grid 256, 0.128 from 1 to 1.5 x the first focus depth and 0.23 from 1.5 to 3 x; at
    // 512, 0.059 up to 3 x
    // and 0.097 beyond (0.044 and 0.068 at 1024). So past the focus the claim needs the grid the receiver is
    // drawn at there, fold_refine x grid, to be 512 or finer, and the receiver at most 3 x the focus depth.
    // render() refines where the base grid's map folds, which its sampling puts within a fraction of a percent
    // of the first focus depth; just past the focus, where it may not fold yet, the base grid's error is that
    // of a focus (grid 256: 0.018 up to 1.02 x, 0.057 up to 1.1 x), inside the claim.
    const regime::WaterRegime w = regime::water_regime(frame);
    const double depth_ratio = w.depth_over_first_focus();
    std::vector<RegimeBound> bounds = {{"tan_tilt_times_max_slope", tan_tilt * steepest, 1.0, true},
                                       {"grid", static_cast<double>(base_grid_), static_cast<double>(kClaimMinGrid), false},
                                       {"depth_over_first_focus", depth_ratio, kClaimMaxFocusFraction, true}};
    if (depth_ratio > 1.0)
        bounds.push_back({"grid_past_focus", static_cast<double>(grid_past_focus()),
                          static_cast<double>(kClaimMinFoldGrid), false});
    for (const RegimeBound& b : bounds) {
        if (b.holds()) continue;
        char why[260];
        if (b.quantity == "grid")
            std::snprintf(why, sizeof why, "grid %d below the %d where the claim was measured (the error grows about as "
                          "grid^-2 below it)", base_grid_, kClaimMinGrid);
        else if (b.quantity == "grid_past_focus")
            std::snprintf(why, sizeof why, "the receiver lies past the first focus (%.2f x its depth), where the folds "
                          "need a grid of %d or finer; where the grid's map folds it is drawn at %d (fold_refine x grid)",
                          depth_ratio, kClaimMinFoldGrid, grid_past_focus());
        else if (b.quantity == "depth_over_first_focus")
            std::snprintf(why, sizeof why, "the receiver lies %.3g m below the water, %.2f x the first focus depth %.3g m, "
                          "beyond %.2f: the folds multiply and sharpen faster than grid %d samples them",
                          w.depth, b.value, w.focus.first_focus_depth, kClaimMaxFocusFraction, grid_past_focus());
        else
            std::snprintf(why, sizeof why,
                          "the light's tilt (tan %.3g) times the steepest slope (%.3g) is %.3g >= 1: crests shadow the "
                          "surface, which this method does not model",
                          tan_tilt, steepest, tan_tilt * steepest);
        return AccuracyClaim::outside(why, bounds);
    }
    return AccuracyClaim::within(kClaimError, bounds);
}

void CausticTriangles::ensure_topology() {
    const int g = grid_;
    const std::size_t count = 2 * static_cast<std::size_t>(g - 1) * (g - 1);
    if (triangles_.size() == count) return;
    // A frame past the focus draws at the fold grid after probing the base grid: both topologies are kept.
    std::swap(triangles_, other_triangles_);
    if (triangles_.size() == count) return;
    // Two counter-clockwise (seen from above) triangles per cell; fixed for each grid.
    triangles_.clear();
    triangles_.reserve(count);
    for (unsigned j = 0; j + 1 < static_cast<unsigned>(g); ++j)
        for (unsigned i = 0; i + 1 < static_cast<unsigned>(g); ++i) {
            const unsigned v00 = j * g + i, v10 = v00 + 1, v01 = v00 + g, v11 = v01 + 1;
            triangles_.push_back({v00, v10, v11});
            triangles_.push_back({v00, v11, v01});
        }
}

bool CausticTriangles::draw_dispersion_samples(const FrameGeometry& frame, const ChartMap& map, int W, int H,
                                               double scale, bool periodic, Image& scalar, Image& rgb,
                                               Counters& counters, RasterStats& raster_stats, double& refract_ms,
                                               double& raster_ms, bool stop_on_fold) {
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
        const std::int64_t folded_before = counters.folded;
        triangle_values(map, scale, counters);
        refract_ms += clock.ms();
        if (stop_on_fold && counters.folded > folded_before) return false;

        clock.reset();
        Image& target = dispersive ? sample_map_ : scalar;
        const RasterStats st = raster_.draw({image_, triangles_, values_, {}}, {coverage_, periodic, false}, target);
        raster_stats.nonfinite += st.nonfinite;
        raster_stats.too_large += st.too_large;
        if (dispersive)
            add_spectral_sample(sample_map_, 1.0f / samples, weights[static_cast<std::size_t>(k)], scalar, rgb);
        raster_ms += clock.ms();
    }
    return true;
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
    grid_ = base_grid_;   // textures are drawn at `grid` (fold_refine applies to the receiver)
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
    const ChartMap map(*chart, frame);
    const double scale = map.plane ? 1.0 / chart->bin_area(0, 0) : 1.0;
    double refract_ms = 0.0, raster_ms = 0.0;
    const bool dispersive = material.dispersion > 0.0;
    Counters counters;
    RasterStats raster_stats;
    out.receiver = Image(W, H);
    if (dispersive) out.receiver_rgb = Image(W, H, 3);
    auto draw_at = [&](int grid, bool stop_on_fold) {
        grid_ = grid;
        clock.reset();
        ensure_topology();
        resample_surface(*water->heightfield);
        compute_triangle_flux(light_dir, scene.lights[0].irradiance);
        refract_ms += clock.ms();
        return draw_dispersion_samples(frame, map, W, H, scale, false, out.receiver, out.receiver_rgb, counters,
                                       raster_stats, refract_ms, raster_ms, stop_on_fold);
    };
    // Past a focus the folds sharpen faster than the base grid samples them (README, "Regime and measured
    // error": at grid 256 up to 0.23 from 1 to 3 x the first focus depth, 0.059 at 512). Where the base
    // grid's map folds (some lit triangle's image turns over), the receiver is drawn at fold_refine x grid
    // instead; the probe's refraction is the cost of a frame past the focus, nothing is drawn twice.
    const bool probe = grid_past_focus() > base_grid_;
    const bool regrid = !draw_at(base_grid_, probe);
    if (regrid) {   // a later dispersion sample (a higher index focuses sooner) may fold after earlier ones drew
        counters = Counters{};
        raster_stats = RasterStats{};
        out.receiver = Image(W, H);
        if (dispersive) out.receiver_rgb = Image(W, H, 3);
        draw_at(grid_past_focus(), false);
    }
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
    // 1 where the base grid's map folded and the receiver was drawn at the finer grid (a diagnostic, not a
    // failure).
    out.health.add("drawn_refined", regrid ? 1 : 0);
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
        {"grid", ParamType::Int, "256", 2, kMaxGrid, {},
         "surface grid resolution (vertices per side) the water surface is resampled at", {"64", "128", "256"}},
        {"fold_refine", ParamType::Int, "2", 1, 4, {},
         "where the `grid` map folds (a receiver past a focus), the receiver is drawn at fold_refine x grid (at most "
         "4096); 1: `grid` throughout"},
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

}  // namespace caustic_triangles

CAUSTICS_REGISTER_METHOD(caustic_triangles::caustic_triangles_info);

}  // namespace caustics
