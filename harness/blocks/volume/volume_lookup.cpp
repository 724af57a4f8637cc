// Receiver lookups into a volume caustic texture and the flux normalization of the relative methods.
#include <caustics/blocks/volume/volume_lookup.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

#include <tbb/parallel_for.h>

#include <caustics/frame/baseline.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {

// The flat-interface optics are shared with the no-caustic baseline (baseline.cpp).
glm::dvec3 mean_refracted_direction(const Scene& scene, double ior) {
    return flat_interface_transmission(scene.lights.empty() ? Light{} : scene.lights.front(), 1.0, ior, false).direction;
}

double flat_transmitted_irradiance(const Scene& scene, double ior, const glm::dvec3& receiver_normal) {
    if (scene.lights.empty()) return 0.0;
    const FlatTransmission beam = flat_interface_transmission(scene.lights.front(), 1.0, ior, scene.fresnel);
    const glm::dvec3& t = beam.direction;
    // Flux per horizontal area E0 cos_i T, carried along t onto the receiver.
    const double on_receiver = std::max(0.0, -glm::dot(t, glm::normalize(receiver_normal)));
    return beam.horizontal_irradiance * on_receiver / std::max(std::fabs(t.z), 1e-9);
}

// ---- Receiver lookups ----

namespace {

struct LookupContext {
    const VolumeLookup* lookup;
    glm::dvec3 refracted{0, 0, -1};
    double depth_scale = 1.0;
};

// Length of the mean refracted ray from the mean water surface down to p.
double path_below_surface(const LookupContext& ctx, const glm::dvec3& p) {
    return refracted_path_length(p, ctx.refracted, ctx.lookup->surface_z);
}

// Whether light reaches p through the water's rectangle along the mean refracted direction.
bool lit(const LookupContext& ctx, const glm::dvec3& p) {
    const VolumeLookup& l = *ctx.lookup;
    if (!(l.water_hi.x > l.water_lo.x && l.water_hi.y > l.water_lo.y)) return true;
    return enters_through_rectangle(p, ctx.refracted, l.surface_z, l.water_lo, l.water_hi);
}

constexpr double kFaceTolerance = 1e-2;

// Texture value at a receiver point; false when it falls outside the box.
bool lookup_value(const LookupContext& ctx, glm::dvec3 p, float& value, bool& clamped) {
    const VolumeShape& s = ctx.lookup->texture->shape;
    clamped = false;
    // Receivers on the box's faces (walls bounding the water) have float G-buffer positions that land a
    // rounding error on either side of the face: points within kFaceTolerance cells of the box are
    // moved onto it, so such a wall does not read a speckle of zeros.
    const glm::dvec3 lo = s.origin, hi = s.origin + s.extent();
    const double tolerance = kFaceTolerance * s.spacing;
    if (glm::any(glm::lessThan(p, lo - tolerance)) || glm::any(glm::greaterThan(p, hi + tolerance))) {
        value = 0.0f;
        return false;
    }
    p = glm::clamp(p, lo, hi);
    if (!lit(ctx, p)) {
        value = 0.0f;
        return true;
    }
    if (ctx.lookup->scaled_ior) {
        const double along = path_below_surface(ctx, p);
        glm::dvec3 q = p - along * ctx.refracted;   // entry point on the surface
        q.z = ctx.lookup->surface_z - along * ctx.depth_scale;
        const glm::dvec3 qc = glm::clamp(q, lo, hi);
        clamped = qc != q;
        p = qc;
    }
    return trilinear(*ctx.lookup->texture, p, value);
}

}  // namespace

CausticOutput render_volume_texture(const FrameGeometry& frame, const RenderRequest& request, const VolumeLookup& lookup) {
    CausticOutput out;
    const Scene& scene = *frame.scene;
    LookupContext ctx{&lookup};
    ctx.refracted = mean_refracted_direction(scene, lookup.ior);
    ctx.depth_scale = (lookup.ior - 1.0) / lookup.ior;
    std::int64_t outside = 0, clamped = 0, nonfinite = 0;

    Stopwatch watch;
    std::optional<ReceiverChart> own_chart;
    const ReceiverChart* chart = request.receiver;
    if (!chart && lookup.normalize_flux) {
        own_chart.emplace(frame, scene.receiver.width, scene.receiver.height);
        chart = &*own_chart;
    }
    Image receiver;
    if (chart) {
        const int w = chart->width(), hgt = chart->height();
        receiver = Image(w, hgt, 1);
        std::vector<std::int64_t> row_outside(static_cast<std::size_t>(hgt)), row_clamped(row_outside.size());
        tbb::parallel_for(0, hgt, [&](int j) {
            for (int i = 0; i < w; ++i) {
                const glm::dvec3 p = chart->point((i + 0.5) / w, (j + 0.5) / hgt);
                float v;
                bool c;
                if (!lookup_value(ctx, p, v, c)) ++row_outside[static_cast<std::size_t>(j)];
                if (c) ++row_clamped[static_cast<std::size_t>(j)];
                receiver.at(i, j) = v;
            }
        });
        for (std::size_t j = 0; j < row_outside.size(); ++j) {
            outside += row_outside[j];
            clamped += row_clamped[j];
        }
    }
    out.stages_ms.emplace_back("receiver_lookup", watch.ms());

    // Flux normalization: the area-weighted mean over the receiver equals the irradiance a flat
    // interface would transmit onto it (from the light and the interface only, never the reference).
    double scale = 1.0;
    if (lookup.normalize_flux && chart) {
        watch.reset();
        double sum = 0.0, target = 0.0, area = 0.0;
        for (int j = 0; j < chart->height(); ++j)
            for (int i = 0; i < chart->width(); ++i) {
                const double a = chart->bin_area(i, j);
                const double v = receiver.at(i, j);
                if (std::isfinite(v)) sum += a * v;
                const double u = (i + 0.5) / chart->width(), w = (j + 0.5) / chart->height();
                if (lit(ctx, chart->point(u, w)))
                    target += a * flat_transmitted_irradiance(scene, lookup.ior, chart->normal(u, w));
                area += a;
            }
        if (sum > 0.0 && area > 0.0) scale = target / sum;
        out.stages_ms.emplace_back("normalize", watch.ms());
    }
    if (request.receiver) {
        for (float& v : receiver.pixels) {
            v = static_cast<float>(v * scale);
            if (!std::isfinite(v)) {
                ++nonfinite;
                v = 0.0f;
            }
        }
        out.receiver = std::move(receiver);
    }

    if (request.camera) {
        watch.reset();
        const CameraGBuffer& gb = *request.camera;
        out.camera = Image(gb.width, gb.height, 1);
        std::vector<std::int64_t> row_outside(static_cast<std::size_t>(std::max(gb.height, 0))), row_clamped(row_outside.size()),
            row_nonfinite(row_outside.size());
        tbb::parallel_for(0, gb.height, [&](int y) {
            for (int x = 0; x < gb.width; ++x) {
                const std::size_t idx = gb.index(x, y);
                if (!gb.covered[idx]) continue;
                float v;
                bool c;
                if (!lookup_value(ctx, glm::dvec3(gb.position[idx]), v, c)) ++row_outside[static_cast<std::size_t>(y)];
                if (c) ++row_clamped[static_cast<std::size_t>(y)];
                v = static_cast<float>(v * scale);
                if (!std::isfinite(v)) {
                    ++row_nonfinite[static_cast<std::size_t>(y)];
                    v = 0.0f;
                }
                out.camera.at(x, y) = v;
            }
        });
        for (std::size_t y = 0; y < row_outside.size(); ++y) {
            outside += row_outside[y];
            clamped += row_clamped[y];
            nonfinite += row_nonfinite[y];
        }
        out.stages_ms.emplace_back("camera_lookup", watch.ms());
    }
    out.health.add("outside_volume", outside);
    out.health.add("clamped", clamped);
    out.health.add("nonfinite", nonfinite);
    return out;
}

}  // namespace caustics
