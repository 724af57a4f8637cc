// Analytic truth of a ball lens lit straight down (see analytic_truth.hpp, BallLens).
//
// Parallel light along -z meets a dielectric sphere; the ray entering at distance h from the axis stays in
// its meridional plane and is refracted twice (exact vector Snell law, no small-angle approximation) before
// it meets the floor at the signed radius R(h). Past the paraxial focus R(h) crosses the axis and folds,
// which a histogram of fine source annuli handles exactly as the sine's strip histogram does: the annulus
// [h_a, h_b] carries E0 pi (h_b^2 - h_a^2) times the interfaces' transmittance and the chord's absorption,
// spread uniformly over the radii between |R(h_a)| and |R(h_b)|. Light that misses the ball reaches the
// floor directly and is not caustic irradiance (docs/design.md section 3). Each receiver bin averages the radial
// irradiance at 16 x 16 sub-points.
#include <algorithm>
#include <cmath>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>

namespace caustics {

namespace {

// Refraction of unit `d` at unit normal `n` facing the incoming ray, from index n1 into n2; false on TIR.
bool refract2(glm::dvec2 d, glm::dvec2 n, double n1, double n2, glm::dvec2& t, double& cos_i, double& cos_t) {
    const double eta = n1 / n2;
    cos_i = -glm::dot(d, n);
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return false;
    cos_t = std::sqrt(1.0 - sin2_t);
    t = eta * d + (eta * cos_i - cos_t) * n;
    return true;
}

}  // namespace

BallLens::Ray BallLens::trace(double h) const {
    Ray out;
    const double y = std::sqrt(std::max(0.0, radius * radius - h * h));
    glm::dvec2 p(h, y);   // (r, z) relative to the centre: the entry point on the upper hemisphere
    glm::dvec2 t;
    double ci = 0.0, ct = 0.0;
    if (!refract2({0.0, -1.0}, p / radius, 1.0, ior, t, ci, ct)) return out;
    double transmit = fresnel ? fresnel_transmittance(ci, ct, 1.0, ior) : 1.0;
    const double chord = -2.0 * glm::dot(p, t);   // second intersection with the circle
    p += chord * t;
    if (absorption > 0.0) transmit *= std::exp(-absorption * chord);
    glm::dvec2 out_dir;
    if (!refract2(t, -p / radius, ior, 1.0, out_dir, ci, ct)) return out;   // cannot happen in a sphere
    if (fresnel) transmit *= fresnel_transmittance(ci, ct, ior, 1.0);
    if (!(out_dir.y < 0.0)) return out;   // leaves sideways or upwards: never reaches the floor
    out.landing = p.x + out_dir.x * (-depth - p.y) / out_dir.y;
    out.transmittance = transmit;
    out.ok = true;
    return out;
}

std::vector<double> BallLens::radial_irradiance(double r_max, int bins) const {
    std::vector<double> flux(static_cast<std::size_t>(bins), 0.0);
    const double w = r_max / bins;
    auto spread = [&](double Ra, double Rb, double f) {
        const double a = std::min(Ra, Rb) / w, b = std::max(Ra, Rb) / w;
        if (!(a < bins)) return;
        if (b - a < 1e-12) {
            flux[static_cast<std::size_t>(a)] += f;
            return;
        }
        for (int k = std::max(0, static_cast<int>(a)); k <= std::min(bins - 1, static_cast<int>(b)); ++k) {
            const double overlap = std::min(b, k + 1.0) - std::max(a, static_cast<double>(k));
            if (overlap > 0.0) flux[static_cast<std::size_t>(k)] += f * overlap / (b - a);
        }
    };
    // Source annuli 1e-6 R wide: a strip's image is linear to ~(1e-6)^2 except at the rim, where R(h)
    // changes fast but the flux per strip vanishes with the entry cosine.
    const int strips = 1'000'000;
    Ray prev = trace(0.0);
    double h_prev = 0.0;
    for (int i = 1; i <= strips; ++i) {
        const double h = radius * static_cast<double>(i) / strips;
        const Ray cur = trace(h);
        if (prev.ok && cur.ok) {
            const double f = irradiance * 3.14159265358979323846 * (h * h - h_prev * h_prev) * 0.5 *
                             (prev.transmittance + cur.transmittance);
            spread(std::fabs(prev.landing), std::fabs(cur.landing), f);
        }
        prev = cur;
        h_prev = h;
    }
    for (int k = 0; k < bins; ++k)
        flux[static_cast<std::size_t>(k)] /= 3.14159265358979323846 * w * w * ((k + 1.0) * (k + 1.0) - k * k);
    return flux;
}

AnalyticTruth ball_lens_truth(const FrameGeometry& frame, const ReceiverChart& chart, const ObjectInstance& ball) {
    AnalyticTruth out;
    const Scene& scene = *frame.scene;
    const Light& light = scene.lights[0];
    const Object& bo = *ball.object;
    const Object& ro = scene.receiver_object();
    const glm::dvec3 l = glm::normalize(light.direction);
    if (std::fabs(l.x) > 1e-12 || std::fabs(l.y) > 1e-12) {
        out.reason = "the light is not vertical: the ball lens's closed form needs light along its axis";
        return out;
    }
    if (bo.material.type != MaterialType::Dielectric) {
        out.reason = "'" + bo.name + "' is not a dielectric";
        return out;
    }
    if (bo.material.dispersion != 0.0) {
        out.reason = "the ball is dispersive: its index varies over the band";
        return out;
    }
    if (scene.fresnel) {
        // Reflected light would bounce inside the ball and leave along paths the two-refraction map omits.
        out.reason = "Fresnel reflection is on: light reflected inside the ball leaves by other paths";
        return out;
    }
    BallLens lens;
    lens.radius = bo.radius;
    lens.ior = bo.material.ior;
    lens.absorption = bo.material.absorption;
    lens.irradiance = light.irradiance;
    lens.depth = bo.center.z - ro.center.z;
    if (!(lens.depth > bo.radius)) {
        out.reason = "the receiver is not below the ball";
        return out;
    }
    const glm::dvec2 c(bo.center);
    double r_max = 0.0;
    for (double s : {0.0, 1.0})
        for (double t : {0.0, 1.0}) r_max = std::max(r_max, glm::length(glm::dvec2(chart.point(s, t)) - c));
    // Radial bins ~1/4 of a sub-point's spacing: the irradiance between two sub-points is resolved.
    const double sub_spacing = std::sqrt(chart.total_area() / (chart.width() * chart.height())) / 16.0;
    const int bins = static_cast<int>(std::clamp(std::ceil(r_max / (0.25 * sub_spacing)), 64.0, 2.0e6));
    const std::vector<double> E = lens.radial_irradiance(r_max * (1.0 + 1e-9), bins);
    const double w = r_max * (1.0 + 1e-9) / bins;
    out.receiver = bin_average_around(chart, c, 16, [&](const glm::dvec2& P) {
        return E[static_cast<std::size_t>(std::min(bins - 1, static_cast<int>(glm::length(P) / w)))];
    });
    out.available = true;
    out.kind = "analytic:ball_lens";
    return out;
}

}  // namespace caustics
