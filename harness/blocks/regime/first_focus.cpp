// First focus of the refracted plane wave under a height field, and a frame's water regime (see
// first_focus.hpp).
#include <caustics/blocks/regime/first_focus.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::regime {
namespace {

glm::dvec3 normal_of(const glm::dvec2& g) { return glm::normalize(glm::dvec3(-g.x, -g.y, 1.0)); }

glm::dvec2 run_of(const glm::dvec3& t) { return glm::dvec2(t) / std::max(-t.z, 1e-9); }

// Smallest positive root of a + b x + c x^2 (1e300 if none).
double smallest_positive_root(double a, double b, double c) {
    double best = 1e300;
    auto take = [&](double x) {
        if (x > 0.0 && x < best) best = x;
    };
    if (std::fabs(c) < 1e-12 * (std::fabs(a) + std::fabs(b))) {
        if (b != 0.0) take(-a / b);
        return best;
    }
    const double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return best;
    const double r = std::sqrt(disc);
    take((-b - r) / (2.0 * c));
    take((-b + r) / (2.0 * c));
    return best;
}

}  // namespace

glm::dvec3 refract_direction(const glm::dvec3& light, const glm::dvec3& normal, double ior) {
    // t = eta d + (eta cos_i - cos_t) N, eta = 1 / n.
    const double eta = 1.0 / ior, cos_i = std::max(0.0, -glm::dot(light, normal));
    const double cos_t = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)));
    return glm::normalize(eta * light + (eta * cos_i - cos_t) * normal);
}

double first_focus_depth(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z) {
    double depth = 1e300;
    for (double d : focus_depth_map(hf, light, ior, surface_z)) depth = std::min(depth, d);
    return depth;
}

FocusAnalysis analyze_focus(const HeightField& hf, const glm::dvec3& light, double ior, double surface_z) {
    FocusAnalysis out;
    out.first_focus_depth = first_focus_depth(hf, light, ior, surface_z);
    const glm::dvec3 l = glm::normalize(light);
    for (int b = 0; b < hf.ny; ++b)
        for (int a = 0; a < hf.nx; ++a) {
            if (glm::dot(l, normal_of(glm::dvec2(hf.grad(a, b)))) >= 0.0) out.shadowed = true;
            // Convex curvature along x and y (second differences of the height) for the messages.
            if (a > 0 && a + 1 < hf.nx)
                out.max_curvature = std::max(out.max_curvature, -(hf.z(a + 1, b) - 2.0 * hf.z(a, b) + hf.z(a - 1, b)) /
                                                                    (hf.spacing.x * hf.spacing.x));
            if (b > 0 && b + 1 < hf.ny)
                out.max_curvature = std::max(out.max_curvature, -(hf.z(a, b + 1) - 2.0 * hf.z(a, b) + hf.z(a, b - 1)) /
                                                                    (hf.spacing.y * hf.spacing.y));
        }
    return out;
}

std::vector<double> focus_depth_map(const HeightField& hf, const glm::dvec3& light_in, double ior, double surface_z) {
    const glm::dvec3 light = glm::normalize(light_in);
    const int nx = hf.nx, ny = hf.ny;
    std::vector<double> out(static_cast<std::size_t>(std::max(nx, 0)) * std::max(ny, 0), 1e300);
    if (nx < 2 || ny < 1) return out;
    // Rows in parallel: every value is its vertex's own, so the map does not depend on the threads (a claim
    // and a render that decide on it each frame agree).
    std::vector<glm::dvec2> u(static_cast<std::size_t>(nx) * ny);
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int b = rows.begin(); b != rows.end(); ++b)
            for (int a = 0; a < nx; ++a) {
                const glm::dvec3 n = normal_of(glm::dvec2(hf.grad(a, b)));
                u[static_cast<std::size_t>(b) * nx + a] = run_of(refract_direction(light, n, ior));
            }
    });
    auto at = [&](int a, int b) { return u[static_cast<std::size_t>(b) * nx + a]; };
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int b = rows.begin(); b != rows.end(); ++b)
            for (int a = 0; a < nx; ++a) {
                const int a0 = std::max(a - 1, 0), a1 = std::min(a + 1, nx - 1);
                const int b0 = std::max(b - 1, 0), b1 = std::min(b + 1, ny - 1);
                const glm::dvec2 dudx = a1 > a0 ? (at(a1, b) - at(a0, b)) / ((a1 - a0) * hf.spacing.x) : glm::dvec2(0.0);
                const glm::dvec2 dudy = b1 > b0 ? (at(a, b1) - at(a, b0)) / ((b1 - b0) * hf.spacing.y) : glm::dvec2(0.0);
                const glm::dvec2 g(hf.grad(a, b)), uu = at(a, b);
                // A = I + u g^T, B = grad u (columns d/dx, d/dy).
                const double a00 = 1.0 + uu.x * g.x, a01 = uu.x * g.y, a10 = uu.y * g.x, a11 = 1.0 + uu.y * g.y;
                const double b00 = dudx.x, b01 = dudy.x, b10 = dudx.y, b11 = dudy.y;
                const double c0 = a00 * a11 - a01 * a10;
                const double c1 = a00 * b11 + a11 * b00 - a01 * b10 - a10 * b01;
                const double c2 = b00 * b11 - b01 * b10;
                const double d = smallest_positive_root(c0, c1, c2);
                if (d < 1e299) out[static_cast<std::size_t>(b) * nx + a] = d + surface_z - hf.z(a, b);
            }
    });
    return out;
}

double ray_spread(const HeightField& hf, const glm::dvec3& light_in, double ior) {
    const glm::dvec3 light = glm::normalize(light_in);
    double gmax = 0.0;
    for (int b = 0; b < hf.ny; ++b)
        for (int a = 0; a < hf.nx; ++a) gmax = std::max(gmax, static_cast<double>(glm::length(hf.grad(a, b))));
    const glm::dvec2 mean = run_of(refract_direction(light, glm::dvec3(0, 0, 1), ior));
    double spread = 0.0;
    for (const glm::dvec2 g : {glm::dvec2(gmax, 0), glm::dvec2(-gmax, 0), glm::dvec2(0, gmax), glm::dvec2(0, -gmax)})
        spread = std::max(spread, glm::length(run_of(refract_direction(light, normal_of(g), ior)) - mean));
    return spread;
}

SurfaceScales surface_scales(const HeightField& hf) {
    SurfaceScales out;
    if (hf.nx < 3 || hf.ny < 2 || hf.gradient.size() != hf.height.size()) return out;
    double slope2 = 0.0, curv2 = 0.0;
    std::int64_t count = 0;
    for (int j = 0; j < hf.ny; ++j)
        for (int i = 0; i < hf.nx; ++i) {
            const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, hf.nx - 1);
            const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, hf.ny - 1);
            const glm::dvec2 gx = (glm::dvec2(hf.grad(i1, j)) - glm::dvec2(hf.grad(i0, j))) / ((i1 - i0) * hf.spacing.x);
            const glm::dvec2 gy = j1 > j0 ? (glm::dvec2(hf.grad(i, j1)) - glm::dvec2(hf.grad(i, j0))) / ((j1 - j0) * hf.spacing.y)
                                          : glm::dvec2(0.0);
            const double xx = gx.x, yy = gy.y, xy = 0.5 * (gx.y + gy.x);
            const double mean = 0.5 * (xx + yy), rad = std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
            out.focusing_curvature = std::max(out.focusing_curvature, -(mean - rad));
            const glm::dvec2 g(hf.grad(i, j));
            slope2 += glm::dot(g, g);
            curv2 += xx * xx + yy * yy + 2.0 * xy * xy;
            ++count;
        }
    if (curv2 > 0.0 && count > 0) out.feature = 2.0 * M_PI * std::sqrt(slope2 / curv2);
    return out;
}

WaterRegime water_regime(const FrameGeometry& frame, RegimeParts parts) {
    WaterRegime r;
    if (!frame.scene || frame.scene->lights.empty()) return r;
    for (const ObjectInstance& o : frame.objects)
        if (o.heightfield && o.object && o.object->material.type == MaterialType::Dielectric) {
            r.water = &o;
            break;
        }
    if (!r.water) return r;
    const HeightField& hf = *r.water->heightfield;
    double sum = 0.0;
    for (float z : hf.height) sum += z;
    r.surface_z = hf.height.empty() ? r.water->bounds.center().z : sum / static_cast<double>(hf.height.size());
    const Light& light = frame.scene->lights.front();
    const glm::dvec3 dir = light.type == LightType::Point ? glm::normalize(r.water->bounds.center() - light.position)
                                                          : glm::normalize(light.direction);
    r.tilt_deg = std::acos(std::clamp(-dir.z, -1.0, 1.0)) * 180.0 / M_PI;
    r.ior = r.water->object->material.ior;
    for (const ObjectInstance& o : frame.objects)
        if (o.object && o.object->material.type == MaterialType::Diffuse && o.bounds.valid() && o.bounds.lo.z < r.surface_z)
            r.depth = std::max(r.depth, r.surface_z - o.bounds.lo.z);
    if (parts == RegimeParts::FocusOnly) {
        r.focus.first_focus_depth = first_focus_depth(hf, dir, r.ior, r.surface_z);
    } else {
        r.focus = analyze_focus(hf, dir, r.ior, r.surface_z);
        r.feature_length = surface_scales(hf).feature;
    }
    r.valid = true;
    return r;
}

AccuracyClaim claim_within_bounds(std::vector<RegimeBound> bounds, double max_error,
                                  const std::function<std::string(const RegimeBound&)>& explain) {
    for (const RegimeBound& b : bounds)
        if (!b.holds()) {
            std::string why = explain(b);
            return AccuracyClaim::outside(std::move(why), std::move(bounds));
        }
    return AccuracyClaim::within(max_error, std::move(bounds));
}

std::string describe(const RegimeBound& b) {
    char text[160];
    std::snprintf(text, sizeof text, "%s %.3g %s %.3g", b.quantity.c_str(), b.value, b.upper ? ">" : "<", b.limit);
    return text;
}

}  // namespace caustics::regime
