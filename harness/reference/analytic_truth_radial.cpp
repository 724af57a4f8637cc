// Analytic truth of a Gaussian bump lit at normal incidence (see analytic_truth.hpp, RadialBump).
//
// Every ray stays in the vertical plane through the bump's axis, so the receiver map is a function of the
// radius R alone: E(R) = density(r) r / (R dR/dr) at the preimage r of R (flux conservation between the
// annulus [r, r + dr] and its image), where density is the flux per unit horizontal area reaching the floor
// (E0 T_fresnel exp(-Ka L): at normal incidence E0 cos_i |N| = E0). Before the first focus r -> R is
// one-to-one, E is smooth and bin averages follow from sub-point means; past it the map folds and the
// closed form is declared unavailable.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>

namespace caustics {

RadialBump::Ray RadialBump::trace(double r) const {
    Ray out;
    const double hp = slope(r);
    const double norm = std::sqrt(1.0 + hp * hp);
    const double nr = -hp / norm, nz = 1.0 / norm;   // upward unit normal in the (r, z) plane
    const double cos_i = nz;                         // light along -z
    const double eta = 1.0 / ior;
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return out;
    const double cos_t = std::sqrt(1.0 - sin2_t);
    const double tr = (eta * cos_i - cos_t) * nr, tz = -eta + (eta * cos_i - cos_t) * nz;   // Snell, vector form
    const double tl = std::sqrt(tr * tr + tz * tz);
    if (!(tz < 0.0)) return out;
    const double path = (height(r) - floor_z) / (-tz / tl);
    out.landing = r + tr / tl * path;
    out.density = irradiance;   // E0 (d . -N) with N = (-h', 1) unnormalised: E0 at normal incidence
    if (fresnel) out.density *= fresnel_transmittance(cos_i, cos_t, 1.0, ior);
    if (absorption > 0.0) out.density *= std::exp(-absorption * path);
    out.ok = true;
    return out;
}

bool RadialBump::profile(double r_max, RadialProfile& p, std::string& reason) const {
    // Step: far below the scale sigma on which the map bends, so that linear interpolation of r(R) and
    // central differences of dR/dr are exact to ~(step / sigma)^2 ~ 1e-8.
    const double step = std::min(sigma, r_max) * 1e-4;
    const std::size_t n = static_cast<std::size_t>(std::ceil(r_max / step)) + 2;
    p.r.resize(n);
    p.R.resize(n);
    p.density.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double r = step * static_cast<double>(i);
        const Ray ray = trace(r);
        if (!ray.ok) {
            reason = "a ray is not transmitted downwards";
            return false;
        }
        p.r[i] = r;
        p.R[i] = ray.landing;
        p.density[i] = ray.density;
        if (i > 0 && !(p.R[i] > p.R[i - 1])) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "the floor lies past the bump's first focus (rays from r = %.4g m cross): the map folds",
                          r);
            reason = text;
            return false;
        }
    }
    return true;
}

double RadialProfile::irradiance(double R) const {
    // The preimage: R is increasing in r (checked when the table was built).
    const std::size_t n = r.size();
    std::size_t hi = static_cast<std::size_t>(std::upper_bound(this->R.begin(), this->R.end(), R) - this->R.begin());
    hi = std::clamp<std::size_t>(hi, 1, n - 2);
    const std::size_t lo = hi - 1;
    const double f = (R - this->R[lo]) / (this->R[hi] - this->R[lo]);
    const double r_pre = r[lo] + f * (r[hi] - r[lo]);
    const double dens = density[lo] + f * (density[hi] - density[lo]);
    // dR/dr by central differences at the two table points, interpolated.
    auto dRdr = [&](std::size_t i) {
        const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1;
        return (this->R[b] - this->R[a]) / (r[b] - r[a]);
    };
    const double slope = dRdr(lo) + f * (dRdr(hi) - dRdr(lo));
    // r / R -> 1 / (dR/dr) on the axis.
    const double ratio = R > 1e-9 ? r_pre / R : 1.0 / slope;
    return dens * ratio / slope;
}

AnalyticTruth radial_bump_truth(const FrameGeometry& frame, const ReceiverChart& chart, const ObjectInstance& water) {
    AnalyticTruth out;
    const Scene& scene = *frame.scene;
    const Light& light = scene.lights[0];
    const Object& wo = *water.object;
    const HeightFieldDesc& desc = wo.heightfield;
    const Object& ro = scene.receiver_object();
    const glm::dvec3 l = glm::normalize(light.direction);
    if (std::fabs(l.x) > 1e-12 || std::fabs(l.y) > 1e-12) {
        out.reason = "the light is not vertical: the Gaussian bump's closed form needs normal incidence";
        return out;
    }
    RadialBump bump;
    bump.amplitude = desc.amplitude;
    bump.sigma = desc.sigma;
    bump.base = desc.base_height;
    bump.ior = wo.material.ior;
    bump.absorption = wo.material.absorption;
    bump.fresnel = scene.fresnel;
    bump.irradiance = light.irradiance;
    bump.floor_z = ro.center.z;
    if (!(bump.floor_z < bump.base - std::fabs(bump.amplitude))) {
        out.reason = "the receiver is not below the water";
        return out;
    }
    const glm::dvec2 c = desc.gauss_center;
    const glm::dvec2 lo = water.heightfield->origin, hi = lo + water.heightfield->extent();
    // The table reaches past the receiver's farthest corner (rays are displaced by less than that margin,
    // checked below: a sub-point whose preimage is off the table or off the water is refused).
    double R_far = 0.0;
    for (double s : {0.0, 1.0})
        for (double t : {0.0, 1.0}) R_far = std::max(R_far, glm::length(glm::dvec2(chart.point(s, t)) - c));
    RadialProfile prof;
    if (!bump.profile(R_far + 0.25 * glm::length(hi - lo), prof, out.reason)) return out;
    if (!(prof.R.back() > R_far)) {
        out.reason = "rays from the table's edge land inside the receiver";
        return out;
    }
    // 8 x 8 sub-points per bin: E is smooth before the focus, so the midpoint rule's error is
    // ~(bin / sigma)^2 / 24 / 64, below 1e-4 of E on the shipped scene's 256^2 receiver.
    // A sub-point whose light entered outside the water's rectangle makes the closed form inapplicable.
    out.receiver = bin_average_around(chart, c, 8, [&](const glm::dvec2& P) {
        const double R = glm::length(P);
        // The preimage's world point lies on the same ray from the axis.
        const std::size_t k =
            static_cast<std::size_t>(std::upper_bound(prof.R.begin(), prof.R.end(), R) - prof.R.begin());
        const double r_pre = prof.r[std::min(k, prof.r.size() - 1)];
        const glm::dvec2 src = c + (R > 1e-12 ? P * (r_pre / R) : glm::dvec2(0.0));
        if (src.x < lo.x || src.x > hi.x || src.y < lo.y || src.y > hi.y) return std::nan("");
        return prof.irradiance(R);
    });
    for (float v : out.receiver.pixels)
        if (std::isnan(v)) {
            out.reason = "the receiver sees light that entered outside the water's rectangle";
            out.receiver = Image();
            return out;
        }
    out.available = true;
    out.kind = "analytic:gaussian";
    return out;
}

}  // namespace caustics
